"""What every study script shares: its command line, its HDF5 file and its figure file.

A study computes its numbers into one HDF5 file (datasets with a ``units``
attribute, scalars as attributes with ``<name>_units``, the layout name and
version, and the parameters it ran with) and draws its PNG from that file
alone, so that a figure can be redrawn without recomputing (``--plot-only``).

Command line of every study::

    python studies/<study>.py [--quick] [--out OUT] [--docs-figures] [-o FILE.h5]
                              [--png FILE.png] [--plot-only] [--force]
                              [--workers N] [--scheduler ADDRESS] [-v]

Outputs go to ``OUT`` (``--out``, default ``./runin-studies-out``, which
git ignores), never into the source tree unless asked: ``OUT/<study>.h5``
and ``OUT/<study>.png`` for the full run, ``OUT/quick/<study>.h5`` and
``OUT/quick/<study>.png`` with ``--quick``; ``-o`` and ``--png`` name other
files.  ``--docs-figures`` (full runs only) redraws the committed figure
``docs/figures/<study>.png`` of the source tree instead, and for the design
table also rewrites the table shipped with the package.  Sweep files go to
``OUT`` too, and are reused from there.  Every study script takes these
options from :func:`add_output_arguments`.

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

from steady.safe_files import atomic_h5, file_identity

__all__ = ["DEFAULT_OUT", "DOCS_FIGURES", "FORMAT_VERSION", "ROOT", "add_output_arguments",
           "figure", "output_paths", "plain_log_ticks", "read_study", "run_study", "save_figure",
           "write_study"]

logger = logging.getLogger(__name__)

#: Layout version of every study file (attribute ``format_version``).
FORMAT_VERSION = 1

#: The repository root (studies/ is one level below it).
ROOT = pathlib.Path(__file__).resolve().parent.parent

#: Where the studies write unless told otherwise (``--out``), relative to the
#: current directory.
DEFAULT_OUT = pathlib.Path("runin-studies-out")

#: The committed figures, redrawn only with ``--docs-figures``.
DOCS_FIGURES = ROOT / "docs" / "figures"

# The outputs :func:`run_study` checked before computing, by resolved path:
# the identity of the file found then (None: none), or _ANY with --force.
_checked = {}
_ANY = object()


def write_study(path, name, params, datasets, attrs=None):
    """Write a study's numbers to HDF5, replacing an earlier run's file.

    Written atomically (:func:`steady.safe_files.atomic_h5`): an interrupted run
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
    steady.safe_files.OutputAppearedError
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
    FileNotFoundError
        The file does not exist.
    ValueError
        Another study's file or another layout version.
    """
    path = pathlib.Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"study file {str(path)!r} does not exist; run the study first")
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


def add_output_arguments(parser, *, docs_figures=True):
    """Add the output options every study shares: ``--out OUT`` and ``--docs-figures``.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        A study's parser; gains ``out`` (a :class:`pathlib.Path`) and
        ``docs_figures`` (bool).
    docs_figures : bool, optional
        Whether the script draws a committed figure (default True); the
        scripts that make the example scenes' map files take ``--out`` alone.
    """
    parser.add_argument("--out", type=pathlib.Path, default=DEFAULT_OUT, metavar="OUT",
                        help=f"directory of the outputs (default: ./{DEFAULT_OUT}"
                             + ("; quick runs in OUT/quick)" if docs_figures else ")"))
    if docs_figures:
        parser.add_argument("--docs-figures", action="store_true",
                            help=f"redraw the committed figure in {DOCS_FIGURES} (full runs "
                                 f"only)")


def output_paths(args, name, *, default_output=None, committed_output=None):
    """The HDF5 file and the figure of a study run, from its parsed arguments.

    Parameters
    ----------
    args : argparse.Namespace
        With ``out``, ``docs_figures`` and ``quick`` (:func:`add_output_arguments`),
        ``output`` and ``png`` (None: the defaults).
    name : str
        Study name, the stem of its files.
    default_output : path-like, optional
        HDF5 file of a full run instead of ``OUT/<name>.h5``.
    committed_output : path-like, optional
        The HDF5 file committed in the source tree that ``--docs-figures``
        rewrites (the design table); by default ``--docs-figures`` leaves
        the HDF5 file in ``OUT``.

    Returns
    -------
    h5, png : pathlib.Path

    Raises
    ------
    ValueError
        ``--docs-figures`` with ``--quick`` (a smoke test must not replace a
        committed figure).
    """
    out = pathlib.Path(args.out)
    if args.quick:
        if args.docs_figures:
            raise ValueError("--docs-figures redraws the committed figures from full runs; "
                             "not with --quick")
        h5 = pathlib.Path(args.output or out / "quick" / f"{name}.h5")
        return h5, pathlib.Path(args.png or h5.with_suffix(".png"))
    if args.docs_figures and committed_output is not None:
        default_output = committed_output
    h5 = pathlib.Path(args.output or default_output or out / f"{name}.h5")
    figures = DOCS_FIGURES if args.docs_figures else out
    return h5, pathlib.Path(args.png or figures / f"{name}.png")


def _parser(name, doc, parallel):
    """The argument parser of a study (see the module notes)."""
    parser = argparse.ArgumentParser(prog=f"python studies/{name}.py", description=doc,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true",
                        help="small smoke-test run (seconds)")
    add_output_arguments(parser)
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
                            help="sweep file to resume or reuse (default: in OUT, named by "
                                 "the study, or beside the output with --quick)")
        parser.add_argument("--n", type=int, default=None,
                            help="grid of the sweep (default: the study's)")
    parser.add_argument("-v", "--verbose", action="count", default=0)
    return parser


def run_study(name, doc, compute, plot, params, quick_params, argv=None, *, parallel=False,
              default_output=None, committed_output=None, default_sweep=None):
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
    default_output, committed_output : path-like, optional
        See :func:`output_paths`.
    default_sweep : str, optional
        Name of the sweep file of a full run in ``OUT``, formatted with the
        run's parameters (``"voronoi_sweep_n{n}.h5"``), given to ``compute``
        as ``params["sweep"]``; without it a study places its own sweep.

    Returns
    -------
    int
        Exit status.
    """
    args = _parser(name, doc, parallel).parse_args(argv)
    logging.basicConfig(level=(logging.WARNING, logging.INFO, logging.DEBUG)[min(args.verbose,
                                                                                2)],
                        format="%(levelname)s %(name)s: %(message)s")
    try:
        out, png = output_paths(args, name, default_output=default_output,
                                committed_output=committed_output)
    except ValueError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    run_params = dict(quick_params, quick=True) if args.quick else dict(params)
    if parallel:
        if args.n is not None:
            run_params["n"] = args.n
        if args.sweep is not None:
            run_params["sweep"] = args.sweep
        elif default_sweep is not None and not args.quick:
            run_params["sweep"] = str(pathlib.Path(args.out) / default_sweep.format(**run_params))
    checked = out.resolve()
    # What the study may replace: the file there now (see write_study).
    _checked[checked] = _ANY if args.force else file_identity(out)
    try:
        if not args.plot_only:
            t0 = time.perf_counter()
            if parallel:
                compute(out, run_params, workers=args.workers, scheduler=args.scheduler,
                        progress=True)
            else:
                compute(out, run_params)
            print(f"{name}: computed in {time.perf_counter() - t0:.1f} s -> {out}")
        plot(out, png)
        print(f"{name}: figure {png}")
    except (ValueError, FileNotFoundError) as err:  # a missing input is bad input
        print(f"error: {err}", file=sys.stderr)
        return 2
    finally:
        del _checked[checked]
    return 0
