"""The plot helpers' figures are pyplot's where the caller uses pyplot, and nobody's elsewhere.

A script or a gallery page that imports pyplot gets figures that ``plt.show()`` shows and that
sphinx-gallery keeps; the commands, which never import pyplot, draw on a bare Agg canvas.  A
figure made only to be written to a file is closed once written.
"""

import subprocess
import sys

import numpy as np
from conftest import GEOMETRIES, K1, problem

from steady.solution import solve
from transient.runin import RunOptions, run_in

SCRIPT = """
import sys
import matplotlib
matplotlib.use("Agg")
{pyplot}
from steady.plotting import plot_face, new_figure
from steady.solution import solve
sys.path.insert(0, {tests!r})
from conftest import GEOMETRIES, K1, problem
fig = plot_face(solve(problem(GEOMETRIES["voronoi"], [K1, 10 * K1], n=24)))
print("pyplot" if "matplotlib.pyplot" in sys.modules else "none",
      len(__import__("matplotlib.pyplot").pyplot.get_fignums())
      if "matplotlib.pyplot" in sys.modules else 0)
"""


def _run(pyplot):
    import pathlib

    tests = str(pathlib.Path(__file__).parent)
    code = SCRIPT.format(pyplot="import matplotlib.pyplot as plt" if pyplot else "", tests=tests)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    return out.stdout.split()


def test_a_script_with_pyplot_gets_pyplot_figures():
    assert _run(pyplot=True) == ["pyplot", "1"], "plt.show() would show the figure"


def test_without_pyplot_nothing_imports_it():
    assert _run(pyplot=False) == ["none", "0"], "the helpers must not import pyplot"


def test_a_figure_written_to_a_file_is_closed(tmp_path):
    import matplotlib.pyplot as plt

    from steady.output import write_result
    from steady.plotting import plot_file
    from transient.output import write_run
    from transient.plotting import plot_history, plot_run
    from transient.problem import WearProblem

    steady = solve(problem(GEOMETRIES["voronoi"], [K1, 10 * K1], n=24))
    write_result(tmp_path / "s.h5", steady)
    plt.close("all")
    plot_file(tmp_path / "s.h5", tmp_path / "s.png")
    assert plt.get_fignums() == [], "plot_file left its figure open"
    wear = WearProblem(problem(GEOMETRIES["voronoi"], [K1, 10 * K1], n=24))
    write_run(tmp_path / "r.h5", run_in(wear, np.zeros(wear.shape), RunOptions(tol=1e-2)))
    plot_run(tmp_path / "r.h5", tmp_path / "r.png")
    assert plt.get_fignums() == [], "plot_run left its figure open"
    fig = plot_history(tmp_path / "r.h5")
    assert plt.get_fignums() == [fig.number], "plot_history's figure is pyplot's to show"
