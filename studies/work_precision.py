"""Work-precision of the run-in integrators against a fixed-step explicit Euler loop.

What it reproduces
    docs/benchmarks.md, "Run-in stepping": for a Voronoi biphasic punch with
    ``rho_2 = 0.3`` and ``k_2/k_1 = 1e3`` (400 seeds, the paper's epoxy-cylinder
    load), the error of the run-in history (rms slope at fixed sliding
    distances) and of the face at the end of the history, against the wall
    time and the number of contact solves, for every implicit integrator
    (:mod:`transient.stepping`) at several tolerances and for the baseline
    users write today: a fixed-step explicit Euler loop around a contact
    solve, at its largest stable step.  Also: the direct jump to the steady
    state (implicit Euler with ``ds = 1e8 s*``) against the closed-form face.

    Work is counted in contact solves and in *contact-solve equivalents*:
    wall time divided by the wall time of one cold contact solve of the flat
    face on the same grid (median of three).

    The baseline needs ``distance / ds_max`` steps, ``ds_max ~ 1.16 h /
    (k_max E*)``: at n = 256 that is ~3e5 steps, beyond this machine.  It is
    therefore run over a window (``BASELINE_WINDOW`` s*) at its stable step,
    where its error and its wall time per step are measured; its cost over
    the whole history is the exact step count times the measured time per
    step (stored with ``extrapolated = True``).  ``--full-baseline`` runs it
    to the end instead (use at n <= 64), which also checks the extrapolation.

The spatial axis (``--spatial``)
    The same scene's history error against a *grid-converged* reference
    rather than a same-grid one, for the grid ``n`` and the tolerance
    ``tol`` together: every implicit integrator of the registry
    (:data:`transient.stepping.SCHEMES`) at ``tol = 1e-2, 1e-3, 1e-4`` on
    n = 64, 128, 256.  The reference is ``sdirk2`` at ``tol = 1e-5`` on
    n = 128, 256, 512, extrapolated at each distance with the observed
    order (``studies/runin_convergence.py``'s rule), or the n = 512 value
    where the differences do not shrink; its uncertainty (the size of the
    extrapolation, or ``|S_512 - S_256|``) is stored beside it.  Also the
    run's own error bars: the per-step ``rms_slope_error`` and the companion
    run on ``n/2`` (:mod:`transient.spatial_error`) for ``sdirk2``.

How to run
    python studies/work_precision.py                    # n = 256, ~10 min on 2 cores
    python studies/work_precision.py --n 64 --full-baseline   # ~11 min (10 the baseline)
    python studies/work_precision.py --spatial          # ~40 min (n = 512 reference)
    python studies/work_precision.py --quick --out OUT  # smoke test, n = 40, ~20 s
    python studies/work_precision.py --plot-only [--n N | --spatial] [--out OUT]

Writes ``OUT/work_precision_n{n}.h5`` (``OUT/work_precision_spatial.h5``) and
then draws ``OUT/work_precision_n{n}.png`` (``..._spatial.png``) from that
file.  Default OUT: ``./runin-studies-out``; ``--docs-figures`` draws the
figure into docs/figures instead (its committed copy), as every study does
(:func:`study_io.add_output_arguments`).  This script keeps its own command line rather than
``study_io.run_study`` because it takes ``--n``, ``--full-baseline`` and
``--spatial``.
"""

from __future__ import annotations

import argparse
import datetime
import logging
import math
import os
import platform
import sys
import time

import numpy as np
import study_io

from steady.outline import Circle
from steady.phases import Voronoi
from steady.safe_files import atomic_h5
from steady.scene import Scene
from steady.wear import PowerLaw
from transient.comparison import compare_with_steady
from transient.contact import solve_contact
from transient.history import FaceEstimator
from transient.initial_face import flat
from transient.options import RunOptions
from transient.runin import run_in
from transient.scene import wear_problem_of
from transient.solver import StageSolver
from transient.spatial_error import spatial_error
from transient.stepping import SCHEMES

# -- parameters ----------------------------------------------------------------
RADIUS = 4e-3            # m, the paper's epoxy cylinder (Fig. 6)
FORCE = 10.0             # N
E_STAR = 1.3e6           # Pa
K1 = 1e-13               # 1/Pa, matrix (phase 0)
RATIO = 1e3              # k_2 / k_1
FILL = (0.7, 0.3)        # rho_1, rho_2
SEEDS = 400
SEED = 2029
N = 256
CONTACT_RTOL = 1e-10     # every contact solve, baseline included
# Sliding distances (units of s* = a / (k_1 E*)) where the history is compared;
# multiples of 1e-4 so that the baseline's fixed steps land on them.
DISTANCES = (1e-4, 1e-3, 1e-2, 0.1, 0.3, 1.0, 3.0)
# Every implicit integrator of the registry, at these tolerances (local error / f*);
# first-order schemes stop at 1e-4 (their history error only falls like tol^(1/2)).
TOLERANCES = (1e-2, 1e-3, 1e-4, 1e-5)
RUNS = {name: TOLERANCES if scheme.order > 1 else TOLERANCES[:-1]
        for name, scheme in sorted(SCHEMES.items()) if not scheme.explicit}
REFERENCE = ("sdirk2", 1e-6)
# The spatial axis: grids and tolerances of the runs, and the reference.
SPATIAL_GRIDS = (64, 128, 256)
SPATIAL_TOLERANCES = (1e-2, 1e-3, 1e-4)
SPATIAL_REFERENCE = ("sdirk2", 1e-5, (128, 256, 512))
# Distances where the reference's own uncertainty is below this (relative) enter
# the error of a run; elsewhere the reference is not grid-converged itself.
RESOLVED = 2e-3
SPATIAL_VERSION = 1
BASELINE_WINDOW = 1e-3   # s*, baseline measured over [0, window] unless --full-baseline
FORMAT_VERSION = 1

logger = logging.getLogger("work_precision")


def scene(n=N):
    """The study's scene (a Voronoi punch on the epoxy cylinder's load)."""
    return Scene(outline=Circle(RADIUS), normal_force=FORCE, E_star=E_STAR, n=n,
                 wear=PowerLaw((K1, K1 * RATIO)), geometry=Voronoi(SEEDS, FILL, SEED))


def build(n):
    """The study's wear problem on the ``n x n`` grid."""
    return wear_problem_of(scene(n), n=n)


def unit_cost(hs, face):
    """Median wall time of a cold contact solve of the flat face, s."""
    times = []
    for _ in range(3):
        t = time.perf_counter()
        solve_contact(hs, face, np.zeros(face.shape), FORCE, rtol=CONTACT_RTOL)
        times.append(time.perf_counter() - t)
    return float(np.median(times))


def run_scheme(n, scheme, tol, distances, *, companion=False):
    """One adaptive run of a registered integrator up to the last compared distance.

    Parameters
    ----------
    n : int
        Grid size.
    scheme : str
        A key of :data:`transient.stepping.SCHEMES`.
    tol : float
        Local error per step, shape rms / ``f*``.
    distances : sequence of float
        Compared sliding distances, units of ``s*`` (the run lands on them).
    companion : bool, optional
        Also run the companion on a coarser grid (:mod:`transient.spatial_error`).

    Returns
    -------
    dict
        ``wall`` (s), ``solves``, ``iterations``, ``steps``, ``rejected``,
        ``slopes`` (rms slope at ``distances``), ``errors`` (its per-step
        error bar there), ``face`` (height at the last distance, m, NaN off
        the face), ``s_star`` (m) and ``depth_scale`` (m); with
        ``companion``, ``spatial`` (the companion's error bar at
        ``distances``), ``companion_wall`` (s) and ``companion_grid``.
    """
    problem = build(n)
    # No jump: the history up to the last distance is what is measured.
    options = RunOptions(scheme=scheme, tol=tol, snapshots_s_star=distances,
                         distance_limit=distances[-1] * problem.distance_scale, jump_spread=0.0,
                         spread_tol=1e-300, shape_tol=1e-300, max_steps=10 ** 6)
    t = time.perf_counter()
    result = run_in(problem, np.zeros((n, n)), options)
    wall = time.perf_counter() - t
    s = result.history["distance"]
    at = []
    for d in distances:
        i = int(np.argmin(np.abs(s - d * result.distance_scale)))
        assert abs(s[i] / (d * result.distance_scale) - 1) < 1e-9, (s[i], d)
        at.append(i)
    face_end = result.snapshot_recession[-1]
    out = dict(wall=wall, solves=result.solves, iterations=result.iterations,
               steps=result.steps, rejected=result.rejected,
               slopes=result.history["rms_slope"][at], errors=result.history["rms_slope_error"][at],
               face=face_end, s_star=result.distance_scale, depth_scale=result.depth_scale)
    if companion:
        t = time.perf_counter()
        try:
            extra = spatial_error(scene(n), flat, options, result)
        except ValueError as err:  # no admissible coarser grid
            logger.info("no companion run at n = %d: %s", n, err)
            return out
        out.update(spatial=extra.error[at], companion_wall=time.perf_counter() - t,
                   companion_grid=min(extra.grids))
    return out


def run_baseline(n, distances, end):
    """The loop users write: fixed-step explicit Euler around a contact solve."""
    problem = build(n)
    hs, face, wear = problem.halfspace, problem.face_mask, problem.wear_field
    s_star = problem.distance_scale
    p = solve_contact(hs, face, np.zeros((n, n)), FORCE, rtol=CONTACT_RTOL).pressure
    limit = StageSolver(problem).stable_step(p) / s_star
    per = math.ceil(1e-4 / limit)          # steps per 1e-4 s*, so steps land on distances
    ds = 1e-4 / per * s_star
    w = np.zeros((n, n))
    estimator = FaceEstimator(problem, w)
    slopes = np.full(len(distances), np.nan)
    targets = [round(d / 1e-4) * per for d in distances]
    steps_end = round(end / 1e-4) * per
    t = time.perf_counter()
    res = None
    for step in range(1, steps_end + 1):
        w = w + ds * wear * p
        res = solve_contact(hs, face, w, FORCE, x0=p, rtol=CONTACT_RTOL)
        p = res.pressure
        if step in targets:
            slopes[targets.index(step)] = estimator.figures(step * ds, w, p,
                                                            res.approach)["rms_slope"]
    wall = time.perf_counter() - t
    steps_full = round(distances[-1] / 1e-4) * per
    return dict(ds=ds / s_star, limit=limit, steps=steps_end, wall=wall,
                per_step=wall / steps_end, steps_full=steps_full,
                wall_full=wall / steps_end * steps_full,
                extrapolated=steps_end < steps_full, slopes=slopes,
                face=np.where(face, w, np.nan) if steps_end == steps_full else None)


def steady_jump(n):
    """Implicit Euler with ds = 1e8 s* from the flat face, against eq. 9."""
    problem = build(n)
    t = time.perf_counter()
    result = run_in(problem, np.zeros((n, n)), RunOptions(jump_spread=math.inf))
    wall = time.perf_counter() - t
    cmp = compare_with_steady(result, problem.solve_steady(), problem)
    return dict(wall=wall, solves=result.solves, iterations=result.iterations,
                face_error=cmp.face_error, face_rms_error=cmp.face_rms_error,
                rms_slope_error=cmp.rms_slope_error,
                phase_pressure_error=cmp.phase_pressure_error,
                spread=float(result.history["spread"][-1]), status=result.status)


def shape_error(face, ref):
    """Rms over the face of the difference (best constant removed) / relief of ``ref``."""
    on = np.isfinite(ref)
    d = face[on] - ref[on]
    return float(np.sqrt(np.mean((d - d.mean()) ** 2)) / (ref[on].max() - ref[on].min()))


def compute(n, out, *, full_baseline, runs, distances, reference, window):
    """Run the reference, every scheme and tolerance, the baseline and the jump; write HDF5.

    Parameters
    ----------
    n : int
        Grid size.
    out : pathlib.Path
        Directory of ``work_precision_n{n}.h5``.
    full_baseline : bool
        Run the explicit baseline over the whole history instead of ``window``.
    runs : mapping of str to sequence of float
        Scheme name to the tolerances to run.
    distances : sequence of float
        Compared sliding distances, units of ``s*``.
    reference : (str, float)
        Scheme and tolerance of the reference run.
    window : float
        Distance (``s*``) over which the baseline is measured otherwise.
    """
    problem = build(n)
    unit = unit_cost(problem.halfspace, problem.face_mask)
    logger.info("n=%d: one cold contact solve %.3f s", n, unit)
    logger.info("reference %s tol %g ...", *reference)
    ref = run_scheme(n, reference[0], reference[1], distances)
    logger.info("reference: %d steps, %.1f s", ref["steps"], ref["wall"])
    path = out / f"work_precision_n{n}.h5"
    with atomic_h5(path, format="runin.work_precision", version=FORMAT_VERSION,
                   force=True) as f:
        f.attrs.update(dict(
            n=n, ratio=RATIO,
            fill_factors=FILL, seeds=SEEDS, seed=SEED, radius=RADIUS, normal_force=FORCE,
            E_star=E_STAR, k1=K1, contact_rtol=CONTACT_RTOL,
            unit_cost=unit, unit_cost_units="s (cold contact solve of the flat face)",
            machine=f"{_cpu()}, {os.cpu_count()} cores, {platform.platform()}",
            python=sys.version.split()[0], numpy=np.__version__,
            date=datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
            command=" ".join(["python"] + sys.argv)))
        d = f.create_dataset("distances", data=np.array(distances))
        d.attrs["units"] = "s* = a / (k_1 E*)"
        g = f.create_group("reference")
        g.attrs.update(scheme=reference[0], tol=reference[1], wall=ref["wall"],
                       solves=ref["solves"], steps=ref["steps"])
        g.create_dataset("slopes", data=ref["slopes"]).attrs["units"] = "1"
        g.create_dataset("face", data=ref["face"]).attrs["units"] = "m"
        runs_g = f.create_group("runs")
        for scheme, tols in runs.items():
            for tol in tols:
                r = run_scheme(n, scheme, tol, distances)
                hist_err = float(np.max(np.abs(r["slopes"] / ref["slopes"] - 1)))
                face_err = shape_error(r["face"], ref["face"])
                logger.info("%s tol %g: %d steps, %d solves, %.1f s, history error %.2e, "
                            "face error %.2e", scheme, tol, r["steps"], r["solves"], r["wall"],
                            hist_err, face_err)
                rg = runs_g.create_group(f"{scheme}_tol{tol:g}")
                rg.attrs.update(scheme=scheme, tol=tol, wall=r["wall"], solves=r["solves"],
                                iterations=r["iterations"], steps=r["steps"],
                                rejected=r["rejected"], history_error=hist_err,
                                face_error=face_err, equivalents=r["wall"] / unit)
                rg.create_dataset("slopes", data=r["slopes"]).attrs["units"] = "1"
        end = distances[-1] if full_baseline else window
        b = run_baseline(n, distances, end)
        within = np.isfinite(b["slopes"])
        b_err = float(np.max(np.abs(b["slopes"][within] / ref["slopes"][within] - 1)))
        b_face = shape_error(b["face"], ref["face"]) if b["face"] is not None else np.nan
        logger.info("baseline: ds %.3g s* (limit %.3g), %d steps in %.1f s, full history "
                    "%d steps, %.0f s%s, history error %.2e over %d distances", b["ds"],
                    b["limit"], b["steps"], b["wall"], b["steps_full"], b["wall_full"],
                    " (extrapolated)" if b["extrapolated"] else "", b_err, within.sum())
        bg = f.create_group("baseline")
        bg.attrs.update(ds=b["ds"], stability_limit=b["limit"], steps=b["steps"],
                        wall=b["wall"], per_step=b["per_step"], steps_full=b["steps_full"],
                        solves_full=b["steps_full"] + 1, wall_full=b["wall_full"],
                        equivalents_full=b["wall_full"] / unit,
                        extrapolated=b["extrapolated"], window=end, history_error=b_err,
                        history_error_distances=int(within.sum()), face_error=b_face)
        bg.create_dataset("slopes", data=b["slopes"]).attrs["units"] = "1"
        j = steady_jump(n)
        logger.info("steady jump: %d solves, %.2f s (%.1f equivalents), face error %.2e",
                    j["solves"], j["wall"], j["wall"] / unit, j["face_error"])
        jg = f.create_group("steady_jump")
        jg.attrs.update({k_: v for k_, v in j.items()})
        jg.attrs["equivalents"] = j["wall"] / unit
    return path


def _cpu():
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown CPU"


def plot(path, png):
    """Draw the work-precision figure from the HDF5 file of :func:`compute`."""
    import h5py
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    with h5py.File(path) as f:
        n = int(f.attrs["n"])
        unit = float(f.attrs["unit_cost"])
        distances = f["distances"][()]
        ref = f["reference/slopes"][()]
        runs = {name: dict(g.attrs) for name, g in f["runs"].items()}
        base = dict(f["baseline"].attrs)
        base_slopes = f["baseline/slopes"][()]
        jump = dict(f["steady_jump"].attrs)
        ref_name = f"{f['reference'].attrs['scheme']}, tol {f['reference'].attrs['tol']:g}"
        ratio = float(f.attrs["ratio"])
    fig = Figure(figsize=(16, 5))
    FigureCanvasAgg(fig)
    ax = fig.subplots(1, 3)
    markers = {"implicit_euler": "o-", "bdf2": "s-", "sdirk2": "^-", "explicit_euler": "v-",
               "esdirk3": "D-", "esdirk4": "P-"}
    for scheme in sorted({r["scheme"] for r in runs.values()}):
        rs = sorted((r for r in runs.values() if r["scheme"] == scheme), key=lambda r: r["tol"])
        ax[0].loglog([r["wall"] / unit for r in rs], [r["history_error"] for r in rs],
                     markers.get(scheme, "o-"), label=scheme)
        ax[1].loglog([r["solves"] for r in rs], [r["face_error"] for r in rs],
                     markers.get(scheme, "o-"), label=scheme)
    label = "explicit Euler loop at ds_max" + (" (cost extrapolated)"
                                               if base["extrapolated"] else "")
    ax[0].loglog([base["equivalents_full"]], [max(base["history_error"], 1e-12)], "kX",
                 ms=10, label=label)
    if np.isfinite(base["face_error"]):
        ax[1].loglog([base["solves_full"]], [base["face_error"]], "kX", ms=10, label=label)
    else:
        ax[1].axvline(base["solves_full"], color="k", ls=":", label=label + ": solves")
    ax[0].axhline(1e-3, color="grey", lw=0.8)
    ax[0].set_xlabel("work (contact-solve equivalents = wall time / cold solve)")
    ax[0].set_ylabel("history error: max relative error of rms slope")
    ax[0].set_title(f"n = {n}, k2/k1 = {ratio:g}: run-in history")
    ax[0].legend(fontsize=8, loc="center right")
    ax[1].set_xlabel("contact solves")
    ax[1].set_ylabel(f"face error at s = {distances[-1]:g} s* (rms / relief)")
    ax[1].set_title(f"steady jump: {int(jump['solves'])} solves, "
                    f"{jump['equivalents']:.1f} equiv., face error {jump['face_error']:.1e}")
    ax[1].legend(fontsize=8)
    ax[2].semilogx(distances, ref, "k.-", label=f"reference ({ref_name})")
    ok = np.isfinite(base_slopes)
    ax[2].semilogx(distances[ok], base_slopes[ok], "rx", ms=9, label="explicit Euler loop")
    ax[2].set_xlabel("sliding distance / s*")
    ax[2].set_ylabel("rms slope")
    ax[2].legend(fontsize=8)
    ax[2].set_title("rms slope at the compared distances")
    fig.tight_layout()
    fig.savefig(png, dpi=110)


def spatial_reference(reference, distances):
    """The grid-converged reference history: ``reference = (scheme, tol, grids)``.

    Returns
    -------
    dict
        ``slopes`` (extrapolated rms slope at ``distances``, or the finest
        grid's value where the differences do not shrink), ``uncertainty``
        (the size of the extrapolation, or the last difference), ``order``
        (observed, NaN where none), ``values`` (each grid's, shape
        (grids, distances)), ``wall`` (s, each grid's).
    """
    from runin_convergence import extrapolate

    scheme, tol, grids = reference
    runs = [run_scheme(g, scheme, tol, distances) for g in grids]
    values = np.array([r["slopes"] for r in runs])
    slopes, uncertainty, order = [], [], []
    for j in range(len(distances)):
        p, extrapolated = extrapolate(grids, values[:, j])
        if not np.isfinite(extrapolated):
            extrapolated = values[-1, j]
            uncertainty.append(abs(values[-1, j] - values[-2, j]))
        else:
            uncertainty.append(abs(extrapolated - values[-1, j]))
        slopes.append(extrapolated)
        order.append(p)
    return dict(slopes=np.array(slopes), uncertainty=np.array(uncertainty),
                order=np.array(order), values=values, wall=np.array([r["wall"] for r in runs]))


def compute_spatial(out, *, grids, tolerances, schemes, reference, distances):
    """History error against the grid-converged reference for every (n, tol); write HDF5.

    Parameters
    ----------
    out : pathlib.Path
        Directory of ``work_precision_spatial.h5``.
    grids : sequence of int
        Grids of the runs.
    tolerances : sequence of float
        Tolerances of the runs.
    schemes : sequence of str
        Registered implicit integrators.
    reference : (str, float, tuple of int)
        Scheme, tolerance and grids of the reference (:func:`spatial_reference`).
    distances : sequence of float
        Compared sliding distances, units of ``s*``.
    """
    logger.info("spatial reference %s tol %g on %s ...", *reference)
    ref = spatial_reference(reference, distances)
    logger.info("reference: %s (uncertainty %s, orders %s)", ref["slopes"], ref["uncertainty"],
                ref["order"])
    path = out / "work_precision_spatial.h5"
    with atomic_h5(path, format="runin.work_precision_spatial", version=SPATIAL_VERSION,
                   force=True) as f:
        f.attrs.update(dict(
            ratio=RATIO, fill_factors=FILL, seeds=SEEDS, seed=SEED, radius=RADIUS,
            normal_force=FORCE, E_star=E_STAR, k1=K1, contact_rtol=CONTACT_RTOL,
            machine=f"{_cpu()}, {os.cpu_count()} cores, {platform.platform()}",
            python=sys.version.split()[0], numpy=np.__version__,
            date=datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
            command=" ".join(["python"] + sys.argv)))
        f.create_dataset("distances", data=np.array(distances)).attrs["units"] = \
            "s* = a / (k_1 E*)"
        g = f.create_group("reference")
        g.attrs.update(scheme=reference[0], tol=reference[1], grids=np.array(reference[2]))
        for key, unit in (("slopes", "1"), ("uncertainty", "1"), ("order", "1"),
                          ("values", "1"), ("wall", "s")):
            g.create_dataset(key, data=ref[key]).attrs["units"] = unit
        runs_g = f.create_group("runs")
        for n in grids:
            for scheme in schemes:
                for tol in tolerances:
                    companion = scheme == "sdirk2"
                    r = run_scheme(n, scheme, tol, distances, companion=companion)
                    rel = np.abs(r["slopes"] / ref["slopes"] - 1)
                    resolved = ref["uncertainty"] <= RESOLVED * ref["slopes"]
                    err = float(np.max(rel[resolved])) if resolved.any() else np.nan
                    logger.info("n=%d %s tol %g: %d steps, %.1f s, error %.2e against the "
                                "grid-converged reference (%.2e with the unresolved distances)",
                                n, scheme, tol, r["steps"], r["wall"], err, float(np.max(rel)))
                    rg = runs_g.create_group(f"n{n}_{scheme}_tol{tol:g}")
                    rg.attrs.update(n=n, scheme=scheme, tol=tol, wall=r["wall"],
                                    solves=r["solves"], steps=r["steps"], error=err,
                                    error_all=float(np.max(rel)))
                    rg.create_dataset("slopes", data=r["slopes"]).attrs["units"] = "1"
                    rg.create_dataset("relative_error", data=rel).attrs["units"] = "1"
                    rg.create_dataset("error_bar", data=r["errors"]).attrs["units"] = "1"
                    if "spatial" in r:
                        rg.attrs.update(companion_wall=r["companion_wall"],
                                        companion_grid=r["companion_grid"])
                        rg.create_dataset("spatial_error_bar", data=r["spatial"]).attrs[
                            "units"] = "1"
    return path


def plot_spatial(path, png):
    """Draw the spatial work-precision figure from the HDF5 file of :func:`compute_spatial`."""
    import h5py
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    with h5py.File(path) as f:
        distances = f["distances"][()]
        ref = f["reference/slopes"][()]
        ref_unc = f["reference/uncertainty"][()]
        ref_name = (f"{f['reference'].attrs['scheme']}, tol {f['reference'].attrs['tol']:g}, "
                    f"n = {', '.join(str(g) for g in f['reference'].attrs['grids'])}")
        runs = [dict(g.attrs, **{k: g[k][()] for k in g}) for g in f["runs"].values()]
    resolved = ref_unc <= RESOLVED * ref
    for r in runs:
        r["error"] = float(np.max(r["relative_error"][resolved])) if resolved.any() else np.nan
    fig = Figure(figsize=(15, 5))
    FigureCanvasAgg(fig)
    ax = fig.subplots(1, 3)
    grids = sorted({int(r["n"]) for r in runs})
    markers = ("o", "s", "^", "D", "v", "P")
    schemes = sorted({r["scheme"] for r in runs})
    for i, n in enumerate(grids):
        for j, scheme in enumerate(schemes):
            rs = sorted((r for r in runs if r["n"] == n and r["scheme"] == scheme),
                        key=lambda r: r["tol"])
            ax[0].loglog([r["wall"] for r in rs], [r["error"] for r in rs],
                         markers[j % len(markers)] + "-", color=f"C{i}", ms=5, lw=0.8,
                         label=f"n = {n}, {scheme}")
            for r in rs:
                ax[0].annotate(f"{r['tol']:g}", (r["wall"], r["error"]), fontsize=6,
                               xytext=(3, 2), textcoords="offset points")
    for level in (1e-2, 1e-3):
        ax[0].axhline(level, color="grey", lw=0.8)
    if resolved.any():
        ax[0].axhline(float(np.max((ref_unc / ref)[resolved])), color="k", ls=":", lw=0.8,
                      label="reference uncertainty")
    shown = ", ".join(f"{d:g}" for d in distances[resolved])
    ax[0].set_xlabel("wall time (s), this machine")
    ax[0].set_ylabel(f"max relative error at s/s* = {shown}")
    ax[0].set_title("history error against the grid-converged reference, for (n, tol)\n"
                    "(at the distances where the reference is converged to 0.2 %)", fontsize=10)
    ax[0].legend(fontsize=6, ncol=2)
    for i, n in enumerate(grids):
        r = next((r for r in runs if r["n"] == n and r["scheme"] == "sdirk2"
                  and r["tol"] == min(x["tol"] for x in runs)), None)
        if r is None:
            continue
        ax[1].loglog(distances, r["relative_error"], "o-", color=f"C{i}", ms=4,
                     label=f"n = {n}: actual error")
        ax[1].loglog(distances, r["error_bar"] / r["slopes"], "--", color=f"C{i}", lw=0.9,
                     label="per-step error bar")
        if "spatial_error_bar" in r:
            ax[1].loglog(distances, r["spatial_error_bar"] / r["slopes"], ":", color=f"C{i}",
                         lw=1.2, label=f"companions down to n = {int(r['companion_grid'])}")
    ax[1].loglog(distances, ref_unc / ref, "k-", lw=0.8, label="reference uncertainty")
    ax[1].set_xlabel("sliding distance / s*")
    ax[1].set_ylabel("relative error of the rms slope")
    ax[1].set_title(f"sdirk2 at tol {min(x['tol'] for x in runs):g}: error and error bars",
                    fontsize=10)
    ax[1].legend(fontsize=6, ncol=2)
    ax[2].errorbar(distances, ref, yerr=ref_unc, fmt="k.-", label=f"reference ({ref_name})")
    ax[2].set_xscale("log")
    ax[2].set_xlabel("sliding distance / s*")
    ax[2].set_ylabel("rms slope")
    ax[2].legend(fontsize=7)
    ax[2].set_title("grid-converged reference history", fontsize=10)
    fig.tight_layout()
    fig.savefig(png, dpi=100)


def main(argv=None):
    """Command line of the study (see the module docstring).

    Parameters
    ----------
    argv : list of str, optional
        Arguments (default: ``sys.argv[1:]``); ``--help`` lists them.
    """
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--n", type=int, default=N)
    parser.add_argument("--quick", action="store_true",
                        help="smoke test (n = 40; with --spatial, n = 40 against 40, 80, 160)")
    parser.add_argument("--full-baseline", action="store_true",
                        help="run the explicit baseline over the whole history")
    parser.add_argument("--spatial", action="store_true",
                        help="the spatial axis: (n, tol) against a grid-converged reference")
    parser.add_argument("--plot-only", action="store_true")
    study_io.add_output_arguments(parser)
    args = parser.parse_args(argv)
    if args.quick and args.docs_figures:
        parser.error("--docs-figures redraws the committed figures from full runs; "
                     "not with --quick")
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(message)s")
    args.out.mkdir(parents=True, exist_ok=True)
    figures = study_io.DOCS_FIGURES if args.docs_figures else args.out
    implicit = sorted(RUNS)
    if args.spatial:
        path = args.out / "work_precision_spatial.h5"
        if not args.plot_only:
            if args.quick:
                compute_spatial(args.out, grids=(40,), tolerances=(1e-2,), schemes=implicit,
                                reference=("sdirk2", 1e-2, (40, 80, 160)),
                                distances=(1e-3, 1e-2))
            else:
                compute_spatial(args.out, grids=SPATIAL_GRIDS, tolerances=SPATIAL_TOLERANCES,
                                schemes=implicit, reference=SPATIAL_REFERENCE,
                                distances=DISTANCES)
        png = figures / f"{path.stem}.png"
        plot_spatial(path, png)
        print(f"wrote {path} and {png}")
        return
    n = 40 if args.quick else args.n
    path = args.out / f"work_precision_n{n}.h5"
    if not args.plot_only:
        if args.quick:
            compute(n, args.out, full_baseline=True, runs={name: (1e-2,) for name in implicit},
                    distances=(1e-4, 1e-3, 1e-2), reference=("sdirk2", 1e-4), window=1e-2)
        else:
            compute(n, args.out, full_baseline=args.full_baseline, runs=RUNS,
                    distances=DISTANCES, reference=REFERENCE, window=BASELINE_WINDOW)
    png = figures / f"{path.stem}.png"
    plot(path, png)
    print(f"wrote {path} and {png}")


if __name__ == "__main__":
    main()
