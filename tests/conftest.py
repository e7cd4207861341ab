"""The test gallery: named scenes and wear problems that the tests share.

Tests draw their scenes from here rather than carrying inline copies:

- :data:`RADIUS`, :data:`E_STAR`, :data:`FORCE`, :data:`K1` -- the paper's
  epoxy cylinder (Fig. 6) and a matrix wear coefficient;
- :data:`GEOMETRIES` -- named phase geometries;
- :func:`problem` -- the :class:`steady.problem.Problem` of a geometry on a
  face's grid; :func:`wear_problem` -- its
  :class:`transient.problem.WearProblem` (named geometries);
- :data:`SCENES` and :func:`scene_text` -- scene files (TOML) by name, with
  keys overridden where a test needs it (the phase map too: homogeneous,
  Voronoi, rods or a file); the fixture ``scene_file`` writes one into the
  test's directory;
- :func:`run_cli`, :func:`one_error_line`, :func:`temporaries` -- a command
  run in-process, its one ``error:`` line, the temporary files it left;
- :func:`benchmark` -- a script of ``studies/benchmarks`` loaded as a module.
"""

import dataclasses
import importlib.util
import math
import pathlib
import sys

import pytest

from steady.halfspace import HalfSpace
from steady.outline import Annulus, Circle, Ellipse, FaceGrid, Rectangle, as_outline
from steady.phases import Homogeneous, Rods, Voronoi
from steady.problem import FacePhases, Problem
from steady.wear import PowerLaw
from transient.problem import WearProblem

RADIUS = 4e-3      # m, the paper's epoxy cylinder (Fig. 6)
E_STAR = 1.3e6     # Pa
FORCE = 10.0       # N
K1 = 1e-13         # 1/Pa, wear coefficient of the matrix (phase 0)

#: Tilt beyond which a flat punch lifts off on one side (transient.initial_face.tilted).
CRITICAL_TILT = FORCE / (4 * RADIUS ** 2 * E_STAR)

#: Five rods of radius 0.25 a on the disk of :data:`RADIUS`: one on the axis, four at 0.6 a
#: on the axes (the arrangement of steady/examples/rods_*.toml).
RODS = Rods(((0.0, 0.0), (0.6 * RADIUS, 0.0), (0.0, 0.6 * RADIUS), (-0.6 * RADIUS, 0.0),
             (0.0, -0.6 * RADIUS)), (0.25 * RADIUS,) * 5)

GEOMETRIES = {
    "homogeneous": Homogeneous(),
    # 64 seeds, 30 % of phase 1: coarse enough for n = 32.
    "voronoi": Voronoi(64, (0.7, 0.3), 2029),
    # 9 seeds, fits n = 12 (dense matrix-exponential references).
    "voronoi_small": Voronoi(9, (0.6, 0.4), 2027),
    # 400 seeds for the fine-grid cases.
    "voronoi_fine": Voronoi(400, (0.7, 0.3), 2029),
    "rods": RODS,
}

#: Named face outlines besides the paper's disk, at the scale of the epoxy
#: cylinder (a tread block of aspect 1:3, a seal ring, an elliptic pad).
OUTLINES = {
    "circle": Circle(RADIUS),
    "rectangle": Rectangle(2 * RADIUS / 3, 2 * RADIUS),
    "annulus": Annulus(0.5 * RADIUS, RADIUS),
    "ellipse": Ellipse(RADIUS, 0.5 * RADIUS),
}


def halfspace(n, radius=RADIUS, E_star=E_STAR):
    """The half-space operator of the ``n x n`` grid over the punch of ``radius``."""
    return HalfSpace(n, Circle(radius).grid(n).h, E_star)


def problem(labels_or_geometry, wear, *, n=None, outline=RADIUS, force=FORCE, E_star=E_STAR,
            n_phases=None):
    """The :class:`steady.problem.Problem` of a phase map on a face's grid.

    Parameters
    ----------
    labels_or_geometry : ndarray or phase geometry
        Labels on the outline's grid (then ``n`` is their longer side), or
        a geometry rasterised on ``outline.grid(n)``.
    wear : wear law or sequence of float
        Coefficients stand for Archard's law.
    n : int, optional
        Grid size (with a geometry).
    outline : outline object or float
        The face; a number is a disk's radius (default :data:`RADIUS`).
    force, E_star : float
    n_phases : int, optional
        Declared phases (default: the geometry's, or ``labels.max() + 1``).
    """
    outline = as_outline(outline)
    if hasattr(labels_or_geometry, "labels"):
        grid = outline.grid(n)
        labels = labels_or_geometry.labels(grid)
        n_phases = labels_or_geometry.n_phases if n_phases is None else n_phases
    else:
        labels = labels_or_geometry
        grid = FaceGrid(outline, max(labels.shape))
        n_phases = int(labels.max()) + 1 if n_phases is None else n_phases
    return Problem(FacePhases(grid, labels, n_phases), wear, force, E_star)


def wear_problem(geometry="voronoi", ratios=(1.0, 10.0), n=32, *, exponent=1.0, columns=None,
                 **options):
    """Wear problem of a gallery geometry (a name, or a geometry object).

    ``ratios`` are the wear coefficients in units of :data:`K1`, of the
    power law of ``exponent`` (default 1, Archard); ``columns`` (a
    :class:`steady.depth.DepthColumns` whose surface section is the map) the
    phases below the face; ``options`` go to the
    :class:`~transient.problem.WearProblem` constructor.
    """
    if isinstance(geometry, str):
        geometry = GEOMETRIES[geometry]
    wear = PowerLaw([K1 * r for r in ratios], exponent=exponent)
    return WearProblem(with_columns(problem(geometry, wear, n=n), columns), **options)


def with_columns(problem, columns):
    """``problem`` (a :class:`steady.problem.Problem`) on ``columns``: their surface section."""
    if columns is None:
        return problem
    phases = FacePhases(problem.grid, columns.phase_at(0.0), problem.n_phases,
                        problem.phase_names, columns)
    return dataclasses.replace(problem, phases=phases)


_MAPS = {
    "homogeneous": '{{ kind = "homogeneous" }}',
    "voronoi": ('{{ kind = "voronoi", n_seeds = {n_seeds}, fill_factors = {fill_factors}, '
                'seed = {seed} }}'),
    "rods": '{{ kind = "rods", centres = {centres}, radii = {radii} }}',
    "file": '{{ kind = "file", path = {path} }}',
}

#: Named scenes: the keys of :func:`scene_text`.
SCENES = {
    # A two-phase Voronoi punch for the steady command line.
    "steady": dict(n=40, coefficients=(1.0e-9, 1.0e-8), n_seeds=100,
                   fill_factors=(0.5, 0.5), seed=6007),
    # The same with an odd grid, for output files.
    "steady_odd": dict(n=33, coefficients=(1.0e-9, 3.0e-9), n_seeds=64,
                       fill_factors=(0.5, 0.5), seed=5501),
    # Every core key present, for the scene parser's error tests.
    "parser": dict(n=64, coefficients=(1.0e-9, 1.7e-9), exponent=1.0, n_seeds=100,
                   fill_factors=(0.5, 0.5), seed=2024),
    # A run-in: the gallery's "voronoi" geometry with k_1/k_0 = 10, snapshots.
    "runin": dict(n=32, coefficients=(1.0e-13, 1.0e-12), n_seeds=64,
                  fill_factors=(0.7, 0.3), seed=2029,
                  transient={"tol": 1e-3, "snapshots_s_star": (0.1, 1.0)}),
}


def _toml(value):
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (tuple, list)):
        return "[" + ", ".join(_toml(v) for v in value) + "]"
    if isinstance(value, float) and not math.isfinite(value):
        return "inf" if value > 0 else ("-inf" if value < 0 else "nan")
    return repr(value)


def scene_text(name="runin", *, extra="", **overrides):
    """TOML text of a gallery scene.

    Parameters
    ----------
    name : str
        A key of :data:`SCENES`.
    extra : str, optional
        Text appended verbatim (further sections or keys).
    **overrides
        Keys of the scene to change: ``radius``, ``normal_force``,
        ``E_star``, ``n``, ``coefficients``, ``exponent`` (None drops it),
        ``map`` (``"homogeneous"``, ``"voronoi"`` with ``n_seeds``,
        ``fill_factors`` and ``seed``, ``"rods"`` with ``centres`` and
        ``radii`` in metres, or ``"file"`` with ``path``), ``transient`` and
        ``initial_face`` (dicts, or None to drop), ``punch`` (a dict of
        ``[punch]`` keys, e.g. ``shape`` and its lengths, replacing
        ``radius``), ``load`` and ``counterbody`` (dicts of further keys of
        those sections, e.g. a ``programme``, a layer's ``thickness``).
    """
    spec = dict(radius=0.004, normal_force=10.0, E_star=1.3e6, exponent=None,
                map="voronoi", transient=None, initial_face=None, punch=None, load={},
                counterbody={})
    spec.update(SCENES[name])
    spec.update(overrides)
    phase_map = _MAPS[spec["map"]].format(
        n_seeds=spec.get("n_seeds"), fill_factors=_toml(spec.get("fill_factors", ())),
        seed=spec.get("seed"), centres=_toml(spec.get("centres", ())),
        radii=_toml(spec.get("radii", ())), path=_toml(spec.get("path", "")))
    punch = ([f"radius = {spec['radius']!r}"] if spec["punch"] is None
             else [f"{key} = {_toml(value)}" for key, value in spec["punch"].items()])
    lines = ["[punch]", *punch,
             "[load]", f"normal_force = {spec['normal_force']!r}",
             *(f"{key} = {_toml(value)}" for key, value in spec["load"].items()),
             "[counterbody]", f"E_star = {spec['E_star']!r}",
             *(f"{key} = {_toml(value)}" for key, value in spec["counterbody"].items()),
             "[grid]", f"n = {spec['n']}",
             "[wear]", f"coefficients = {_toml(spec['coefficients'])}"]
    if spec["exponent"] is not None:
        lines.append(f"exponent = {spec['exponent']!r}")
    lines += ["[phases]", f"map = {phase_map}"]
    for section in ("transient", "initial_face"):
        if spec[section] is not None:
            lines.append(f"[{section}]")
            lines += [f"{key} = {_toml(value)}" for key, value in spec[section].items()]
    text = "\n".join(lines) + "\n"
    return text + (extra + "\n" if extra else "")


@pytest.fixture
def scene_file(tmp_path):
    """Factory: write a gallery scene into the test's directory, return its path."""
    def write(name="runin", *, filename="scene.toml", **overrides):
        path = tmp_path / filename
        path.write_text(scene_text(name, **overrides))
        return path
    return write


def run_cli(module, argv, capsys):
    """Exit status, stdout and stderr of ``module.main(argv)`` (a command, in-process)."""
    try:
        status = module.main([str(a) for a in argv])
    except SystemExit as done:  # argument errors exit from the parser
        status = done.code
    out, err = capsys.readouterr()
    return status, out, err


def one_error_line(err):
    """The one ``error:`` line of stderr (notes allowed before it); fails otherwise."""
    assert "Traceback" not in err, f"traceback on stderr: {err[-2000:]}"
    lines = [line for line in err.splitlines() if not line.startswith("note: ")]
    assert len(lines) == 1 and lines[0].startswith("error: "), \
        f"expected one 'error:' line, got {lines!r}"
    return lines[0]


def temporaries(directory):
    """Temporary files (``*.tmp``) a writer left in ``directory``."""
    return sorted(p.name for p in pathlib.Path(directory).iterdir() if p.name.endswith(".tmp"))


@pytest.fixture(autouse=True)
def _close_pyplot_figures():
    """Close the figures of pyplot after each test, where a test (or an example) imported it.

    The plot helpers draw into pyplot's figures once pyplot is imported
    (steady.plotting.new_figure): left open they would add up over the suite.
    """
    yield
    pyplot = sys.modules.get("matplotlib.pyplot")
    if pyplot is not None:
        pyplot.close("all")


BENCHMARKS = pathlib.Path(__file__).parents[1] / "studies" / "benchmarks"


def benchmark(name, monkeypatch=None):
    """The script ``studies/benchmarks/<name>.py`` loaded as a module (not run).

    With ``monkeypatch`` (the pytest fixture) its directory is put on
    ``sys.path`` for the test, for a script that imports a sibling
    (``bench_runin``).
    """
    if monkeypatch is not None:
        monkeypatch.syspath_prepend(str(BENCHMARKS))
    spec = importlib.util.spec_from_file_location(name, BENCHMARKS / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module
