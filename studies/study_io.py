"""What every study script shares: its command line, its HDF5 file and its figure file.

A study computes its numbers into one HDF5 file (datasets with a ``units``
attribute, scalars as attributes with ``<name>_units``, the layout name and
version, and the parameters it ran with) and draws its PNG from that file
alone, so that a figure can be redrawn without recomputing (``--plot-only``).

Command line of every study::

    python studies/<study>.py [--quick] [-o OUT.h5] [--png OUT.png] [--plot-only]
                              [--force] [--workers N] [--scheduler ADDRESS] [-v]

Defaults: ``out/<study>.h5`` and ``docs/figures/<study>.png`` for the full
run; ``out/quick/<study>.h5`` and ``out/quick/<study>.png`` with ``--quick``.
A run replaces the HDF5 file an earlier run left, but not one that another
process wrote while this one computed (two runs of a study on one output
at once): that is refused, exit status 2, unless ``--force`` is given.
"""

from __future__ import annotations

import argparse
import json
import logging
import pathlib
import sys
import time

import h5py
import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from steady.output import atomic_h5, file_identity

__all__ = ["FORMAT_VERSION", "ROOT", "figure", "plain_log_ticks", "read_study", "run_study",
           "save_figure", "write_study"]

logger = logging.getLogger(__name__)

#: Layout version of every study file (attribute ``format_version``).
FORMAT_VERSION = 1

#: The repository root (studies/ is one level below it).
ROOT = pathlib.Path(__file__).resolve().parent.parent

# The outputs :func:`run_study` checked before computing, by resolved path:
# the identity of the file found then (None: none), or _ANY with --force.
_checked = {}
_ANY = object()


def write_study(path, name, params, datasets, attrs=None):
    """Write a study's numbers to HDF5, replacing an earlier run's file.

    Written atomically (:func:`steady.output.atomic_h5`): an interrupted run
    leaves the previous file, not half a file.  Under :func:`run_study`,
    only the file found at ``path`` when the study started is replaced (any
    file with ``--force``): one another process wrote meanwhile is refused.
    Called outside it, whatever file ``path`` names is replaced.

    Parameters
    ----------
    path : str or path-like
    name : str
        Study name; the layout is ``runin.study.<name>``.
    params : mapping
        The parameters of the run (stored as JSON text in ``params``).
    datasets : mapping of str to (array_like, str)
        ``name -> (values, unit)``; a name with ``/`` makes groups.
    attrs : mapping of str to (scalar, str), optional
        ``name -> (value, unit)`` root attributes, the unit in ``<name>_units``.

    Returns
    -------
    pathlib.Path

    Raises
    ------
    steady.output.OutputAppearedError
        (a ``ValueError``) Under :func:`run_study` without ``--force``:
        another process wrote ``path`` since the study started; nothing is
        written.
    """
    path = pathlib.Path(path)
    found = _checked.get(path.resolve(), _ANY)
    if found is _ANY:
        options = {"force": True}
    else:
        options = {"replaces": found, "checked": True}
    with atomic_h5(path, format=f"runin.study.{name}", version=FORMAT_VERSION,
                   **options) as f:
        f.attrs["params"] = json.dumps(params, sort_keys=True, default=_jsonable)
        for key, (value, unit) in (attrs or {}).items():
            f.attrs[key] = value
            f.attrs[f"{key}_units"] = unit
        for key, (value, unit) in datasets.items():
            ds = f.create_dataset(key, data=np.asarray(value))
            ds.attrs["units"] = unit
    logger.info("wrote %s", path)
    return path


def _jsonable(value):
    if isinstance(value, (np.integer, np.floating)):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, pathlib.Path):
        return str(value)
    raise TypeError(f"{type(value).__name__} is not JSON-serialisable")


def read_study(path, name):
    """Read a study file back.

    Returns
    -------
    data : dict
        Every dataset (by its path in the file) as an array.
    attrs : dict
        Root attributes (``params`` decoded from JSON).

    Raises
    ------
    ValueError
        Missing file, another study's file or another layout version.
    """
    path = pathlib.Path(path)
    if not path.is_file():
        raise ValueError(f"study file {str(path)!r} does not exist; run the study first")
    data = {}
    with h5py.File(path, "r") as f:
        if f.attrs.get("format") != f"runin.study.{name}":
            raise ValueError(f"{str(path)!r} is not a {name} study file "
                             f"(format {f.attrs.get('format')!r})")
        if int(f.attrs["format_version"]) != FORMAT_VERSION:
            raise ValueError(f"{str(path)!r} has layout version {f.attrs['format_version']}, "
                             f"expected {FORMAT_VERSION}")
        f.visititems(lambda key, obj: data.__setitem__(key, obj[()])
                     if isinstance(obj, h5py.Dataset) else None)
        attrs = dict(f.attrs)
    attrs["params"] = json.loads(attrs["params"])
    return data, attrs


def figure(width, height):
    """A matplotlib figure on an Agg canvas (no pyplot state), inches."""
    fig = Figure(figsize=(width, height), layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def plain_log_ticks(ax):
    """Label the log axes of ``ax`` with plain numbers (0.1, 2, 20), not powers of ten."""
    from matplotlib.ticker import FormatStrFormatter, LogLocator

    for axis, scale in ((ax.xaxis, ax.get_xscale()), (ax.yaxis, ax.get_yscale())):
        if scale == "log":
            axis.set_major_locator(LogLocator(subs=(1.0, 2.0, 5.0)))
            axis.set_major_formatter(FormatStrFormatter("%g"))
            axis.set_minor_formatter(FormatStrFormatter(""))


def save_figure(fig, path, *, dpi=90):
    """Save a figure as PNG (small: the figures live in the repository)."""
    path = pathlib.Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=dpi)
    logger.info("figure written to %s (%.0f kB)", path, path.stat().st_size / 1e3)
    return path


def run_study(name, doc, compute, plot, params, quick_params, argv=None, *, parallel=False,
              default_output=None):
    """Command line of a study (see the module notes).

    Parameters
    ----------
    name : str
        Study name (file stem of its outputs).
    doc : str
        The study's docstring, for ``--help``.
    compute : callable
        ``compute(h5_path, params, *, workers, scheduler, progress)`` (with
        ``parallel``) or ``compute(h5_path, params)``.
    plot : callable
        ``plot(h5_path, png_path)``.
    params, quick_params : mapping
        Parameters of the full and of the ``--quick`` run.
    argv : list of str, optional
    parallel : bool, optional
        The study runs sweeps (adds ``--workers``, ``--scheduler``, ``--sweep``
        and ``--n``).
    default_output : path-like, optional
        HDF5 file of the full run, instead of ``out/<name>.h5``.

    Returns
    -------
    int
        Exit status.
    """
    parser = argparse.ArgumentParser(prog=f"python studies/{name}.py", description=doc,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true",
                        help="small smoke-test run (seconds)")
    parser.add_argument("-o", "--output", help="HDF5 file to write (or read with --plot-only)")
    parser.add_argument("--png", help="figure to draw")
    parser.add_argument("--plot-only", action="store_true",
                        help="redraw the figure from an existing HDF5 file")
    parser.add_argument("--force", action="store_true",
                        help="replace the HDF5 file even if another process wrote it while "
                             "this run computed (an earlier run's file is always replaced)")
    if parallel:
        parser.add_argument("--workers", type=int, default=None,
                            help="local worker processes (default: 2)")
        parser.add_argument("--scheduler", default=None,
                            help="Dask scheduler address, e.g. tcp://host:8786 "
                                 "(needs the extra 'dask')")
        parser.add_argument("--sweep", default=None,
                            help="sweep file to resume or reuse (default: "
                                 "out/voronoi_sweep_n<n>.h5, or beside the output with --quick)")
        parser.add_argument("--n", type=int, default=None,
                            help="grid of the sweep (default: the study's)")
    parser.add_argument("-v", "--verbose", action="count", default=0)
    args = parser.parse_args(argv)
    logging.basicConfig(level=(logging.WARNING, logging.INFO, logging.DEBUG)[min(args.verbose,
                                                                                2)],
                        format="%(levelname)s %(name)s: %(message)s")
    if args.quick:
        out = pathlib.Path(args.output or ROOT / "out" / "quick" / f"{name}.h5")
        png = pathlib.Path(args.png or out.with_suffix(".png"))
        run_params = dict(quick_params, quick=True)
    else:
        out = pathlib.Path(args.output or default_output or ROOT / "out" / f"{name}.h5")
        png = pathlib.Path(args.png or ROOT / "docs" / "figures" / f"{name}.png")
        run_params = dict(params)
    checked = out.resolve()
    # What the study may replace: the file there now (see write_study).
    _checked[checked] = _ANY if args.force else file_identity(out)
    try:
        if not args.plot_only:
            t0 = time.perf_counter()
            if parallel:
                if args.sweep is not None:
                    run_params["sweep"] = args.sweep
                if args.n is not None:
                    run_params["n"] = args.n
                compute(out, run_params, workers=args.workers, scheduler=args.scheduler,
                        progress=True)
            else:
                compute(out, run_params)
            print(f"{name}: computed in {time.perf_counter() - t0:.1f} s -> {out}")
        plot(out, png)
        print(f"{name}: figure {png}")
    except ValueError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    finally:
        del _checked[checked]
    return 0
