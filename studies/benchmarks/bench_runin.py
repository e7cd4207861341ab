"""Run-in speed: contact-solver work against the grid, and the integrators at equal history error.

What it reproduces
    docs/benchmarks.md, "Run-in speed":

    ``--table``: the shipped scene ``steady/examples/voronoi_transient.toml``
    with only ``[grid] n`` changed (its ``[transient]`` settings, ``tol``
    overridable, flat start to the steady state, no checkpoints): accepted
    steps, contact solves, solver iterations, iterations per solve, padded
    FFT products (``HalfSpace.displacement``), unpadded FFT pairs of the
    preconditioner, the wall time of the run and the process's peak
    resident memory after it, also per pixel (the grids run in ascending
    order in one process, so the high-water mark is the largest grid's so
    far; it includes the interpreter and its libraries, about 110 MiB).

    ``--schemes``: the same scene (wear ratio overridable with ``--ratio``)
    at one grid, no jump, up to ``3 s*``: every implicit integrator of the
    registry on a ladder of tolerances, against ``sdirk2`` at ``tol = 1e-6``
    on the same grid.  History error: the largest relative deviation of the
    plain pixel rms slope of the face (:func:`transient.diagnostics.face_rms_slope`,
    computed from the stored snapshots, so that it does not depend on the
    figures the run itself records) at ``s/s* = 1e-4, 1e-3, 1e-2, 0.1, 0.3, 1, 3``;
    face error: rms of the shape difference at ``3 s*`` (best constant
    removed) over the reference's relief.  ``--scheme-names`` runs only the
    integrators named.

    ``--interfaces``: a scene whose phases change with depth (default
    ``steady/examples/spheres_transient.toml``, from its initial face to its
    ``end_depth``) at each of ``--sizes``: steps, rejected attempts, contact
    solves, Newton solves of the stages beyond their first
    (:attr:`transient.solver.StageSolver.stage_solves`), solver iterations,
    face pixels crossing an interface, CPU and wall time; with
    ``--reference-tol`` also the errors against a run of the same scene at
    that tolerance: the rms of the final worn depth's difference (its mean
    removed) in ``f*``, and the largest difference of the history's
    ``rms_slope`` (reference interpolated in the sliding distance) in
    ``grad_f0``.

    ``--levers``: the stopping rule of the stage solves side by side
    (``transient.solver.STAGE_NORM`` and ``STAGE_SHARE_FACTOR`` set per
    variant, :data:`LEVERS`; one of them also takes the conjugate
    directions' products in single precision, :func:`single_directions`), on
    two cases at each grid of ``--sizes``: the shipped scene as ``--table``
    runs it, and the homogeneous 1:2 rectangle
    (4 x 8 mm, the scene's load and counter-body) from flat at
    ``tol = 1e-4`` (the slow test of ``tests/test_transient_outlines.py``).
    Per run: steps, rejected attempts, solves, iterations, padded products,
    the process's CPU time and the wall time; history error: the largest
    deviation of the run's corrected rms slope (``history["rms_slope"]``,
    in ``grad_f0``) at ``s/s* = 1e-4 .. 3`` from that of a reference run of
    the same case with the first rule of :data:`LEVERS` at ``tol = 1e-6``;
    change: the same deviation from the first rule's run at the case's
    ``tol`` (what the rule alone moves).  The variants of one case run one after the other in one
    process, so that their CPU times compare on a shared machine.

    ``--shipped``: the rules of ``--rules`` on every shipped run-in scene
    (those with an ``[initial_face]``), each at its own grid and settings;
    the reference run takes ``0.1`` of the scene's ``tol``.

    ``--periodic``: the scene at each grid beside the same map on a periodic
    cell (``[punch] shape = "periodic"``, the punch's bounding square, the
    force scaled to the punch's mean pressure), alternated in one process:
    the work of each (operator products: padded for the punch, plain FFT
    pairs of the cell), its wall and CPU time, and the wall time of one
    product (the best of five means of ten).

    ``--memory``: the command line, ``python -m transient SCENE -o RUN.h5``
    (checkpoints every ``--checkpoint-interval`` seconds of wall time,
    default the scene's 10 s), on the scene with only ``[grid] n`` changed,
    one fresh process per grid: its peak resident memory (the maximum
    resident set of the child, imports included, about 100 MiB), per pixel,
    and :func:`transient.memory.run_in_memory` over it.  Each scene and run
    file goes to a temporary directory, removed afterwards.

    Wall times here are in-process and single; the side-by-side timing of
    two versions of the code is done on whole processes (docs/benchmarks.md
    gives the command).

How to run
    python studies/benchmarks/bench_runin.py --table --sizes 64 128 256 512 1024   # ~5 min
    python studies/benchmarks/bench_runin.py --table --sizes 2048   # manual, not CI: ~5 min
    python studies/benchmarks/bench_runin.py --schemes --n 256          # ~15 min on 2 cores
    python studies/benchmarks/bench_runin.py --schemes --n 256 --ratio 1000
    python studies/benchmarks/bench_runin.py --memory --sizes 512 1024   # ~5 min
    python studies/benchmarks/bench_runin.py --memory --sizes 2048   # manual, not CI: ~7 min, 4 GiB
    python studies/benchmarks/bench_runin.py --table --schemes --sizes 40 --n 40 --quick
                                                        # smoke test, seconds
    python studies/benchmarks/bench_runin.py --memory --sizes 40   # smoke test, seconds
    python studies/benchmarks/bench_runin.py --schemes --n 128 --scheme-names esdirk3 esdirk4
    python studies/benchmarks/bench_runin.py --interfaces --sizes 64 128 --reference-tol 1e-6
                                                        # ~10 min on 2 cores
    python studies/benchmarks/bench_runin.py --levers --sizes 64 128 192 256   # ~15 min
    python studies/benchmarks/bench_runin.py --levers --sizes 40 --quick   # smoke test, seconds
    python studies/benchmarks/bench_runin.py --shipped --rules "rms, share 1e-3" \
        "max, share 3e-2"                                                   # ~5 min
    python studies/benchmarks/bench_runin.py --periodic --sizes 512 1024   # ~10 min
    python studies/benchmarks/bench_runin.py --periodic --sizes 40   # smoke test, seconds

Writes ``--out`` (HDF5: one group per table row) and prints the tables in
Markdown.
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import logging
import os
import pathlib
import platform
import re
import resource
import subprocess
import sys
import tempfile
import time

import numpy as np

import transient.solver
from steady.halfspace import HalfSpace
from steady.outline import PeriodicCell, Rectangle
from steady.periodic import PeriodicHalfSpace
from steady.phases import Homogeneous
from steady.problem import FacePhases, Problem
from steady.safe_files import atomic_h5
from transient.diagnostics import face_rms_slope, shape_rms
from transient.memory import run_in_memory
from transient.options import RunOptions
from transient.output import read_run
from transient.preconditioners import FourierPreconditioner
from transient.problem import WearProblem
from transient.runin import run_in
from transient.scene import load_transient_scene, wear_problem_of
from transient.solver import StageSolver
from transient.spatial_error import _at
from transient.stepping import SCHEMES

# -- parameters -------------------------------------------------------------------
EXAMPLES = pathlib.Path(__file__).resolve().parents[2] / "steady" / "examples"
SCENE = EXAMPLES / "voronoi_transient.toml"
INTERFACES_SCENE = EXAMPLES / "spheres_transient.toml"
SIZES = (64, 128, 256, 512, 1024)
SCHEME_N = 256
DISTANCES = (1e-4, 1e-3, 1e-2, 0.1, 0.3, 1.0, 3.0)   # s*, where the history is compared
REFERENCE = ("sdirk2", 1e-6)
QUICK_REFERENCE = ("sdirk2", 1e-4)
LADDERS = {
    "implicit_euler": (1e-3, 1e-4, 1e-5),
    "bdf2": (1e-4, 1e-5, 3e-6),
    "sdirk2": (2e-3, 1e-3, 5e-4, 2e-4, 1e-4),
    "esdirk3": (1e-3, 5e-4, 2e-4, 1e-4, 5e-5, 2e-5),
    "esdirk4": (1e-3, 5e-4, 2e-4, 1e-4, 5e-5, 2e-5),
}
QUICK_LADDER = (1e-2, 1e-3)
#: Stopping rules of the stage solves (--levers): name -> (norm, factor on the share), and
#: "single" for the directions' products in single precision (:func:`single_directions`).
#: The first is the reference of the "change" column.
LEVERS = {
    "rms, share 1e-3": ("rms", 1.0),
    "rms, share 1e-2": ("rms", 10.0),
    "max, share 1e-3": ("max", 1.0),
    "max, share 1e-2": ("max", 10.0),
    "max, share 3e-2": ("max", 30.0),
    "max, share 1e-1": ("max", 100.0),
    "max, share 3e-1": ("max", 300.0),
    "max, share 3e-2, single K t": ("max", 30.0, "single"),
}
LEVER_TARGETS = (1e-4, 3e-4, 1e-3, 3e-3, 1e-2, 3e-2, 0.1, 0.3, 1.0, 3.0)   # s*
LEVER_REFERENCE_TOL = 1e-6
RECTANGLE = Rectangle(4e-3, 8e-3)
RECTANGLE_TOL = 1e-4
SHIPPED_REFERENCE = 0.1   # --shipped: the reference run's tol, times the scene's

logger = logging.getLogger("bench_runin")


@contextlib.contextmanager
def counted_transforms():
    """Count operator products (``displacement``) and the preconditioner's FFT pairs.

    A product is a padded FFT pair of :class:`HalfSpace` or a plain one of
    :class:`PeriodicHalfSpace`; a pair is one forward transform of
    :class:`FourierPreconditioner` (one per level and application), padded or
    not.
    """
    counts = {"products": 0, "pairs": 0}
    displacements = {cls: cls.displacement for cls in (HalfSpace, PeriodicHalfSpace)}
    forward = FourierPreconditioner._forward

    def counting(displacement):
        def counting_displacement(self, pressure_r):
            counts["products"] += 1
            return displacement(self, pressure_r)
        return counting_displacement

    def counting_forward(self, field):
        counts["pairs"] += 1
        return forward(self, field)

    for cls, displacement in displacements.items():
        cls.displacement = counting(displacement)
    FourierPreconditioner._forward = counting_forward
    try:
        yield counts
    finally:
        for cls, displacement in displacements.items():
            cls.displacement = displacement
        FourierPreconditioner._forward = forward


def problem_of(scene, n, ratio=None):
    """The scene's wear problem on the ``n x n`` grid, wear ratio ``k_2/k_1`` optionally reset."""
    if ratio is not None:
        k = scene.wear.coefficients
        scene = dataclasses.replace(scene, wear=dataclasses.replace(
            scene.wear, coefficients=(k[0], k[0] * ratio)))
    return wear_problem_of(scene, n=n)


def _peak_rss():
    """The process's peak resident memory so far, bytes (Linux counts ``ru_maxrss`` in KiB)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024


def run_counted(problem, initial_height, options):
    """One run-in with its work: ``(result, row)``.

    ``row``: steps, rejected, solves, iterations, products (padded FFT
    products), pairs (unpadded FFT pairs, the preconditioner's), wall and
    cpu (s, the process's CPU time over the run), peak_rss (bytes, the
    process's high-water mark after the run).
    """
    with counted_transforms() as counts:
        t, cpu = time.perf_counter(), time.process_time()
        result = run_in(problem, initial_height, options)
        wall, cpu = time.perf_counter() - t, time.process_time() - cpu
    row = dict(status=result.status, steps=result.steps, rejected=result.rejected,
               solves=result.solves, iterations=result.iterations,
               products=counts["products"], pairs=counts["pairs"],
               wall=wall, cpu=cpu, peak_rss=_peak_rss())
    return result, row


def grid_table(scene_path, sizes, tol):
    """Rows of the table: the scene at each grid size, to the steady state."""
    scene, options, initial = load_transient_scene(scene_path)
    tol = options.tol if tol is None else tol
    options = dataclasses.replace(options, tol=tol, checkpoint_interval=1e9)
    rows = []
    for n in sizes:
        problem = problem_of(scene, n)
        result, row = run_counted(problem, initial.recession(problem.grid), options)
        row.update(n=n, scheme=options.scheme, tol=tol)
        rows.append(row)
        logger.info("n = %d: %s", n, row)
    return rows


def periodic_scene(scene):
    """The scene's map on a periodic cell: the outline's bounding box, its mean pressure.

    The seeds of a Voronoi map are drawn in the box, so the cell holds the
    same seeds (its tessellation repeats with the cell).
    """
    lx, ly = scene.outline.half_extent
    cell = PeriodicCell(2 * lx, 2 * ly)
    return dataclasses.replace(scene, outline=cell,
                               normal_force=scene.normal_force * cell.area / scene.outline.area)


def _product_time(problem, repeats=5, count=10):
    """Wall time of one operator product (``displacement``), s: the best of ``repeats``."""
    hs, pressure = problem.halfspace, problem.steady_pressure()
    hs.displacement(pressure)
    best = np.inf
    for _ in range(repeats):
        t = time.perf_counter()
        for _ in range(count):
            hs.displacement(pressure)
        best = min(best, (time.perf_counter() - t) / count)
    return best


def periodic_table(scene_path, sizes, tol):
    """Rows of the side-by-side table: at each grid the punch, then the periodic cell."""
    scene, options, initial = load_transient_scene(scene_path)
    tol = options.tol if tol is None else tol
    options = dataclasses.replace(options, tol=tol, checkpoint_interval=1e9)
    rows = []
    for n in sizes:
        for face, variant in (("punch", scene), ("periodic cell", periodic_scene(scene))):
            problem = problem_of(variant, n)
            _, row = run_counted(problem, initial.recession(problem.grid), options)
            row.update(n=n, face=face, scheme=options.scheme, tol=tol,
                       product=_product_time(problem))
            rows.append(row)
            logger.info("n = %d, %s: %s", n, face, row)
    return rows


def scene_at(text, n):
    """The scene's TOML text with its ``[grid] n`` set to ``n``."""
    grid = re.search(r"(?ms)^\[grid\]$(.*?)(?=^\[|\Z)", text)
    if grid is None or not re.search(r"(?m)^n = \d+", grid.group(1)):
        raise ValueError("the scene has no '[grid] n = <int>' line to change")
    body = re.sub(r"(?m)^n = \d+", f"n = {int(n)}", grid.group(1), count=1)
    return text[:grid.start(1)] + body + text[grid.end(1):]


def command_peak(argv):
    """Run ``argv`` in a child process: ``(wall s, peak resident memory, bytes)``.

    The peak is the child's own maximum resident set (:func:`os.wait4`); a
    child that fails raises :class:`RuntimeError` with the end of its stderr.
    """
    # The child imports the packages of this tree, as this process does.
    root = str(pathlib.Path(__file__).resolve().parents[2])
    path = os.environ.get("PYTHONPATH")
    env = dict(os.environ, PYTHONPATH=root if not path else root + os.pathsep + path)
    t = time.perf_counter()
    with subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                          env=env) as proc:
        stderr = proc.stderr.read()
        _, status, usage = os.wait4(proc.pid, 0)
        proc.returncode = code = os.waitstatus_to_exitcode(status)  # reaped here
    if code != 0:
        raise RuntimeError(f"{' '.join(argv)} failed ({code}): "
                           f"{stderr.decode(errors='replace')[-2000:]}")
    return time.perf_counter() - t, usage.ru_maxrss * 1024


def memory_table(scene_path, sizes, checkpoint_interval=None):
    """Rows of the memory table: the command line on the scene at each grid size."""
    text = pathlib.Path(scene_path).read_text()
    rows = []
    with tempfile.TemporaryDirectory(prefix="bench_runin.") as tmp:
        for n in sizes:
            scene = pathlib.Path(tmp) / f"scene_{n}.toml"
            scene.write_text(scene_at(text, n))
            out = pathlib.Path(tmp) / f"run_{n}.h5"
            argv = [sys.executable, "-m", "transient", str(scene), "-o", str(out), "--force"]
            if checkpoint_interval is not None:
                argv += ["--checkpoint-interval", repr(float(checkpoint_interval))]
            wall, peak = command_peak(argv)
            result = read_run(out)[0]
            snapshots = int(result.snapshot_recession.shape[0])
            out.unlink()
            periodic = load_transient_scene(scene)[0].outline.periodic
            estimate = run_in_memory(n, snapshots, periodic=periodic)
            rows.append(dict(n=n, steps=result.steps, snapshots=snapshots, wall=wall,
                             peak_rss=peak, estimate=estimate, ratio=estimate / peak))
            logger.info("n = %d: %s", n, rows[-1])
    return rows


def history(result, problem):
    """Plain pixel rms slope of the face at the snapshots, and the last face (m)."""
    hs, face = problem.halfspace, problem.face_mask
    slopes = []
    for height, pressure in zip(result.snapshot_recession, result.snapshot_pressure,
                                strict=True):
        height = np.where(face, height, 0.0)
        kp = hs.displacement(pressure)
        contact = face & (pressure > 0)
        approach = float(np.mean((height + kp)[contact]))
        slopes.append(face_rms_slope(hs, face, height, pressure, approach,
                                     periodic=problem.outline.periodic))
    return np.array(slopes), np.where(face, result.snapshot_recession[-1], 0.0)


def scheme_table(scene_path, n, ratio, ladders, reference=REFERENCE):
    """Rows of the integrator comparison at equal history error (see the module docstring)."""
    scene, _, _ = load_transient_scene(scene_path)

    def one(name, tol):
        problem = problem_of(scene, n, ratio)
        options = RunOptions(scheme=name, tol=tol, snapshots_s_star=DISTANCES,
                             distance_limit=DISTANCES[-1] * problem.distance_scale,
                             jump_spread=0.0, spread_tol=1e-300,
                             shape_tol=1e-300, max_steps=10 ** 6, checkpoint_interval=1e9)
        result, row = run_counted(problem, np.zeros((n, n)), options)
        slopes, face = history(result, problem)
        return row, slopes, face, problem.face_mask

    _, ref_slopes, ref_face, face_mask = one(*reference)
    relief = shape_rms(ref_face, face_mask)
    rows = []
    for name, ladder in ladders.items():
        for tol in ladder:
            row, slopes, face = one(name, tol)[:3]
            deviation = np.abs(slopes / ref_slopes - 1)
            row.update(scheme=name, tol=tol, n=n, history_error=float(deviation.max()),
                       worst_distance=DISTANCES[int(np.argmax(deviation))],
                       face_error=shape_rms(face - ref_face, face_mask) / relief)
            rows.append(row)
            logger.info("%s tol %.0e: %s", name, tol, row)
    return rows


@contextlib.contextmanager
def counted_stages():
    """Count the implicit stages (:meth:`transient.solver.StageSolver.implicit` calls)."""
    counts = {"stages": 0}
    implicit = StageSolver.implicit

    def counting_implicit(self, *args, **kwargs):
        counts["stages"] += 1
        return implicit(self, *args, **kwargs)

    StageSolver.implicit = counting_implicit
    try:
        yield counts
    finally:
        StageSolver.implicit = implicit


def _interface_run(scene, options, initial, n):
    """One run of a depth scene on the ``n x n`` grid: ``(row, worn depth, history, scales)``.

    ``row`` as :func:`run_counted`'s, with ``crossings`` (face pixels that
    changed segment, summed over the steps) and ``extra_newton`` (contact
    solves of the stages beyond one each); the worn depth on the face (m),
    the history's ``distance`` and ``rms_slope``, and ``(f*, grad_f0)``.
    """
    problem = problem_of(scene, n)
    with counted_stages() as counts:
        result, row = run_counted(problem, initial.recession(problem.grid), options)
    state, face = result.state, problem.face_mask
    worn = problem.worn_depth(np.where(face, state.recession, 0.0), state.offset,
                              np.where(face, state.initial_recession, 0.0))
    history = {k: np.asarray(result.history[k]) for k in ("distance", "rms_slope", "crossings")}
    row.update(n=n, tol=options.tol, scheme=options.scheme,
               crossings=int(np.nansum(history["crossings"])),
               extra_newton=int(result.solves - 1 - counts["stages"]))
    return row, worn[face], history, (problem.depth_scale, result.reference_slope)


def interface_table(scene_path, sizes, tol, reference_tol):
    """Rows of the table of a scene across interfaces (see the module docstring)."""
    scene, options, initial = load_transient_scene(scene_path)
    options = dataclasses.replace(options, checkpoint_interval=1e9,
                                  tol=options.tol if tol is None else tol)
    rows = []
    for n in sizes:
        row, worn, history, (f_star, grad_f0) = _interface_run(scene, options, initial, n)
        if reference_tol is not None:
            _, worn_ref, ref, _ = _interface_run(
                scene, dataclasses.replace(options, tol=reference_tol), initial, n)
            d = worn - worn_ref
            inside = history["distance"] <= ref["distance"][-1]
            slope = np.interp(history["distance"][inside], ref["distance"], ref["rms_slope"])
            row.update(reference_tol=reference_tol,
                       face_error=float(np.sqrt(np.mean((d - d.mean()) ** 2))) / f_star,
                       slope_error=float(np.max(np.abs(history["rms_slope"][inside] - slope)))
                       / grad_f0)
        rows.append(row)
        logger.info("n = %d: %s", n, row)
    return rows


def markdown_interfaces(rows):
    """The table across interfaces in Markdown."""
    lines = ["| n | scheme, tol | steps (rejected) | contact solves | second Newton solves "
             "| iterations | iterations / solve | crossings | CPU (s) | wall (s) "
             "| final face (f*) | rms slope (grad_f0) |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        errors = (f"{r['face_error']:.1e} | {r['slope_error']:.1e}" if "face_error" in r
                  else "- | -")
        lines.append(f"| {r['n']} | {r['scheme']}, {r['tol']:.2g} | {r['steps']} "
                     f"({r['rejected']}) | {r['solves']} | {r['extra_newton']} | "
                     f"{r['iterations']} | {r['iterations'] / r['solves']:.1f} | "
                     f"{r['crossings']} | {r['cpu']:.1f} | {r['wall']:.1f} | {errors} |")


@contextlib.contextmanager
def stage_rule(norm, factor):
    """The stage solves' stopping rule set to ``norm`` and ``factor`` (see ``--levers``)."""
    saved = transient.solver.STAGE_NORM, transient.solver.STAGE_SHARE_FACTOR
    transient.solver.STAGE_NORM, transient.solver.STAGE_SHARE_FACTOR = norm, factor
    try:
        yield
    finally:
        transient.solver.STAGE_NORM, transient.solver.STAGE_SHARE_FACTOR = saved


@contextlib.contextmanager
def single_directions():
    """The conjugate directions' products ``K t`` in single precision (``--single``).

    A probe of mixed precision: each iteration's product of the direction by
    ``K`` is a float32 padded FFT product (``scipy.fft``, the influence
    spectrum rounded to complex64); the pressure, ``K p`` (updated with
    those products, recomputed in double every 50 iterations and before a
    solve ends) and the residual stay in double.
    """
    import scipy.fft

    from transient import contact

    call = contact._Operator.__call__
    spectra = {}

    def single(self, p, *, contiguous=True):
        if contiguous:
            return call(self, p, contiguous=True)
        self.products += 1
        hs = self.halfspace
        nx, ny = hs.shape
        kernel = spectra.get(id(hs))
        if kernel is None:
            kernel = spectra[id(hs)] = hs._influence_q.astype(np.complex64)
        q = scipy.fft.rfft2(p.astype(np.float32), s=(2 * nx, 2 * ny))
        q *= kernel
        return scipy.fft.irfft2(q, s=(2 * nx, 2 * ny))[:nx, :ny].astype(float)

    contact._Operator.__call__ = single
    try:
        yield
    finally:
        contact._Operator.__call__ = call


def lever_cases(scene_path, sizes):
    """The cases of ``--levers``: ``(n, name, problem, initial recession, options)``."""
    scene, options, initial = load_transient_scene(scene_path)
    options = dataclasses.replace(options, checkpoint_interval=1e9)
    for n in sizes:
        voronoi = problem_of(scene, n)
        yield n, "voronoi", voronoi, initial.recession(voronoi.grid), options
        grid = RECTANGLE.grid(n)
        rectangle = WearProblem(Problem(FacePhases(grid, Homogeneous().labels(grid), 1),
                                        [scene.wear.coefficients[0]], scene.normal_force,
                                        scene.E_star))
        yield (n, "rectangle", rectangle, np.zeros(grid.shape),
               RunOptions(tol=RECTANGLE_TOL, checkpoint_interval=1e9))


def history_values(result):
    """The run's corrected rms slope at ``LEVER_TARGETS`` (s*), in ``grad_f0``."""
    h = result.history
    at = np.asarray(LEVER_TARGETS) * result.distance_scale
    return _at(h["distance"], h["rms_slope"], at, steady=result.status == "steady") \
        / result.reference_slope


def shipped_cases():
    """Every shipped run-in scene at its own grid: ``(n, name, problem, initial, options)``."""
    for path in sorted(SCENE.parent.glob("*.toml")):
        if not re.search(r"(?m)^\[initial_face\]", path.read_text()):
            continue
        scene, options, initial = load_transient_scene(path)
        problem = wear_problem_of(scene)
        yield (max(problem.grid.shape), path.stem, problem, initial.recession(problem.grid),
               dataclasses.replace(options, checkpoint_interval=1e9))


def lever_table(cases, levers, reference_tol):
    """Rows of the stopping-rule comparison (see the module docstring).

    ``cases``: ``(n, name, problem, initial recession, options)``; ``reference_tol``:
    the reference run's ``tol`` from the case's.
    """
    rows = []
    for n, case, problem, initial, options in cases:
        with stage_rule(*next(iter(levers.values()))[:2]):
            reference, _ = run_counted(problem, initial, dataclasses.replace(
                options, tol=reference_tol(options.tol)))
        ref, first = history_values(reference), None
        for name, (norm, factor, *single) in levers.items():
            with stage_rule(norm, factor), \
                    single_directions() if single else contextlib.nullcontext():
                result, row = run_counted(problem, initial, options)
            values = history_values(result)
            first = values if first is None else first
            deviation = np.abs(values - ref)
            row.update(n=n, case=case, rule=name, tol=options.tol,
                       history_error=float(np.nanmax(deviation)),
                       worst_distance=LEVER_TARGETS[int(np.nanargmax(deviation))],
                       change=float(np.nanmax(np.abs(values - first))))
            rows.append(row)
            logger.info("%s n = %d %s: %s", case, n, name, row)
    return rows


def markdown_levers(rows):
    """The stopping-rule table in Markdown."""
    lines = ["| case | n | stage rule | steps | rejected | contact solves | iterations "
             "| iterations / solve | padded products | CPU (s) | wall (s) "
             "| history error, grad_f0 (at s/s*) | change, grad_f0 |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['case']} | {r['n']} | {r['rule']} | {r['steps']} | "
                     f"{r['rejected']} | {r['solves']} | {r['iterations']} | "
                     f"{r['iterations'] / r['solves']:.2f} | {r['products']} | "
                     f"{r['cpu']:.1f} | {r['wall']:.1f} | {r['history_error']:.1e} "
                     f"({r['worst_distance']:g}) | {r['change']:.1e} |")
    return "\n".join(lines)


def markdown_table(rows):
    """The grid table in Markdown."""
    lines = ["| n | scheme, tol | steps | contact solves | iterations | iterations / solve "
             "| padded products | preconditioner pairs | wall (s) | peak memory (MiB) "
             "| bytes / pixel |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['n']} | {r['scheme']}, {r['tol']:.2g} | {r['steps']} | "
                     f"{r['solves']} | {r['iterations']} | "
                     f"{r['iterations'] / r['solves']:.1f} | {r['products']} | {r['pairs']} | "
                     f"{r['wall']:.1f} | {r['peak_rss'] / 2 ** 20:.0f} | "
                     f"{r['peak_rss'] / r['n'] ** 2:.0f} |")
    return "\n".join(lines)


def markdown_periodic(rows):
    """The side-by-side table in Markdown, each cell's time over the punch's."""
    lines = ["| n | face | steps | contact solves | iterations | operator products "
             "| one product (ms) | wall (s) | CPU (s) | CPU / punch's |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    punch = {}
    for r in rows:
        if r["face"] == "punch":
            punch[r["n"]] = r["cpu"]
        ratio = r["cpu"] / punch[r["n"]] if r["n"] in punch else float("nan")
        lines.append(f"| {r['n']} | {r['face']} | {r['steps']} | {r['solves']} | "
                     f"{r['iterations']} | {r['products']} | {1e3 * r['product']:.2f} | "
                     f"{r['wall']:.1f} | {r['cpu']:.1f} | {ratio:.2f} |")
    return "\n".join(lines)


def markdown_memory(rows):
    """The memory table in Markdown."""
    lines = ["| n | steps | snapshots | wall (s) | peak memory (MiB) | bytes / pixel "
             "| `run_in_memory` (MiB) | estimate / peak |",
             "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['n']} | {r['steps']} | {r['snapshots']} | {r['wall']:.1f} | "
                     f"{r['peak_rss'] / 2 ** 20:.0f} | {r['peak_rss'] / r['n'] ** 2:.0f} | "
                     f"{r['estimate'] / 2 ** 20:.0f} | {r['ratio']:.2f} |")
    return "\n".join(lines)


def markdown_schemes(rows):
    """The integrator table in Markdown."""
    lines = ["| integrator | tol | steps | contact solves | iterations | padded products "
             "| history error (at s/s*) | face error at 3 s* | wall (s) |",
             "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['scheme']} | {r['tol']:.2g} | {r['steps']} | {r['solves']} | "
                     f"{r['iterations']} | {r['products']} | {r['history_error']:.1e} "
                     f"({r['worst_distance']:g}) | {r['face_error']:.1e} | {r['wall']:.1f} |")
    return "\n".join(lines)


def write_h5(path, groups, meta):
    """Write the tables (a group per row) and the run's metadata."""
    with atomic_h5(path, format="runin.bench_runin", version=1, force=True) as f:
        f.attrs["wall_units"] = "s"
        for k, v in meta.items():
            f.attrs[k] = v
        for name, rows in groups.items():
            g = f.create_group(name)
            for i, row in enumerate(rows):
                r = g.create_group(f"{i:03d}")
                for k, v in row.items():
                    r.attrs[k] = v


def main(argv=None):
    """Command line of the benchmark (see the module docstring).

    Parameters
    ----------
    argv : list of str, optional
        Arguments (default: ``sys.argv[1:]``).

    Returns
    -------
    dict
        The rows of the tables that were run, by table name.
    """
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--table", action="store_true", help="work per solve against n")
    parser.add_argument("--schemes", action="store_true", help="integrators at equal error")
    parser.add_argument("--interfaces", action="store_true",
                        help="a scene across interfaces against n")
    parser.add_argument("--interfaces-scene", type=pathlib.Path, default=INTERFACES_SCENE)
    parser.add_argument("--reference-tol", type=float,
                        help="tol of the reference runs of --interfaces (default: none)")
    parser.add_argument("--scheme-names", nargs="+",
                        help="integrators of --schemes (default: every implicit one)")
    parser.add_argument("--levers", action="store_true",
                        help="stopping rules of the stage solves side by side")
    parser.add_argument("--rules", nargs="+", choices=sorted(LEVERS), metavar="RULE",
                        help="stage rules of --levers, the first the reference of 'change' "
                             "(default: all of LEVERS)")
    parser.add_argument("--shipped", action="store_true",
                        help="--rules (at least two) on every shipped run-in scene")
    parser.add_argument("--memory", action="store_true",
                        help="peak memory of the command line against n")
    parser.add_argument("--periodic", action="store_true",
                        help="the scene beside its map on a periodic cell, against n")
    parser.add_argument("--checkpoint-interval", type=float,
                        help="checkpoint interval of --memory, s (default: the scene's)")
    parser.add_argument("--scene", type=pathlib.Path, default=SCENE)
    parser.add_argument("--sizes", type=int, nargs="+", default=list(SIZES))
    parser.add_argument("--tol", type=float,
                        help="tol of --table and --interfaces (default: the scene's)")
    parser.add_argument("--n", type=int, default=SCHEME_N, help="grid of --schemes")
    parser.add_argument("--ratio", type=float, help="k_2/k_1 of --schemes (default: the scene's)")
    parser.add_argument("--quick", action="store_true", help="smoke test: short ladders")
    parser.add_argument("--out", type=pathlib.Path, default=pathlib.Path("bench_runin.h5"))
    args = parser.parse_args(argv)
    if not (args.table or args.schemes or args.memory or args.interfaces or args.levers
            or args.shipped or args.periodic):
        parser.error("choose --table, --schemes, --interfaces, --levers, --shipped, "
                     "--periodic and/or --memory")
    if args.shipped and not (args.rules and len(args.rules) > 1):
        parser.error("--shipped compares the --rules given, at least two")
    logging.basicConfig(level=logging.INFO, format="%(message)s", stream=sys.stderr)
    groups = {}
    if args.table:
        groups["grids"] = grid_table(args.scene, args.sizes, args.tol)
        print(markdown_table(groups["grids"]))
    if args.interfaces:
        groups["interfaces"] = interface_table(args.interfaces_scene, args.sizes, args.tol,
                                               args.reference_tol)
        print(markdown_interfaces(groups["interfaces"]))
    if args.levers:
        names = args.rules or (list(LEVERS)[:2] if args.quick else list(LEVERS))
        levers = {k: LEVERS[k] for k in names}
        reference = 1e-4 if args.quick else LEVER_REFERENCE_TOL
        groups["levers"] = lever_table(lever_cases(args.scene, args.sizes), levers,
                                       lambda tol: reference)
        print(markdown_levers(groups["levers"]))
    if args.shipped:
        groups["shipped"] = lever_table(shipped_cases(), {k: LEVERS[k] for k in args.rules},
                                        lambda tol: SHIPPED_REFERENCE * tol)
        print(markdown_levers(groups["shipped"]))
    if args.periodic:
        groups["periodic"] = periodic_table(args.scene, args.sizes, args.tol)
        print(markdown_periodic(groups["periodic"]))
    if args.memory:
        groups["memory"] = memory_table(args.scene, args.sizes, args.checkpoint_interval)
        print(markdown_memory(groups["memory"]))
    if args.schemes:
        implicit = [name for name, s in sorted(SCHEMES.items()) if not s.explicit
                    and (args.scheme_names is None or name in args.scheme_names)]
        ladders = {name: QUICK_LADDER if args.quick else LADDERS.get(name, (1e-3, 1e-4))
                   for name in implicit}
        groups["schemes"] = scheme_table(args.scene, args.n, args.ratio, ladders,
                                         QUICK_REFERENCE if args.quick else REFERENCE)
        print(markdown_schemes(groups["schemes"]))
    meta = dict(machine=platform.processor() or platform.machine(),
                python=platform.python_version(), numpy=np.__version__,
                scene=str(args.scene), command=" ".join(sys.argv))
    write_h5(args.out, groups, meta)
    return groups


if __name__ == "__main__":
    main()
