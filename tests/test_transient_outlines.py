"""The run-in on faces other than the disk: rectangles, annuli, ellipses (``steady.outline``).

Physics first: the flat rectangle's contact pressure (load, symmetry, the
corner's singularity stronger than an edge's and than the disk rim's), the
run-in of two-phase rectangles and an annulus reaching the closed-form
steady face, load conservation all along; then the plumbing: the problem's
scales and reference slope, initial faces, run files (outline group, old
files), figures, the command line and bad input.

Measured values behind the tolerances (``python -m pytest`` prints nothing
of them; they were measured with the same calls as the tests):

- flat punch, ``solve_contact`` at ``rtol = 1e-10``: ``sum p h^2 = F`` to
  0 .. 3e-16 relative (n = 32 .. 128); mirror asymmetry of the pressure
  1e-12 of the peak at n = 48, 2.5e-10 at n = 128 (the solver's
  tolerance, not the geometry), bound 1e-9.  Pressures in units of the
  pixel mean pressure, 1:2 rectangle, n = 48: corner 5.71, long side's
  middle 2.30, short side's middle 2.67, centre 0.51; the disk of the same
  pixel size, largest rim pixel 4.55.  Growth under refinement, n = 48 ->
  96: corner ``h^-0.692``, edges' middles ``h^-0.485`` and ``h^-0.483``
  (the inverse square root), disk rim ``h^-0.468`` (0.463 .. 0.548 over
  n = 32 .. 128: the staircase).
- run-in from flat to steady, 1:2 rectangle (Voronoi, k1/k0 = 10; rods,
  1.7) and 1:2 annulus (Voronoi), n = 48 and 64: face minus steady face
  with the best constant removed 0.93e-8 .. 1.3e-8 of the steady relief
  (the final jump's ``s* / ds = 1e-8``), with the best plane removed the
  same to 5 %, the plane's slope below 2e-10; phase pressures and the load
  to 7e-16; the history's last rms slope against the steady module's
  corrected value on the twice finer grid: 0.08 .. 0.39 of the sum of the
  two error bars.
"""

import dataclasses
import math
import pathlib
import warnings

import h5py
import numpy as np
import pytest
from conftest import E_STAR, FORCE, K1, RADIUS
from conftest import problem as face_problem

from steady.halfspace import HalfSpace
from steady.normalisation import reference_slope
from steady.outline import Annulus, Circle, Ellipse, MaskOutline, Rectangle
from steady.phases import Homogeneous, Rods, Voronoi
from steady.relief import PlaneFit
from steady.rms_slope import estimate_rms_slope
from steady.scene import load_scene
from steady.solution import solve
from transient import initial_face
from transient.comparison import compare_with_steady
from transient.contact import solve_contact
from transient.output import read_run, write_run
from transient.problem import WearProblem
from transient.result import HISTORY_UNITS
from transient.runin import RunOptions, run_in
from transient.scene import wear_problem_of

ROOT = pathlib.Path(__file__).resolve().parents[1]
FAST = RunOptions(tol=1e-3, snapshots_s_star=(0.01, 0.1, 1.0))

#: A tread block of aspect 1:2 (x: 4 mm, y: 8 mm), L = 4 mm like the epoxy disk.
BLOCK = Rectangle(4e-3, 8e-3)
#: A seal ring of aspect 1:2 (inner radius half the outer one).
RING = Annulus(2e-3, 4e-3)
#: 64 seeds, 30 % of phase 1 in the bounding box: n >= 23 on the block.
VORONOI = Voronoi(64, (0.7, 0.3), 2029)
#: Three rods of radius 1 mm along the block's long axis.
BLOCK_RODS = Rods(((0.0, 0.0), (0.0, 2.2e-3), (0.0, -2.2e-3)), (1e-3,) * 3)


def problem_on(outline, geometry, ratios, n, **options):
    """The wear problem of a geometry on an outline's grid ``n``."""
    return WearProblem(face_problem(geometry, [K1 * r for r in ratios], n=n, outline=outline),
                       **options)


def flat_contact(outline, n):
    grid = outline.grid(n)
    hs = HalfSpace(grid.shape, grid.h, E_STAR)
    res = solve_contact(hs, grid.mask, np.zeros(grid.shape), FORCE, rtol=1e-10)
    assert res.success, res.message
    pbar = FORCE / (grid.mask.sum() * grid.h ** 2)
    return grid, res.pressure, pbar


def edge_peaks(pressure, pbar):
    """Corner, long side's middle (x = -Lx) and short side's middle (y = -Ly), in pbar."""
    nx, ny = pressure.shape
    corner = pressure[0, 0]
    long_side = 0.5 * (pressure[0, ny // 2 - 1] + pressure[0, ny // 2])
    short_side = 0.5 * (pressure[nx // 2 - 1, 0] + pressure[nx // 2, 0])
    centre = pressure[nx // 2 - 1:nx // 2 + 1, ny // 2 - 1:ny // 2 + 1].mean()
    return corner / pbar, long_side / pbar, short_side / pbar, centre / pbar


# -- (a) the flat rectangle under a rigid punch --------------------------------------------

def test_flat_rectangle_pressure_is_balanced_symmetric_and_peaks_at_the_corners():
    grid, p, pbar = flat_contact(BLOCK, 48)
    assert grid.shape == (24, 48), grid.shape
    load = float(np.sum(p) * grid.h ** 2)
    assert load == pytest.approx(FORCE, rel=1e-12), f"load {load!r} N, not {FORCE} N"
    assert np.all(p[grid.mask] > 0), "a flat punch is in full contact"
    for name, mirrored in (("x -> -x", p[::-1, :]), ("y -> -y", p[:, ::-1])):
        asym = float(np.max(np.abs(p - mirrored)) / p.max())
        assert asym < 1e-9, f"pressure not symmetric under {name}: {asym:.2e} of the peak"
    corner, long_side, short_side, centre = edge_peaks(p, pbar)
    peak = np.unravel_index(np.argmax(p), p.shape)
    assert peak in ((0, 0), (0, 47), (23, 0), (23, 47)), f"the peak is at {peak}, not a corner"
    assert corner > 1.5 * max(long_side, short_side), \
        f"corner {corner:.3f} pbar not well above the edges' middles {long_side:.3f}, " \
        f"{short_side:.3f}"
    assert min(long_side, short_side) > 3 * centre, \
        f"edges' middles {long_side:.3f}, {short_side:.3f} pbar not well above the centre " \
        f"{centre:.3f}"
    # Away from the edges the flat punch's pressure is below the mean (the
    # disk's centre: pbar / 2).
    assert 0.4 < centre < 0.6, f"centre {centre:.3f} pbar"


def test_flat_rectangle_corner_is_stronger_than_the_disk_rim():
    """At equal pixel size, and in how fast it grows as the grid is refined."""
    peaks = {}
    for n in (48, 96):
        _, p, pbar = flat_contact(BLOCK, n)
        _, pd, pbar_d = flat_contact(Circle(RADIUS), n)  # the same L and h
        peaks[n] = (*edge_peaks(p, pbar), float(pd.max() / pbar_d))
    corner, long_side, short_side, _, disk = peaks[48]
    assert corner > 1.2 * disk, f"corner {corner:.3f} pbar, disk rim {disk:.3f} pbar (n = 48)"

    def growth(i):
        return math.log(peaks[96][i] / peaks[48][i]) / math.log(2.0)

    g_corner, g_long, g_short, g_disk = growth(0), growth(1), growth(2), growth(4)
    for name, g in (("long side", g_long), ("short side", g_short)):
        assert abs(g - 0.5) < 0.05, f"{name}'s middle grows as h^-{g:.3f}, not the edge's h^-1/2"
    assert g_corner > 0.6, f"corner grows as h^-{g_corner:.3f}"
    assert g_corner > g_disk + 0.15, \
        f"corner h^-{g_corner:.3f} not a stronger singularity than the disk rim's h^-{g_disk:.3f}"


@pytest.mark.parametrize("shifted", [False, True])
def test_every_preconditioner_solves_the_rectangle_alike(shifted):
    """A tilted block in partial contact (91 % of the face), and a two-level shift.

    Measured at rtol = 1e-12: the preconditioners' pressures agree to
    1.4e-11 of the peak, the load to 2e-16.
    """
    grid = BLOCK.grid(48)
    hs = HalfSpace(grid.shape, grid.h, E_STAR)
    height = initial_face.tilted(grid, angle=0.2, azimuth=1.0)
    shift = None
    if shifted:
        shift = np.where(VORONOI.labels(grid) == 1, 10.0, 1.0) * 3.0 * hs.self_influence
    names = ["fourier", "fourier-padded", "jacobi", "none"]
    pressures = {}
    for name in names:
        res = solve_contact(hs, grid.mask, height, FORCE, shift=shift, rtol=1e-12,
                            preconditioner=name)
        assert res.success, f"{name}: {res.message}"
        assert float(np.sum(res.pressure) * grid.h ** 2) == pytest.approx(FORCE, rel=1e-12)
        pressures[name] = res.pressure
    reference = pressures["fourier"]
    if not shifted:
        assert 0.8 < np.mean(reference[grid.mask] > 0) < 0.95, "not in partial contact"
    for name, p in pressures.items():
        gap = float(np.max(np.abs(p - reference)) / reference.max())
        assert gap < 1e-9, f"{name} differs from fourier by {gap:.1e} of the peak"


# -- (b), (c) run-ins reaching the steady face -------------------------------------------

def run_to_steady(outline, geometry, ratios, n, options=FAST):
    problem = problem_on(outline, geometry, ratios, n)
    result = run_in(problem, initial_face.flat(problem.grid), options)
    assert result.status == "steady", result.message
    steady = solve(face_problem(geometry, problem.wear.coefficients, n=n, outline=outline))
    return problem, result, steady


def plane_residual(result, steady, problem):
    """Max of (run face - steady face) about its least-squares plane over the face, / relief."""
    mask = problem.face_mask
    diff = np.where(mask, result.face - steady.face, 0.0)
    residual = PlaneFit(mask, problem.halfspace.h).residual(diff)
    return float(np.max(np.abs(residual)) / np.ptp(steady.face[mask]))


@pytest.mark.parametrize("n", [48, 64])
@pytest.mark.parametrize("case", ["voronoi", "rods"])
def test_two_phase_rectangle_runs_in_to_the_steady_face(case, n):
    geometry, ratios = {"voronoi": (VORONOI, (1.0, 10.0)), "rods": (BLOCK_RODS, (1.0, 1.7))}[case]
    problem, result, steady = run_to_steady(BLOCK, geometry, ratios, n)
    assert result.recession.shape == (n // 2, n), result.recession.shape
    cmp = compare_with_steady(result, steady, problem)
    # Measured 0.93e-8 .. 1.3e-8 (both cases, both grids): the final jump's s*/ds.
    assert cmp.face_error < 1e-6, f"face error {cmp.face_error:.3g} of the steady relief"
    assert plane_residual(result, steady, problem) < 1e-6, "face off the steady one beyond a plane"
    assert cmp.phase_pressure_error < 1e-12, f"phase pressures {cmp.phase_pressure_error:.3g}"
    for pressure in (*result.snapshot_pressure, result.pressure):
        load = float(np.sum(pressure) * problem.halfspace.h ** 2)
        assert load == pytest.approx(FORCE, rel=1e-12), f"load {load!r} N"
    # The history ends on the steady module's corrected value on the twice
    # finer grid, within the two error bars (measured 0.08 .. 0.39 of them).
    ref = estimate_rms_slope(geometry, problem.wear.coefficients, FORCE, BLOCK, E_STAR, 2 * n)
    end, bar = result.history["rms_slope"][-1], result.history["rms_slope_error"][-1]
    assert abs(end - ref.rms_slope) <= bar + ref.error, \
        f"run ends at {end:.5f} +- {bar:.5f}, steady (n = {2 * n}) {ref.rms_slope:.5f} +- " \
        f"{ref.error:.5f}"
    assert cmp.rms_slope_agrees, cmp.summary()
    for name, values in result.history.items():
        assert np.all(np.isfinite(values[1:])), f"non-finite {name} history"


def test_annulus_runs_in_and_conserves_the_load():
    problem, result, steady = run_to_steady(RING, VORONOI, (1.0, 10.0), 48)
    mask = problem.face_mask
    hole = problem.grid.x[:, None] ** 2 + problem.grid.y[None, :] ** 2 < RING.inner_radius ** 2
    assert hole.sum() > 100 and not mask[hole].any(), "the ring's hole is not off the face"
    h = problem.halfspace.h
    for pressure in (*result.snapshot_pressure, result.pressure):
        assert not np.any(pressure[~mask]), "pressure off the ring"
        load = float(np.sum(pressure) * h ** 2)
        assert load == pytest.approx(FORCE, rel=1e-12), f"load {load!r} N"
    assert np.all(np.isnan(result.worn_depth[hole])), "worn depth defined in the hole"
    cmp = compare_with_steady(result, steady, problem)
    assert cmp.face_error < 1e-6 and cmp.phase_pressure_error < 1e-12, cmp.summary()
    assert cmp.rms_slope_agrees, cmp.summary()


def test_homogeneous_annulus_wears_the_volume_k_f_s():
    problem = problem_on(RING, Homogeneous(), (1.0,), 48)
    result = run_in(problem, initial_face.flat(problem.grid), RunOptions(tol=1e-3))
    assert result.status == "steady", result.message
    h = result.history
    assert h["worn_volume"][-1] == pytest.approx(K1 * FORCE * result.distance, rel=1e-9), \
        "worn volume breaks the balance k F s"
    # Measured 3.57 pbar on the rim pixels at s = 0 (n = 48).
    assert h["peak_pressure"][0] > 3 * result.pixel_mean_pressure, "no rim concentration at s = 0"
    assert result.pressure.max() == pytest.approx(result.pixel_mean_pressure, rel=1e-6), \
        "the steady pressure of a homogeneous ring is uniform"
    # The history ends with the dynamics, the spread below jump_spread (1e-3).
    assert h["peak_pressure"][-1] == pytest.approx(result.pixel_mean_pressure,
                                                   rel=RunOptions().jump_spread), \
        "the pressure at the end of the dynamics is not near uniform"
    # Normalised by the homogeneous ring's own rms slope, the steady face is 1
    # (measured 1.0008, error bar 0.022).
    end, bar = h["normalised_rms_slope"][-1], h["rms_slope_error"][-1] / result.reference_slope
    assert abs(end - 1.0) <= bar, f"homogeneous ring ends at {end:.4f} +- {bar:.4f} grad_f0"


def test_mask_face_runs_in_to_its_steady_face():
    """An L-shaped face given as pixels (a chipped block); measured face error 1e-8."""
    mask = np.ones((6, 12), dtype=bool)
    mask[:3, :4] = False
    outline = MaskOutline(mask, 1e-3, source="L-shaped test mask")
    problem, result, steady = run_to_steady(outline, VORONOI, (1.0, 10.0), 48)
    assert problem.shape == (24, 48) and problem.face_mask.sum() == 60 * 16
    cmp = compare_with_steady(result, steady, problem)
    assert cmp.face_error < 1e-6 and cmp.phase_pressure_error < 1e-12, cmp.summary()
    load = float(np.sum(result.pressure) * problem.halfspace.h ** 2)
    assert load == pytest.approx(FORCE, rel=1e-12), f"load {load!r} N"
    assert "mask face: corrected rms-slope estimator" in result.reference_slope_source


SHIPPED = ("tread_block", "annular_seal", "elliptic_pad", "aggregate_chip")


@pytest.mark.slow
@pytest.mark.parametrize("name", SHIPPED)
def test_shipped_outline_scenes_run_in_to_the_steady_scene(name):
    """The steady scenes of every outline, run in from flat on their own grids.

    Measured (tol = 1e-3, about 2.5 s each): face error 1.9e-8 .. 3.7e-8 of
    the relief, phase pressures to 3e-16, the last rms slope within 0.24 %
    of :func:`steady.solution.solve_scene`'s and within the error bars.
    """
    from steady.solution import solve_scene
    from steady.validity import ValidityWarning
    from transient.scene import load_transient_scene

    scene, _, initial = load_transient_scene(ROOT / "steady" / "examples" / f"{name}.toml")
    problem = wear_problem_of(scene)
    result = run_in(problem, initial.recession(problem.grid), RunOptions(tol=1e-4))
    assert result.status == "steady", result.message
    with warnings.catch_warnings():
        # The aggregate chip's face lies beyond the small slopes (0.445 rad): the comparison
        # is of the linear model with itself all the same.
        warnings.simplefilter("ignore", ValidityWarning)
        steady = solve_scene(scene)
    cmp = compare_with_steady(result, steady, problem)
    assert cmp.face_error < 1e-6 and cmp.phase_pressure_error < 1e-12, cmp.summary()
    assert cmp.rms_slope_agrees and abs(cmp.rms_slope_error) < 5e-3, cmp.summary()


@pytest.mark.slow
@pytest.mark.parametrize("outline", [BLOCK, RING], ids=["rectangle", "annulus"])
def test_history_of_other_outlines_converges_with_the_grid(outline):
    """Homogeneous faces from flat on n = 48, 96, 192: the history within its error bars.

    The rim-layer correction of :mod:`transient.history` was fitted on the
    disk.  Measured at s = 1e-4 .. 3 s*: consecutive grids differ by at most
    0.014 grad_f0 (rectangle; annulus 0.009, disk 0.010), at most 0.76 of
    the sum of their error bars (annulus 0.49, disk 0.45); n = 48 and 192
    by at most 0.024 grad_f0.  (48 against 192 late in the run, where the
    per-step bars are a few 1e-4, differs by up to 1.3 of them: the grid's
    share of the dynamics that only the companion run measures,
    :mod:`transient.spatial_error`.)
    """
    from transient.spatial_error import _at

    targets = np.array([1e-4, 3e-4, 1e-3, 3e-3, 1e-2, 3e-2, 0.1, 0.3, 1.0, 3.0])
    values = {}
    for n in (48, 96, 192):
        problem = problem_on(outline, Homogeneous(), (1.0,), n)
        result = run_in(problem, initial_face.flat(problem.grid),
                        RunOptions(tol=1e-4, snapshots_s_star=tuple(targets)))
        assert result.status == "steady", result.message
        h, s = result.history, result.history["distance"]
        at = targets * result.distance_scale
        values[n] = (_at(s, h["rms_slope"], at, steady=True) / result.reference_slope,
                     _at(s, h["rms_slope_error"], at, steady=True) / result.reference_slope)
    for a, b in ((48, 96), (96, 192)):
        (va, ea), (vb, eb) = values[a], values[b]
        worst = np.max(np.abs(va - vb) / (ea + eb))
        assert worst <= 1.0, \
            f"n = {a} and {b} differ by {np.abs(va - vb).max():.4f} grad_f0, " \
            f"{worst:.2f} of the error bars"
    spread = np.max(np.abs(values[48][0] - values[192][0]))
    assert spread < 0.04, f"n = 48 and 192 differ by {spread:.4f} grad_f0"


# -- (d) the disk is the disk -----------------------------------------------------------

def test_disk_as_a_radius_or_a_circle_runs_bit_for_bit_the_same():
    geometry = Voronoi(64, (0.7, 0.3), 2029)
    runs = []
    for outline in (RADIUS, Circle(RADIUS)):
        grid = Circle(RADIUS).grid(32)
        problem = WearProblem(face_problem(geometry, [K1, 10 * K1], n=32, outline=outline))
        assert problem.outline.radius == RADIUS and problem.scale == RADIUS \
            and problem.shape == (32, 32)
        assert problem.halfspace.h == 2 * RADIUS / 32, "the disk's pixel size"
        assert np.array_equal(problem.face_mask, grid.mask), "the disk's face"
        runs.append(run_in(problem, initial_face.flat(problem.grid), FAST))
    a, b = runs
    assert a.steps == b.steps and np.array_equal(a.recession, b.recession, equal_nan=True)
    for name in HISTORY_UNITS:
        assert np.array_equal(a.history[name], b.history[name], equal_nan=True), name
    ref = reference_slope(Circle(RADIUS), FORCE, E_STAR)
    assert a.reference_slope == 4 * FORCE / (math.pi * RADIUS ** 2) / (math.pi * E_STAR) \
        == ref.value, "grad_f0 of the disk is eq. 12's"
    assert a.reference_slope_source == ref.source and "eq. 12" in a.reference_slope_source


# -- the problem's scales and reference slope -----------------------------------------------

def test_scales_and_reference_slope_come_from_the_outline():
    problem = problem_on(BLOCK, VORONOI, (1.0, 10.0), 48)
    L = BLOCK.scale
    assert L == 4e-3 and getattr(problem.outline, "radius", None) is None and problem.n == 48
    pbar_pixels = FORCE / (problem.face_mask.sum() * problem.halfspace.h ** 2)
    assert problem.face_mask.all(), "a rectangle of whole pixels covers its grid"
    assert problem.depth_scale == pytest.approx(pbar_pixels * L / E_STAR, rel=1e-15)
    assert problem.distance_scale == pytest.approx(L / (K1 * E_STAR), rel=1e-15)
    ref = reference_slope(BLOCK, FORCE, E_STAR)
    assert problem.reference_slope == ref.value and ref.mean_pressure == FORCE / BLOCK.area
    assert "rectangle" in problem.reference.source, problem.reference.source
    # grad_f0 is the homogeneous rectangle's rms slope (the corrected estimator
    # at n = 64: 1.8e-4 off, error bar 3.9e-4), not the disk's 4 pbar / (pi E*)
    # (1.7 % off for this 1:2 block).
    homogeneous = estimate_rms_slope(Homogeneous(), [K1], FORCE, BLOCK, E_STAR, 64)
    assert abs(homogeneous.rms_slope - ref.value) <= homogeneous.error, \
        f"grad_f0 {ref.value:.6f}, homogeneous block {homogeneous.rms_slope:.6f} +- " \
        f"{homogeneous.error:.1e}"
    assert ref.factor != pytest.approx(4 / math.pi, rel=1e-3), "the block normalised as a disk"


def test_scene_problem_uses_the_scene_outline_and_grid(scene_file):
    path = scene_file(punch={"shape": "rectangle", "width": 0.004, "length": 0.008}, n=48)
    from transient.scene import load_transient_scene

    scene, _, initial = load_transient_scene(path)
    problem = wear_problem_of(scene)
    assert problem.outline == BLOCK and problem.shape == (24, 48) and problem.n == 48
    assert np.array_equal(problem.labels, scene.phase_labels()), "the scene's phase map"
    assert problem.halfspace.h == scene.grid().h
    assert initial.recession(problem.grid).shape == (24, 48)
    assert initial.recession(scene.outline.grid(48)).shape == (24, 48)
    with pytest.raises(ValueError, match=r"n = 12, the minimum is n = 16"):
        wear_problem_of(scene, n=12)


@pytest.mark.parametrize("make, match", [
    (lambda: WearProblem(face_problem(np.zeros((24, 48), int), [K1],
                                      outline=Rectangle(4e-3, 12e-3))),
     r"labels must have shape \(16, 48\) to match the grid of the rectangle face .* "
     r"got \(24, 48\)"),
    # The half-space is the problem's own (its grid's pixel size): a bare one is refused.
    (lambda: WearProblem(HalfSpace((24, 48), 1e-4, E_STAR)),
     "takes a steady.problem.Problem, got HalfSpace"),
    (lambda: WearProblem(face_problem(np.zeros((12, 12), int), [K1],
                                      outline=Annulus(2.5e-3, 4e-3))),
     r"grid too coarse for the annulus face .*: n = 12, the minimum is n = 16"),
    (lambda: WearProblem(face_problem(np.zeros((16, 16), int), [K1], outline="4 mm")),
     "an outline or a radius"),
])
def test_a_problem_off_its_outline_is_refused(make, match):
    with pytest.raises(ValueError, match=match):
        make()


# -- initial faces on other outlines -----------------------------------------------------

def test_tilted_block_touches_at_its_leading_edge():
    grid = BLOCK.grid(48)
    angle = 0.01
    h = initial_face.tilted(grid, angle=angle, azimuth=0.0)
    X = grid.x[:, None] + 0 * grid.y[None, :]
    assert np.allclose(h, math.tan(angle) * (X + BLOCK.width / 2), rtol=0, atol=1e-18), \
        "a plane receding towards +x, zero at the edge x = -width/2"
    # Towards the diagonal: zero at the corner (-Lx, -Ly).
    c, s = math.cos(1.0), math.sin(1.0)
    h = initial_face.initial_recession("tilted", BLOCK.grid(48), angle=angle, azimuth=1.0)
    lx, ly = BLOCK.half_extent
    corner_pixel = math.tan(angle) * ((grid.x[0] + lx) * c + (grid.y[0] + ly) * s)
    assert h[0, 0] == pytest.approx(corner_pixel, rel=1e-12) and h.min() == h[0, 0]
    assert RING.support((0.6, 0.8)) == RING.outer_radius
    assert Ellipse(2e-3, 4e-3).support((1.0, 0.0)) == pytest.approx(2e-3)


def test_crowned_block_and_file_faces():
    grid = BLOCK.grid(32)
    reach = math.hypot(2e-3, 4e-3)
    h = initial_face.crowned(grid, sphere_radius=0.05)
    assert h.shape == (16, 32) and h.min() >= 0
    with pytest.raises(ValueError, match=r"sphere_radius must be finite and at least the largest "
                                         r"distance 0.00447214 m of the rectangle face"):
        initial_face.crowned(grid, sphere_radius=0.99 * reach)
    assert initial_face.exact_statistics("crowned", BLOCK, sphere_radius=0.05) is None
    assert initial_face.exact_statistics("tilted", BLOCK, angle=0.01).rms_slope == \
        math.tan(0.01)
    values = np.full((16, 32), 1e-6)
    assert np.array_equal(initial_face.from_array(values, grid), values)
    with pytest.raises(ValueError, match=r"shape \(16, 32\)"):
        initial_face.from_array(np.zeros((32, 32)), BLOCK.grid(32))
    with pytest.raises(ValueError, match=r"n = 4, the minimum is n = 16"):
        initial_face.flat(BLOCK.grid(4))


def test_file_initial_face_of_a_rectangle(tmp_path, scene_file):
    from transient.scene import load_transient_scene

    np.save(tmp_path / "face.npy", np.zeros((24, 48)))
    np.save(tmp_path / "square.npy", np.zeros((48, 48)))
    punch = {"shape": "rectangle", "width": 0.004, "length": 0.008}
    scene, _, initial = load_transient_scene(
        scene_file(punch=punch, n=48, initial_face={"kind": "file", "path": "face.npy"}))
    assert initial.recession(scene.grid()).shape == (24, 48)
    scene, _, initial = load_transient_scene(
        scene_file(punch=punch, n=48, initial_face={"kind": "file", "path": "square.npy"}))
    with pytest.raises(ValueError, match=r"shape \(48, 48\); \(24, 48\) is needed"):
        initial.recession(scene.grid())


# -- run files, resume, figures ----------------------------------------------------------

def test_rectangle_run_file_round_trip_and_resume(tmp_path):
    problem = problem_on(BLOCK, VORONOI, (1.0, 10.0), 32)
    h0 = initial_face.flat(problem.grid)
    stopped = run_in(problem, h0, dataclasses.replace(FAST, max_steps=4))
    assert stopped.status == "stopped", stopped.message
    path = tmp_path / "run.h5"
    write_run(path, stopped, attrs={"radius": None})
    saved, attrs, _ = read_run(path)
    assert saved.outline == BLOCK and saved.shape == (16, 32)
    assert saved.snapshot_recession.shape[1:] == (16, 32)
    assert "radius" not in attrs, "a rectangle has no radius"
    assert attrs["scale"] == 4e-3 and attrs["pixel_size"] == pytest.approx(2 * 4e-3 / 32)
    assert saved.reference_slope_source == problem.reference.source
    assert "rectangle" in attrs["reference_slope_source"]
    with h5py.File(path) as f:
        assert f["outline"].attrs["kind"] == "rectangle"
        assert f["outline/length"][()] == 8e-3 and f["outline/width"][()] == 4e-3
        assert f["outline/length"].attrs["units"] == "m", dict(f["outline/length"].attrs)
    resumed = run_in(problem_on(BLOCK, VORONOI, (1.0, 10.0), 32), None, FAST, resume=saved)
    straight = run_in(problem_on(BLOCK, VORONOI, (1.0, 10.0), 32), h0, FAST)
    assert resumed.status == straight.status == "steady"
    assert resumed.steps == straight.steps
    assert np.array_equal(resumed.recession, straight.recession, equal_nan=True), "resume differs"
    for name in HISTORY_UNITS:
        assert np.array_equal(resumed.history[name], straight.history[name], equal_nan=True), name


def test_run_files_of_disks_keep_radius_and_old_files_read(tmp_path):
    problem = problem_on(Circle(RADIUS), Homogeneous(), (1.0,), 16)
    result = run_in(problem, initial_face.flat(problem.grid), dataclasses.replace(FAST,
                                                                                   max_steps=2))
    path = tmp_path / "disk.h5"
    write_run(path, result)
    back, attrs, _ = read_run(path)
    assert attrs["radius"] == RADIUS and back.outline == Circle(RADIUS)
    # A file written before the outlines: no outline group, no reference
    # error or source, no checksums (read unverified).
    with h5py.File(path, "r+") as f:
        del f["outline"]
        for name in ("reference_slope_error", "scale", "pixel_size"):
            del f[name]
        for name in ("reference_slope_source", "sha256"):
            del f.attrs[name]
    old, _, _ = read_run(path)
    assert old.outline == Circle(RADIUS), "an old disk file reads as the disk of its radius"
    assert "eq. 12" in old.reference_slope_source and old.reference_slope_error == 0.0
    with h5py.File(path, "r+") as f:
        del f["radius"]
    anonymous, attrs, _ = read_run(path)
    assert anonymous.outline is None and math.isnan(anonymous.pixel_size)
    from transient.plotting import run_figure

    fig = run_figure(anonymous, attrs)
    face_axes = fig.axes[3]
    assert face_axes.get_xlabel() == "x (pixels)", "no outline: axes in pixels"


def test_figure_extent_comes_from_the_grid(tmp_path):
    from transient.plotting import extent, plot_run, run_figure

    assert extent((16, 48), Rectangle(4e-3, 12e-3)) == (
        pytest.approx([-2.0, 2.0, -6.0, 6.0]), "mm")
    problem = problem_on(BLOCK, VORONOI, (1.0, 10.0), 32)
    result = run_in(problem, initial_face.flat(problem.grid), RunOptions(tol=1e-2))
    path = tmp_path / "run.h5"
    write_run(path, result)
    result, attrs, _ = read_run(path)
    fig = run_figure(result, attrs)
    image = fig.axes[3].images[0]
    # x along the horizontal axis, y up, as in the steady figures.
    assert list(image.get_extent()) == pytest.approx([-2.0, 2.0, -4.0, 4.0])
    assert fig.axes[3].get_xlabel() == "x (mm)"
    assert plot_run(path, tmp_path / "run.png").stat().st_size > 10000


# -- the command line --------------------------------------------------------------------

def test_command_line_runs_a_rectangle_and_names_its_reference_slope(tmp_path, scene_file):
    from test_transient_cli import cli

    scene = scene_file(punch={"shape": "rectangle", "width": 0.004, "length": 0.008}, n=48,
                       transient={"tol": 1e-3, "snapshots_s_star": (0.1,)})
    out, png = tmp_path / "run.h5", tmp_path / "run.png"
    proc = cli(scene, "-o", out, "--plot", png, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert "face: rectangle face (width 4 mm, length 8 mm), n = 48 (24 x 48 pixels)" \
        in proc.stdout, proc.stdout
    assert "grad_f0 = " in proc.stdout and "Love's closed-form gradient" in proc.stdout, \
        proc.stdout
    with h5py.File(out) as f:
        # Stored (y, x): 48 rows along y, 24 columns along x.
        assert f["phase"].shape == (48, 24) and f["snapshots/recession"].shape == (1, 48, 24)
        assert "radius" not in f and f["outline"].attrs["kind"] == "rectangle"
        assert "Love" in f.attrs["reference_slope_source"]
        assert f["comparison/face_error"][()] < 1e-6
    assert png.stat().st_size > 10000, "no figure"
    # Resuming on another face is refused, naming both.
    other = scene_file(filename="ring.toml", n=48,
                       punch={"shape": "annulus", "inner_radius": 0.002, "outer_radius": 0.004})
    proc = cli(other, "-o", out, "--resume", cwd=tmp_path)
    assert proc.returncode == 2 and "was run on rectangle face" in proc.stderr \
        and "the scene has the annulus face" in proc.stderr, proc.stderr


@pytest.mark.parametrize("punch, n, match", [
    ({"shape": "annulus", "inner_radius": 0.0025, "outer_radius": 0.004}, 12,
     "grid too coarse for the annulus face (inner_radius 2.5 mm, outer_radius 4 mm): n = 12, "
     "the minimum is n = 16"),
    ({"shape": "rectangle", "width": 0.001, "length": 0.012}, 64,
     "grid too coarse for the rectangle face (width 1 mm, length 12 mm): n = 64, the minimum "
     "is n = 96"),
])
def test_command_line_refuses_a_grid_too_coarse_for_the_outline(tmp_path, scene_file, punch, n,
                                                                 match):
    from test_transient_cli import cli

    scene = scene_file(punch=punch, n=n, map="homogeneous", coefficients=(1e-13,))
    out = tmp_path / "run.h5"
    proc = cli(scene, "-o", out, cwd=tmp_path)
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.startswith("error: ") and match in proc.stderr, proc.stderr
    assert "Traceback" not in proc.stderr and proc.stderr.count("\n") == 1, proc.stderr
    assert not out.exists(), "nothing is written"


def test_shipped_tread_block_run_in_scene():
    scene = load_scene(ROOT / "steady" / "examples" / "tread_block_transient.toml",
                       extra_sections=("transient", "initial_face"))
    assert scene.outline == Rectangle(4e-3, 12e-3) and scene.grid().shape == (64, 192)
    assert scene.geometry.min_grid(scene.outline) <= scene.n
