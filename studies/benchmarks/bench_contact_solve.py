r"""Time per contact solve and per padded product on the contact problems of a real run-in.

What it reproduces
    docs/benchmarks.md, "Contact solve on run-in problems": the contact
    problems an implicit run-in meets, captured from the command line
    (``python -m transient``) on the shipped scene
    ``steady/examples/voronoi_transient.toml`` with only ``[grid] n`` changed,
    then solved again as the run solves them (the entry the run calls,
    :func:`transient.contact.solve_trusted_contact` where the tree has it, else
    :func:`transient.contact.solve_contact`; same height, shift, warm start and
    tolerances), by this tree and by another one (``--base``), side by side in
    one process, interleaved round by round; the padded product
    (:meth:`steady.halfspace.HalfSpace.displacement`) likewise::

        # capture once (every 8th solve of the run, at most 24 of them)
        python studies/benchmarks/bench_contact_solve.py capture --n 1024 --dir /tmp/cs1024
        # this tree against another checkout, e.g. git worktree add ../base REV; 5 rounds
        python studies/benchmarks/bench_contact_solve.py compare --dir /tmp/cs1024 \
            --base ../base --out compare_1024.h5

    ``replay --dir DIR --preconditioner NAME`` solves the problems with this
    tree alone and a preconditioner of choice; ``products --base TREE``
    times padded products and unpadded FFT pairs (double, single precision;
    one and two threads) of both trees on synthetic fields; ``overlap --dir DIR``
    times the solves alone and while the run's history figures are computed on a
    worker thread, as the run does.

    Capturing runs the command line up to the last problem kept (at n = 1024
    about a minute on 2 quiet cores); a comparison takes a few seconds per
    problem and round.  ``capture --n 48 --count 2`` makes a smoke run.  Every
    subcommand but ``capture`` writes HDF5 (one dataset per column, the
    medians as attributes) and prints the medians.
"""

from __future__ import annotations

import argparse
import concurrent.futures
import contextlib
import functools
import importlib
import io
import os
import pathlib
import platform
import re
import sys
import tempfile
import time
import types

import numpy as np
import scipy.fft

SCENE = (pathlib.Path(__file__).resolve().parents[2] / "steady" / "examples"
         / "voronoi_transient.toml")
STRIDE = 8     # keep every STRIDE-th solve of the run
COUNT = 24     # at most this many problems
REPEAT = 3     # best of REPEAT solves per problem
PRODUCTS = 9   # padded products timed (median)
ROUNDS = 7     # interleaved rounds of the product timings


class _Enough(BaseException):
    """Raised inside the run once the last problem is kept.

    Not an ``Exception``: the command line reports those and returns its exit status.
    """


def _scene_copy(n, directory):
    """The shipped scene with ``[grid] n`` set to ``n``, written into ``directory``."""
    text, count = re.subn(r"(?m)^(\[grid\][^\[]*?^n\s*=\s*)\d+", rf"\g<1>{n}", SCENE.read_text())
    if count != 1:
        raise ValueError(f"no [grid] n in {SCENE}")
    path = pathlib.Path(directory) / f"scene_n{n}.toml"
    path.write_text(text)
    return path


def capture(n, directory, *, stride=STRIDE, count=COUNT):
    """Run the command line on the scene at ``n``; keep every ``stride``-th contact problem.

    Returns
    -------
    int
        Problems written to ``directory``.
    """
    directory = pathlib.Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    problem_module = _caller()
    name = _entry(problem_module)
    solve = getattr(problem_module, name)
    calls = [0, 0]

    def keep(halfspace, face_mask, height, normal_force, **kw):
        calls[0] += 1
        if calls[0] % stride == 0:
            arrays = {k: v for k, v in kw.items() if isinstance(v, np.ndarray)}
            np.savez(directory / f"problem_{calls[1]:03d}.npz", face_mask=face_mask,
                     height=height, normal_force=normal_force, shape=halfspace.shape,
                     h=halfspace.h, E_star=halfspace.E_star, rtol=kw["rtol"], atol=kw["atol"],
                     maxiter=-1 if kw["maxiter"] is None else kw["maxiter"], **arrays)
            calls[1] += 1
        res = solve(halfspace, face_mask, height, normal_force, **kw)
        if calls[1] >= count:
            raise _Enough
        return res

    setattr(problem_module, name, keep)
    cli = importlib.import_module("transient.__main__")
    try:
        with tempfile.TemporaryDirectory() as tmp, contextlib.redirect_stdout(io.StringIO()):
            argv = [str(_scene_copy(n, tmp)), "-o", str(pathlib.Path(tmp) / "run.h5")]
            with contextlib.suppress(_Enough):
                cli.main(argv)
    finally:
        setattr(problem_module, name, solve)
    return calls[1]


def _caller():
    """The module whose solver a run calls: the stage solver's (earlier trees: the problem's)."""
    try:
        return importlib.import_module("transient.solver")
    except ImportError:
        return importlib.import_module("transient.problem")


def _entry(module):
    """Name of the contact solver's entry the run calls (trusted where the tree has one)."""
    return ("solve_trusted_contact" if hasattr(module, "solve_trusted_contact")
            else "solve_contact")


def _best(function, repeat):
    """Best wall time (s) of ``repeat`` calls, and the last result."""
    best = np.inf
    for _ in range(repeat):
        t = time.perf_counter()
        result = function()
        best = min(best, time.perf_counter() - t)
    return best, result


def replay(directory, *, repeat=REPEAT, preconditioner="auto"):
    """Solve every captured problem again; one row (dict) per problem.

    ``preconditioner`` (a registered name) replaces the run's ``"auto"``.
    """
    from steady.halfspace import HalfSpace
    from transient import contact

    solve_contact = getattr(contact, _entry(contact))

    paths = sorted(pathlib.Path(directory).glob("problem_*.npz"))
    if not paths:
        raise ValueError(f"no problem_*.npz in {directory}")
    first = np.load(paths[0])
    halfspace = HalfSpace(tuple(first["shape"]), float(first["h"]), float(first["E_star"]))
    field = np.where(first["face_mask"], 1e4, 0.0)
    halfspace.displacement(field)  # plans and work buffers
    product, _ = _best(functools.partial(halfspace.displacement, field), PRODUCTS)
    rows = []
    for path in paths:
        data = dict(np.load(path))
        solve = functools.partial(_captured_solve, solve_contact, halfspace, data,
                                  preconditioner=preconditioner)
        seconds, res = _best(solve, repeat)
        rows.append(dict(problem=path.name, seconds=seconds, nit=res.nit, product=product,
                         success=res.success, approach=res.approach,
                         load=float(res.pressure.sum() * halfspace.h**2)))
    return rows


def _captured_solve(solve, halfspace, data, **options):
    """``solve`` (an entry of ``transient.contact``) on one captured problem ``data``."""
    maxiter = int(data["maxiter"])
    return solve(halfspace, data["face_mask"], data["height"], float(data["normal_force"]),
                 rtol=float(data["rtol"]), atol=float(data["atol"]),
                 maxiter=None if maxiter < 0 else maxiter, **options,
                 **{k: data[k] for k in ("shift", "x0", "x0_displacement") if k in data})


def _base_modules(tree):
    """``steady/halfspace.py`` and ``transient/contact.py`` of another tree, as modules.

    Loaded from their files under other names (``steady`` and ``transient``
    as packages ``runin_base_steady`` and ``runin_base_transient`` whose
    ``__init__`` is not run), so that both versions live in this process.
    """
    tree = pathlib.Path(tree).resolve()
    return (importlib.import_module(_base_package(tree, "steady") + ".halfspace"),
            importlib.import_module(_base_package(tree, "transient") + ".contact"))


def _base_package(tree, name):
    """The package ``name`` of the tree ``tree`` as ``runin_base_<name>``, its ``__init__`` not run.

    Its modules import each other relatively, so they load from that tree.
    """
    package = types.ModuleType(f"runin_base_{name}")
    package.__path__ = [str(pathlib.Path(tree).resolve() / name)]
    sys.modules[package.__name__] = package
    return package.__name__


def compare(directory, base, *, rounds=ROUNDS):
    """The captured problems solved by the tree ``base`` and by this one, interleaved.

    Each round solves every problem with both versions, one after the other
    (the order alternating from round to round), and times one padded
    product of each.

    Returns
    -------
    list of dict
        One row per round, problem and version: wall and CPU seconds,
        iterations, approach (m), the largest difference of the two versions' pressures
        over the base's peak and, for the product rows, ``problem = "product"``.
    """
    from steady import halfspace as this_halfspace
    from transient import contact as this_contact

    paths = sorted(pathlib.Path(directory).glob("problem_*.npz"))
    if not paths:
        raise ValueError(f"no problem_*.npz in {directory}")
    versions = {"base": _base_modules(base), "this": (this_halfspace, this_contact)}
    first = np.load(paths[0])
    spaces, solvers = {}, {}
    for name, (hs_module, contact_module) in versions.items():
        spaces[name] = hs_module.HalfSpace(tuple(first["shape"]), float(first["h"]),
                                           float(first["E_star"]))
        solvers[name] = getattr(contact_module, _entry(contact_module))
    field = np.where(first["face_mask"], 1e4, 0.0)
    problems = [dict(np.load(path)) for path in paths]
    rows = []
    for r in range(rounds):
        order = list(versions) if r % 2 == 0 else list(versions)[::-1]
        for name in order:
            wall, cpu, _ = _timed(functools.partial(spaces[name].displacement, field))
            rows.append(dict(round=r, problem="product", version=name, seconds=wall, cpu=cpu,
                             nit=0, approach=np.nan, pressure_difference=np.nan))
        for path, data in zip(paths, problems, strict=True):
            pressures = {}
            for name in order:
                wall, cpu, res = _timed(functools.partial(
                    _captured_solve, solvers[name], spaces[name], data))
                pressures[name] = res.pressure
                rows.append(dict(round=r, problem=path.name, version=name, seconds=wall,
                                 cpu=cpu, nit=res.nit, approach=res.approach))
            difference = float(np.abs(pressures["this"] - pressures["base"]).max()
                               / pressures["base"].max())
            for row in rows[-2:]:
                row["pressure_difference"] = difference
    return rows


def overlap(directory, *, rounds=ROUNDS):
    """The captured problems solved alone and while the run's history figures are computed.

    The run computes each accepted step's face figures
    (:meth:`transient.history.FaceEstimator.figures`, its transforms on one
    thread) on a worker thread while the solver goes on with the next step
    (``transient.runin``). Per round and problem: the solve alone, the figures
    alone, the solve while the figures run on a worker thread, and the wall time
    of the two together (submit, solve, wait).

    Returns
    -------
    list of dict
        One row per round and problem, in seconds.
    """
    from transient import contact
    from transient.history import FaceEstimator
    from transient.scene import load_transient_scene, wear_problem_of

    paths = sorted(pathlib.Path(directory).glob("problem_*.npz"))
    if not paths:
        raise ValueError(f"no problem_*.npz in {directory}")
    problems = [dict(np.load(path)) for path in paths]
    scene, _, _ = load_transient_scene(SCENE)
    problem = wear_problem_of(scene, n=int(problems[0]["shape"][0]))
    estimator = FaceEstimator(problem, np.zeros(problem.halfspace.shape))
    estimator.workers, estimator.threaded = 1, True  # as the run sets them
    solve = getattr(contact, _entry(contact))
    rows = []
    with concurrent.futures.ThreadPoolExecutor(max_workers=1) as pool:
        for r in range(rounds):
            for path, data in zip(paths, problems, strict=True):
                run = functools.partial(_captured_solve, solve, problem.halfspace, data)
                alone, _, res = _timed(run)
                figures = functools.partial(estimator.figures, 0.0, data["height"],
                                            res.pressure, res.approach)
                figures_alone = _timed(figures)[0]
                start = time.perf_counter()
                future = pool.submit(figures)
                during = _timed(run)[0]
                future.result()
                rows.append(dict(round=r, problem=path.name, solve=alone, figures=figures_alone,
                                 solve_during_figures=during,
                                 together=time.perf_counter() - start))
    return rows


def _timed(function):
    """Wall and CPU seconds of one call, and its result."""
    wall, cpu = time.perf_counter(), time.process_time()
    result = function()
    return time.perf_counter() - wall, time.process_time() - cpu, result


def summary(rows):
    """Medians over the rounds: per solve and per product, each version, and their ratios."""
    out = {}
    for kind in ("solve", "product"):
        per_round = {}
        for row in rows:
            if (row["problem"] == "product") != (kind == "product"):
                continue
            key = (row["round"], row["version"])
            wall, cpu, count = per_round.get(key, (0.0, 0.0, 0))
            per_round[key] = (wall + row["seconds"], cpu + row["cpu"], count + 1)
        rounds = sorted({r for r, _ in per_round})
        for i, unit in enumerate(("wall", "cpu")):
            base = np.array([per_round[r, "base"][i] / per_round[r, "base"][2] for r in rounds])
            this = np.array([per_round[r, "this"][i] / per_round[r, "this"][2] for r in rounds])
            out[f"{kind} {unit} base"] = float(np.median(base))
            out[f"{kind} {unit} this"] = float(np.median(this))
            out[f"{kind} {unit} ratio"] = float(np.median(this / base))
    solves = [r for r in rows if r["problem"] != "product"]
    for name in ("base", "this"):
        out[f"iterations {name}"] = float(np.mean([r["nit"] for r in solves
                                                   if r["version"] == name]))
    approach = {(r["round"], r["problem"], r["version"]): r["approach"] for r in solves}
    out["approach difference"] = max(
        abs(approach[k[0], k[1], "this"] - v) / abs(v)
        for k, v in approach.items() if k[2] == "base")
    out["pressure difference"] = max(r["pressure_difference"] for r in solves)
    nit = {(r["round"], r["problem"], r["version"]): r["nit"] for r in solves}
    out["iteration mismatches"] = sum(nit[k[0], k[1], "this"] != v
                                      for k, v in nit.items() if k[2] == "base")
    return out


def products(sizes, base, *, rounds=ROUNDS):
    """Padded products and unpadded pairs, side by side in this process; one row per case.

    Times :meth:`~steady.halfspace.HalfSpace.displacement` of this tree and of
    the ``steady/halfspace.py`` of the tree ``base`` (loaded from its file), each
    with ``workers`` 1 and 2, and an unpadded ``rfft2``/``irfft2`` pair in
    double and single precision, interleaved over ``rounds`` rounds; the
    median per case.
    """
    from steady.halfspace import HalfSpace

    module = importlib.import_module(_base_package(base, "steady") + ".halfspace")
    rows = []
    for n in sizes:
        p = np.random.default_rng(2711).random((n, n))
        cases = {}
        for workers in (1, 2):
            for label, cls in (("base", module.HalfSpace), ("this", HalfSpace)):
                hs = cls(n, 1e-5, 1e6, workers=workers)
                cases[f"{label} product, workers {workers}"] = functools.partial(
                    hs.displacement, p)
            for dtype in (np.float64, np.float32):
                field = p.astype(dtype)
                cases[f"unpadded {np.dtype(dtype).name} pair, workers {workers}"] = (
                    functools.partial(_pair, field, workers))
        times = {key: [] for key in cases}
        calls = max(1, int(4e6 / n**2))
        for _ in range(rounds):
            for key, function in cases.items():
                times[key].append(_best(function, calls)[0])
        for key, values in times.items():
            rows.append(dict(n=n, case=key, seconds=float(np.median(values))))
    return rows


def _pair(field, workers):
    """An unpadded real FFT pair of ``field``."""
    return scipy.fft.irfft2(scipy.fft.rfft2(field, workers=workers), s=field.shape,
                            workers=workers)


def main(argv=None):
    """Command line (see the module docstring)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    cap = sub.add_parser("capture")
    cap.add_argument("--n", type=int, required=True)
    cap.add_argument("--dir", type=pathlib.Path, required=True)
    cap.add_argument("--stride", type=int, default=STRIDE)
    cap.add_argument("--count", type=int, default=COUNT)
    rep = sub.add_parser("replay")
    rep.add_argument("--dir", type=pathlib.Path, required=True)
    rep.add_argument("--repeat", type=int, default=REPEAT)
    rep.add_argument("--out", type=pathlib.Path, required=True)
    rep.add_argument("--preconditioner", default="auto",
                     help="a registered preconditioner instead of the run's 'auto'")
    comp = sub.add_parser("compare")
    comp.add_argument("--dir", type=pathlib.Path, required=True)
    comp.add_argument("--base", type=pathlib.Path, required=True,
                      help="tree whose solver is the baseline")
    comp.add_argument("--rounds", type=int, default=ROUNDS)
    comp.add_argument("--out", type=pathlib.Path, required=True)
    over = sub.add_parser("overlap")
    over.add_argument("--dir", type=pathlib.Path, required=True)
    over.add_argument("--rounds", type=int, default=ROUNDS)
    over.add_argument("--out", type=pathlib.Path, required=True)
    prod = sub.add_parser("products")
    prod.add_argument("--sizes", type=int, nargs="+", default=[256, 512, 1024, 2048])
    prod.add_argument("--base", type=pathlib.Path, required=True,
                      help="tree whose steady/halfspace.py is the baseline")
    prod.add_argument("--rounds", type=int, default=ROUNDS)
    args = parser.parse_args(argv)
    if args.command == "compare":
        rows = compare(args.dir, args.base, rounds=args.rounds)
        figures = summary(rows)
        for key, value in figures.items():
            print(f"{key}: {value:.4g}")
        _write_rows(args.out, rows, figures, directory=str(args.dir), base=str(args.base))
        return figures
    if args.command == "products":
        rows = products(args.sizes, args.base, rounds=args.rounds)
        for row in rows:
            print(f"| {row['n']} | {row['case']} | {1e3 * row['seconds']:.2f} |")
        return rows
    if args.command == "overlap":
        rows = overlap(args.dir, rounds=args.rounds)
        figures = {key: float(np.median([r[key] for r in rows]))
                   for key in ("solve", "figures", "solve_during_figures", "together")}
        figures["solve during figures / solve"] = float(np.median(
            [r["solve_during_figures"] / r["solve"] for r in rows]))
        figures["together / (solve + figures)"] = float(np.median(
            [r["together"] / (r["solve"] + r["figures"]) for r in rows]))
        for key, value in figures.items():
            print(f"{key}: {value:.4g}")
        _write_rows(args.out, rows, figures, directory=str(args.dir))
        return figures
    if args.command == "capture":
        kept = capture(args.n, args.dir, stride=args.stride, count=args.count)
        print(f"{kept} problems in {args.dir}")
        return kept
    rows = replay(args.dir, repeat=args.repeat, preconditioner=args.preconditioner)
    seconds = np.array([r["seconds"] for r in rows])
    nit = np.array([r["nit"] for r in rows])
    print(f"{len(rows)} solves: median {1e3 * np.median(seconds):.1f} ms, "
          f"mean {1e3 * seconds.mean():.1f} ms, {nit.mean():.2f} iterations; "
          f"padded product {1e3 * rows[0]['product']:.2f} ms")
    _write_rows(args.out, rows, {}, directory=str(args.dir), preconditioner=args.preconditioner)
    return rows


_UNITS = {"seconds": "s", "cpu": "s", "product": "s", "approach": "m", "load": "N", "nit": "1",
          "solve": "s", "figures": "s", "solve_during_figures": "s", "together": "s",
          "pressure_difference": "1"}


def _write_rows(path, rows, figures, **attrs):
    """The rows (one dataset per key) and the summary figures (attributes), HDF5."""
    from steady.safe_files import atomic_h5

    with atomic_h5(path, format="runin.bench_contact_solve", version=1, force=True) as f:
        f.attrs.update(machine=platform.processor() or platform.machine(),
                       python=platform.python_version(), numpy=np.__version__,
                       command=" ".join(sys.argv), load_average=os.getloadavg()[0], **attrs)
        for key, value in figures.items():
            f.attrs[key] = value
        for key in rows[0]:
            values = [r[key] for r in rows]
            text = isinstance(values[0], str)
            f[key] = np.array(values, dtype="S") if text else np.array(values)
            if key in _UNITS:
                f[key].attrs["units"] = _UNITS[key]


if __name__ == "__main__":
    main()
