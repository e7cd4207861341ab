"""Benchmark of the load-controlled contact solver against ContactMechanics and Tamaas.

Reproduces the tables of the "Contact solver" section of docs/benchmarks.md:

1. Flat punch and crowned (paraboloid) face at n = 128 ... 1024: wall time,
   iterations and time per iteration (in units of one padded FFT pair, the
   time of ``HalfSpace.displacement`` on the same grid) of
   :func:`transient.contact.solve_contact` and of the two peers'
   Polonsky-Keer solvers, at equal accuracy.
2. The preconditioners of :func:`solve_contact` (none, Jacobi, Fourier on
   the padded and on the unpadded grid, auto) at equal accuracy,
   without and with a diagonal shift.

Equal accuracy: all three codes use the same discrete operator (the exact
pixel kernel with zero padding; checked at start-up, agreement 1e-13).  Each solver
is run on a ladder of its own tolerance, loosest first, and timed at the
first tolerance whose rigid approach (evaluated the same way for all, from
the returned pressure) lies within ``ACCURACY`` (relative) of a tightly
converged reference, a band well below the depth error against the
analytic value (docs/benchmarks.md).  Timings are the best of ``REPEAT``
runs, every solver measured side by side in one run, one thread each.

Run (about 40 min on 2 shared cores), in a separate environment with the peers::

    python -m venv /work/peers-venv
    /work/peers-venv/bin/pip install -e . -r studies/benchmarks/requirements-peers.txt
    /work/peers-venv/bin/python studies/benchmarks/bench_contact.py --out bench_contact.h5

``--sizes 32 --pc-sizes 32 --repeat 1 --skip-peers`` makes a smoke run;
``--preconditioners-only`` runs table 2 alone (no peers needed).  A
peer that cannot be imported is skipped and the reason recorded.  Writes an HDF5 file (one group per
table) and prints the tables in Markdown.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import logging
import os
import platform
import sys
import tempfile
import time

import numpy as np

from steady import reference
from steady.halfspace import HalfSpace
from steady.outline import Circle
from steady.phases import Voronoi
from steady.safe_files import atomic_h5
from transient.contact import solve_contact

# -- parameters -------------------------------------------------------------------
RADIUS = 4e-3        # m, punch radius (paper Fig. 6)
E_STAR = 1.3e6       # Pa
FLAT_FORCE = 10.0    # N
HERTZ_FORCE = 0.3    # N; with the sphere below the Hertz contact radius is 0.6 a
SPHERE = 4 * E_STAR * (0.6 * RADIUS) ** 3 / (3 * HERTZ_FORCE)  # m, 80 mm
SIZES = (128, 256, 512, 1024)
PRECONDITIONER_SIZES = (256, 512)
REPEAT = 3
ACCURACY = 1e-7      # relative agreement of the approach with the reference
OUR_RTOL = (1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10)
CM_PENTOL = (1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10)   # times the approach
TAMAAS_TOL = (1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12)
# Shifted scenes: label -> (shift on phase 1 in units of K00, phase map, shift
# ratio of phase 0 to phase 1).  "pixels": 40 % of the pixels drawn at random
# (seed 3571) are phase 1; "voronoi": the run-in scene's map (400 seeds, 30 %
# phase 1, seed 2029), as in an implicit stage of steady/examples/voronoi_transient.toml.
SHIFTS = {"shift 1 K00": (1.0, None, 1.0),
          "shift 100 K00, two phases 1:0.01": (100.0, "pixels", 1e-2),
          "shift 10 K00, Voronoi 1:0.1": (10.0, "voronoi", 1e-1)}

logger = logging.getLogger("bench_contact")


class CountingHalfSpace(HalfSpace):
    """Half-space that counts its padded FFT pairs (one forward transform each)."""

    pairs = 0

    def _padded_spectrum(self, field_r, out):
        """Padded spectrum of a grid field, counted (every padded forward transform)."""
        self.pairs += 1
        return super()._padded_spectrum(field_r, out)


def case_setup(case, n):
    """Face mask, height (m), force (N) and analytic approach (m) of a test case.

    Parameters
    ----------
    case : {"flat", "crowned"}
        Flat punch, or the paraboloid face whose Hertz contact radius is ``0.6 a``.
    n : int
        Grid size.
    """
    grid = Circle(RADIUS).grid(n)
    face = grid.mask
    r = grid.radii
    if case == "flat":
        return face, np.zeros((n, n)), FLAT_FORCE, reference.flat_punch_approach(
            FLAT_FORCE, RADIUS, E_STAR)
    height = r**2 / (2 * SPHERE)
    return face, height, HERTZ_FORCE, reference.hertz(HERTZ_FORCE, SPHERE, E_STAR)[2]


def approach_of(hs, face, height, pressure):
    """Rigid approach from a pressure field, the same way for every solver."""
    contact = (pressure > 0) & face
    return float(np.mean((hs.displacement(pressure) + height)[contact]))


def best_time(run, repeat):
    """Best wall time (s) of ``repeat`` calls of ``run()``, and the last call's value."""
    best, out = np.inf, None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = run()
        best = min(best, time.perf_counter() - t0)
    return best, out


def fft_unit(hs, repeat=7):
    """Best wall time (s) of one padded FFT pair, ``hs.displacement``, on a random field."""
    p = np.random.default_rng(8191).random(hs.shape)
    return best_time(lambda: hs.displacement(p), repeat)[0]


# -- the three solvers ------------------------------------------------------------------

def run_ours(hs, face, height, force, tol, preconditioner="auto", shift=None):
    """Solve with :func:`transient.contact.solve_contact`; ``(pressure, nit, FFT pairs)``.

    Parameters
    ----------
    hs : CountingHalfSpace
    face : ndarray of bool, shape (n, n)
    height : ndarray, shape (n, n), m
    force : float, N
    tol : float
        ``rtol`` of the solver.
    preconditioner : str, optional
        As in :func:`~transient.contact.solve_contact` (default ``"auto"``).
    shift : ndarray, shape (n, n), m/Pa, optional
        Diagonal shift of the operator.
    """
    hs.pairs = 0
    res = solve_contact(hs, face, height, force, rtol=tol, shift=shift,
                        preconditioner=preconditioner, maxiter=20 * hs.shape[0])
    if not res.success:
        raise RuntimeError(res.message)
    return res.pressure, res.nit, hs.pairs


def make_cm(n):
    """ContactMechanics' Polonsky-Keer solver on the ``n x n`` grid, as ``run(...)``.

    Raises ``ImportError`` when ContactMechanics is not installed.
    """
    from ContactMechanics import FreeFFTElasticHalfSpace
    from ContactMechanics.Optimization.ConstrainedConjugateGradients import (
        constrained_conjugate_gradients,
    )
    from SurfaceTopography import Topography

    length = 2 * RADIUS
    substrate = FreeFFTElasticHalfSpace((n, n), E_STAR, (length, length))

    def run(hs, face, height, force, tol, d_scale):
        # ContactMechanics' heights are the counter-body's: minus ours.
        topography = Topography(np.ma.masked_array(-height, mask=~face), (length, length))
        res = constrained_conjugate_gradients(
            substrate, topography, external_force=force, pentol=tol * d_scale,
            forcetol=1e-3 * force / face.sum(), thermotol=tol, maxiter=100000)
        if not res.success:
            raise RuntimeError(res.message)
        return np.asarray(res.jac) / hs.h**2, res.nit, None

    return run


def make_tamaas(n):
    """Tamaas' Polonsky-Keer solver on the ``n x n`` grid, as ``run(...)``.

    Raises ``ImportError`` when Tamaas is not installed.
    """
    import tamaas as tm

    length = 2 * RADIUS
    tm.set_log_level(tm.LogLevel.info)

    def run(hs, face, height, force, tol, d_scale):
        model = tm.ModelFactory.createModel(tm.model_type.basic_2d, [length, length], [n, n])
        model.E = E_STAR
        model.nu = 0.0
        tm.ModelFactory.registerNonPeriodic(model, "dcfft")
        # Tamaas' surface is the counter-body's; off the face far out of reach.
        surface = np.where(face, -height, -1.0)
        solver = tm.PolonskyKeerRey(model, surface, tol, tm.PolonskyKeerRey.pressure,
                                    tm.PolonskyKeerRey.pressure)
        solver.setIntegralOperator("dcfft")
        solver.max_iter = 100000
        with _captured_output() as out:
            solver.solve(force / length**2)
        lines = [line.split() for line in out.getvalue().splitlines()]
        its = [int(w[0]) for w in lines if len(w) == 3 and w[0].isdigit()]
        pressure = np.array(model.traction).reshape(n, n)
        return pressure, (its[-1] if its else -1), None

    return run


@contextlib.contextmanager
def _captured_output():
    """Capture what compiled code writes to file descriptors 1 and 2."""
    sys.stdout.flush()
    sys.stderr.flush()
    saved = {fd: os.dup(fd) for fd in (1, 2)}
    buffer = io.StringIO()
    with tempfile.TemporaryFile(mode="w+") as tmp:
        for fd in saved:
            os.dup2(tmp.fileno(), fd)
        try:
            yield buffer
        finally:
            sys.stdout.flush()
            sys.stderr.flush()
            for fd, old in saved.items():
                os.dup2(old, fd)
                os.close(old)
            tmp.seek(0)
            buffer.write(tmp.read())


def peers():
    """The peers that import: ``(found, missing)``, name to factory and name to reason."""
    found, missing = {}, {}
    for name, factory in (("ContactMechanics", make_cm), ("Tamaas", make_tamaas)):
        try:
            factory(8)
            found[name] = factory
        except Exception as exc:  # record exactly why a peer is absent
            missing[name] = f"{type(exc).__name__}: {exc}"
    return found, missing


def check_same_operator(n=64):
    """The peers' operators must equal ours (same discrete problem)."""
    hs = HalfSpace(n, Circle(RADIUS).grid(n).h, E_STAR, workers=1)
    p = np.random.default_rng(4099).random((n, n))
    ours = hs.displacement(p)
    out = {}
    try:
        from ContactMechanics import FreeFFTElasticHalfSpace
        sub = FreeFFTElasticHalfSpace((n, n), E_STAR, (2 * RADIUS, 2 * RADIUS))
        cm = sub.evaluate_disp(-p * hs.h**2)  # forces, compressive negative
        out["ContactMechanics"] = float(np.abs(cm - ours).max() / np.abs(ours).max())
    except ImportError:
        pass
    try:
        import tamaas as tm
        model = tm.ModelFactory.createModel(tm.model_type.basic_2d,
                                            [2 * RADIUS, 2 * RADIUS], [n, n])
        model.E, model.nu = E_STAR, 0.0
        tm.ModelFactory.registerNonPeriodic(model, "dcfft")
        u = np.zeros((n, n, 1))
        model.operators["dcfft"](p[..., None].copy(), u)
        out["Tamaas"] = float(np.abs(u[..., 0] - ours).max() / np.abs(ours).max())
    except ImportError:
        pass
    return out


def at_equal_accuracy(run, ladder, approach, d_ref, repeat):
    """Loosest tolerance of the ladder that meets ACCURACY; best-of-repeat time there.

    ``run(tol)`` returns ``(pressure, nit, fft_pairs)``; ``approach(pressure)``
    the rigid approach it implies.
    """
    d = np.nan
    for tol in ladder:
        t0 = time.perf_counter()
        pressure, nit, pairs = run(tol)
        elapsed = time.perf_counter() - t0
        d = approach(pressure)
        if abs(d / d_ref - 1) <= ACCURACY:
            if repeat > 1:
                more, _ = best_time(lambda tol=tol: run(tol), repeat - 1)
                elapsed = min(elapsed, more)
            return dict(tol=tol, time=elapsed, nit=nit, pairs=pairs, approach=d)
    return dict(tol=np.nan, time=np.nan, nit=-1, pairs=None, approach=d)


# -- tables -------------------------------------------------------------------------------

def peer_table(sizes, repeat, found):
    """Rows of table 1: every solver at equal accuracy on the flat and crowned faces.

    Parameters
    ----------
    sizes : sequence of int
        Grid sizes.
    repeat : int
        Timed runs at the chosen tolerance; the best is kept.
    found : mapping of str to callable
        The peers' factories (:func:`peers`).

    Returns
    -------
    list of dict
    """
    rows = []
    for case in ("flat", "crowned"):
        for n in sizes:
            hs = CountingHalfSpace(n, Circle(RADIUS).grid(n).h, E_STAR, workers=1)
            face, height, force, d_exact = case_setup(case, n)
            unit = fft_unit(hs)
            ref_p = run_ours(hs, face, height, force, 1e-12)[0]
            d_ref = approach_of(hs, face, height, ref_p)
            row = dict(case=case, n=n, fft=unit, d_error=d_ref / d_exact - 1)

            def approach(pressure, hs=hs, face=face, height=height):
                return approach_of(hs, face, height, pressure)

            def ours(tol, hs=hs, face=face, height=height, force=force):
                return run_ours(hs, face, height, force, tol)

            row["runin"] = at_equal_accuracy(ours, OUR_RTOL, approach, d_ref, repeat)
            for name, factory in found.items():
                solver = factory(n)
                ladder = CM_PENTOL if name == "ContactMechanics" else TAMAAS_TOL
                def peer(tol, solver=solver, hs=hs, face=face, height=height, force=force,
                         d_ref=d_ref):
                    return solver(hs, face, height, force, tol, d_ref)

                row[name] = at_equal_accuracy(peer, ladder, approach, d_ref, repeat)
            rows.append(row)
            logger.info("%s n=%d: %s", case, n,
                        {k: (v["time"], v["nit"]) for k, v in row.items()
                         if isinstance(v, dict)})
    return rows


def preconditioner_table(sizes, repeat):
    """Rows of table 2: the preconditioners at equal accuracy, without and with a shift.

    Parameters
    ----------
    sizes : sequence of int
        Grid sizes.
    repeat : int
        Timed runs at the chosen tolerance; the best is kept.

    Returns
    -------
    list of dict
    """
    rows = []
    names = ["none", "jacobi", "fourier-padded", "fourier", "auto"]
    for n in sizes:
        hs = CountingHalfSpace(n, Circle(RADIUS).grid(n).h, E_STAR, workers=1)
        unit = fft_unit(hs)
        phases = {"pixels": np.random.default_rng(3571).random((n, n)) < 0.4,
                  # (fewer seeds on grids below the 400 seeds' minimum, n = 40)
                  "voronoi": Voronoi(min(400, (n // 2) ** 2), (0.7, 0.3), 2029).labels(n) == 1}
        scenes = [("flat", None), ("crowned", None)] + list(SHIFTS.items())
        for label, spec in scenes:
            face, height, force, _ = case_setup("crowned" if label == "crowned" else "flat", n)
            shift = None
            if spec is not None:
                magnitude, kind, low = spec
                ratio = 1.0 if kind is None else np.where(phases[kind], 1.0, low)
                shift = hs.self_influence * magnitude * ratio * np.ones((n, n))

            def approach(pressure, hs=hs, shift=shift, face=face, height=height):
                u = hs.displacement(pressure) + (0 if shift is None else shift * pressure)
                return float(np.mean((u + height)[(pressure > 0) & face]))

            d_ref = approach(run_ours(hs, face, height, force, 1e-12, shift=shift)[0])
            row = dict(scene=label, n=n, fft=unit)
            for name in names:
                def run(tol, name=name, hs=hs, shift=shift, face=face, height=height,
                        force=force):
                    return run_ours(hs, face, height, force, tol, preconditioner=name,
                                    shift=shift)
                row[name] = at_equal_accuracy(run, OUR_RTOL, approach, d_ref, repeat)
            rows.append(row)
            logger.info("%s n=%d: %s", label, n,
                        {k: (v["time"], v["nit"]) for k, v in row.items()
                         if isinstance(v, dict)})
    return rows


def markdown_peers(rows, found):
    """Table 1 in Markdown, from the rows of :func:`peer_table`."""
    names = ["runin"] + list(found)
    head = ("| case | n | depth error vs analytic | FFT pair (ms) | "
            + " | ".join(f"{k}: time (s), it, tol, t/it (FFT pairs)" for k in names)
            + " | runin FFT pairs / it | CM / runin | Tamaas / runin |")
    lines = [head, "|" + "---|" * (head.count("|") - 1)]
    for row in rows:
        cells = [row["case"], str(row["n"]), f"{row['d_error']:+.3e}", f"{1e3 * row['fft']:.1f}"]
        for k in names:
            v = row[k]
            per_it = v["time"] / max(v["nit"], 1) / row["fft"]
            cells.append(f"{v['time']:.3f}, {v['nit']}, {v['tol']:.0e}, {per_it:.2f}")
        ours = row["runin"]
        cells.append(f"{ours['pairs'] / max(ours['nit'], 1):.2f}")
        for k in ("ContactMechanics", "Tamaas"):
            cells.append(f"{row[k]['time'] / ours['time']:.1f}" if k in row else "n/a")
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def markdown_preconditioners(rows):
    """Table 2 in Markdown, from the rows of :func:`preconditioner_table`."""
    names = ["none", "jacobi", "fourier-padded", "fourier", "auto"]
    head = ("| scene | n | "
            + " | ".join(f"{k}: time (s), it, FFT pairs, rtol" for k in names) + " |")
    lines = [head, "|" + "---|" * (len(names) + 2)]
    for row in rows:
        cells = [row["scene"], str(row["n"])]
        for k in names:
            v = row[k]
            pairs = "-" if v["pairs"] is None else str(v["pairs"])
            cells.append(f"{v['time']:.3f}, {v['nit']}, {pairs}, {v['tol']:.0e}")
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def write_h5(path, peer_rows, pc_rows, meta):
    """Write both tables (a group per row) and the run's metadata to HDF5."""
    with atomic_h5(path, format="runin.bench_contact", version=1, force=True) as f:
        f.attrs["time_units"] = "s"
        for k, v in meta.items():
            f.attrs[k] = v
        for group, rows in (("peers", peer_rows), ("preconditioners", pc_rows)):
            g = f.create_group(group)
            for i, row in enumerate(rows):
                r = g.create_group(f"{i:03d}")
                for k, v in row.items():
                    if isinstance(v, dict):
                        s = r.create_group(k)
                        for kk, vv in v.items():
                            s.attrs[kk] = -1 if vv is None else vv
                    else:
                        r.attrs[k] = v


def main(argv=None):
    """Command line of the benchmark (see the module docstring).

    Parameters
    ----------
    argv : list of str, optional
        Arguments (default: ``sys.argv[1:]``).

    Returns
    -------
    peer_rows, pc_rows : list of dict
        The rows of both tables.
    """
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=list(SIZES))
    parser.add_argument("--pc-sizes", type=int, nargs="+", default=list(PRECONDITIONER_SIZES))
    parser.add_argument("--repeat", type=int, default=REPEAT)
    parser.add_argument("--out", default="bench_contact.h5")
    parser.add_argument("--skip-peers", action="store_true")
    parser.add_argument("--preconditioners-only", action="store_true",
                        help="only table 2 (no peers, no table 1)")
    args = parser.parse_args(argv)
    # One thread for every code; set before the peers load their FFT libraries.
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    logging.basicConfig(level=logging.INFO, format="%(message)s", stream=sys.stderr)
    skip = args.skip_peers or args.preconditioners_only
    found, missing = ({}, {"all": "skipped"}) if skip else peers()
    meta = dict(python=platform.python_version(), numpy=np.__version__,
                missing_peers=repr(missing), same_operator=repr(check_same_operator()),
                accuracy=ACCURACY, repeat=args.repeat)
    for name in found:
        try:
            meta[name] = __import__({"ContactMechanics": "ContactMechanics",
                                     "Tamaas": "tamaas"}[name]).__version__
        except AttributeError:
            pass
    print("meta:", meta)
    peer_rows = [] if args.preconditioners_only else peer_table(args.sizes, args.repeat, found)
    if peer_rows:
        print(markdown_peers(peer_rows, found))
    pc_rows = preconditioner_table(args.pc_sizes, args.repeat)
    print(markdown_preconditioners(pc_rows))
    write_h5(args.out, peer_rows, pc_rows, meta)
    return peer_rows, pc_rows


if __name__ == "__main__":
    main()
