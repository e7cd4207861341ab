"""Sliding kinematics (``[sliding]``): the speed field, its steady state and its run-in."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from conftest import FORCE, GEOMETRIES, K1, OUTLINES, RADIUS, problem, scene_text

from steady.fit import FaceModel
from steady.outline import Circle
from steady.problem import Problem
from steady.scene import parse_scene
from steady.sliding import SLIDING, PinOnDisk, Rotation, Translation
from steady.solution import solve
from steady.wear import PowerLaw
from transient import RunOptions, WearProblem, run_in
from transient.initial_face import initial_recession


def _with(prob, sliding):
    """The same problem under other kinematics."""
    return Problem(prob.phases, prob.wear, prob.normal_force, prob.E_star, sliding)


def _shape(face, mask):
    """A face on ``mask`` less its mean (the rigid approach is free)."""
    g = np.where(mask, face, 0.0)
    return np.where(mask, g - g[mask].mean(), 0.0)


def _relative_rms(a, b, mask):
    """The rms of ``a - b`` over the rms of ``b``, on ``mask``, shapes only."""
    a, b = _shape(a, mask), _shape(b, mask)
    return float(np.sqrt(np.mean((a - b)[mask] ** 2) / np.mean(b[mask] ** 2)))


def _love_sum(pressure, grid, E_star):
    """``K p`` at the pixel centres by direct summation of Love's uniform-pixel solution."""
    h = grid.h
    X, Y = np.meshgrid(grid.x, grid.y, indexing="ij")
    src = pressure != 0
    xs, ys, ps = X[src], Y[src], pressure[src]

    def primitive(x, y):  # integral of 1 / r over [0, x] x [0, y], for x, y of any sign
        r = np.hypot(x, y)
        with np.errstate(divide="ignore", invalid="ignore"):
            a = np.where(x != 0, x * np.log((y + r) / np.where(x != 0, np.abs(x), 1.0)), 0.0)
            b = np.where(y != 0, y * np.log((x + r) / np.where(y != 0, np.abs(y), 1.0)), 0.0)
        return a + b

    u = np.zeros(pressure.shape)
    for i, j in zip(*np.nonzero(grid.mask), strict=True):
        dx, dy = xs - X[i, j], ys - Y[i, j]
        w = (primitive(dx + h / 2, dy + h / 2) - primitive(dx - h / 2, dy + h / 2)
             - primitive(dx + h / 2, dy - h / 2) + primitive(dx - h / 2, dy - h / 2))
        u[i, j] = np.dot(w, ps) / (np.pi * E_star)
    return u


# -- the scene section ------------------------------------------------------
def test_scene_reads_each_kind_and_a_translation_is_the_default():
    text = scene_text("steady")
    assert parse_scene(text, ".").sliding is None, "no [sliding]: a translation (None)"
    assert parse_scene(text + '[sliding]\nkind = "translation"\n', ".").sliding is None, \
        "an explicit translation is the default path"
    scene = parse_scene(text + '[sliding]\nkind = "pin_on_disk"\ntrack_radius = 0.02\n', ".")
    assert scene.sliding == PinOnDisk(0.02), f"got {scene.sliding!r}"
    ring = parse_scene(scene_text("steady", punch={"shape": "annulus", "inner_radius": 0.002,
                                                   "outer_radius": 0.004})
                       + '[sliding]\nkind = "rotation"\n', ".")
    assert ring.sliding == Rotation(), f"got {ring.sliding!r}"
    assert set(SLIDING) == {"translation", "pin_on_disk", "rotation"}


@pytest.mark.parametrize("extra, fragment", [
    ('[sliding]\nkind = "rotation"\n', "the rotation axis at (x, y) = (0, 0) m lies on the "
                                       "circle face"),
    ('[sliding]\nkind = "pin_on_disk"\ntrack_radius = 0.003\n',
     "[sliding] pin_on_disk, track_radius = 0.003 m: the rotation axis at (x, y) = (-0.003, 0)"),
    ('[sliding]\nkind = "pin_on_disk"\ntrack_radius = -1\n',
     "[sliding] track_radius must be a number > 0 (m), got -1"),
    ('[sliding]\nkind = "pin_on_disk"\n', "missing key 'track_radius' in [sliding]"),
    ('[sliding]\nkind = "spiral"\n', "[sliding] kind must be one of"),
    ('[sliding]\nkind = "rotation"\ntrack_radius = 0.02\n', "unknown key 'track_radius'"),
])
def test_scene_refuses_bad_kinematics_naming_the_value(extra, fragment):
    with pytest.raises(ValueError) as err:
        parse_scene(scene_text("steady") + extra, ".")
    assert fragment in str(err.value), f"message {str(err.value)!r} lacks {fragment!r}"


@pytest.mark.parametrize("radius", [-1.0, 0, math.nan, True, "2 cm"])
def test_a_pin_on_disk_built_in_python_is_refused_as_in_a_scene(radius):
    with pytest.raises(ValueError) as err:
        PinOnDisk(radius)
    assert f"track_radius must be a number > 0 (m), got {radius!r}" in str(err.value), err.value


def test_a_translation_leaves_the_problem_bit_for_bit():
    base = problem(GEOMETRIES["voronoi"], [K1, 10 * K1], n=32)
    same = _with(base, Translation())
    assert same.sliding is None, "a translation is stored as None (the default path)"
    assert np.array_equal(base.wear_field(), same.wear_field())
    assert np.array_equal(base.steady_pressure(), same.steady_pressure())
    assert base.speed_ratio is None


# -- the steady state -------------------------------------------------------
@pytest.mark.parametrize("exponent", [1.0, 2.0])
@pytest.mark.parametrize("n", [31, 32])
def test_steady_pressure_wears_every_pixel_at_one_rate_and_carries_the_load(exponent, n):
    base = problem(GEOMETRIES["voronoi"], PowerLaw([K1, 10 * K1], exponent), n=n)
    prob = _with(base, PinOnDisk(1.5 * RADIUS))
    p = prob.steady_pressure()
    mask = prob.face_mask
    rate = prob.wear_field()[mask] * p[mask] ** exponent
    assert np.ptp(rate) <= 1e-13 * rate.mean(), f"rates spread {np.ptp(rate) / rate.mean():.3g}"
    load = p.sum() * prob.pixel_area
    assert abs(load - FORCE) <= 1e-13 * FORCE, f"load {load} N, not {FORCE} N"
    assert np.all(p[~mask] == 0.0), "pressure off the face"
    # Within each phase p ~ v^(-1/m): the outer side (x > 0) slides faster and carries less.
    for i in range(2):
        on = mask & (prob.labels == i)
        scaled = p[on] * prob.speed_ratio[on] ** (1.0 / exponent)
        assert np.ptp(scaled) <= 1e-13 * scaled.mean(), f"phase {i}: p v^(1/m) not constant"
        assert np.ptp(p[on]) > 0.1 * p[on].mean(), f"phase {i}: pressure hardly varies"
    means = prob.phase_pressures()
    counts = prob.phases.counts
    assert abs(np.dot(means, counts) * prob.pixel_area - FORCE) <= 1e-12 * FORCE


@pytest.mark.parametrize("n", [23, 24])
def test_steady_face_matches_a_direct_summation_of_the_pixel_influence(n):
    prob = _with(problem(GEOMETRIES["voronoi_small"], [K1, 3 * K1], n=n),
                 PinOnDisk(1.2 * RADIUS))
    result = solve(prob, face_only=True)
    direct = _love_sum(result.pressure, prob.grid, prob.E_star)
    mask = prob.face_mask
    error = np.max(np.abs(result.face[mask] - direct[mask])) / np.ptp(direct[mask])
    # Both are K p of the same pixel pressures: the FFT product agrees to round-off.
    assert error < 1e-12, f"FFT face differs from the direct sum by {error:.3g} of its relief"


def test_rotation_of_an_annulus_has_pressure_inverse_to_the_radius():
    ring = OUTLINES["annulus"]
    prob = Problem(problem(GEOMETRIES["homogeneous"], [K1], n=48, outline=ring).phases,
                   [K1], FORCE, 1.3e6, Rotation())
    p = prob.steady_pressure()
    mask = prob.face_mask
    pr = (p * prob.grid.radii)[mask]
    assert np.ptp(pr) <= 1e-12 * pr.mean(), f"p r spreads by {np.ptp(pr) / pr.mean():.3g}"
    # The closed form p = F / (2 pi (a_o - a_i) r) of the continuous ring, to the pixel area.
    exact = FORCE / (2 * np.pi * (ring.outer_radius - ring.inner_radius))
    measured_area = mask.sum() * prob.pixel_area
    assert abs(pr.mean() / exact - ring.area / measured_area) < 0.02, \
        f"p r = {pr.mean():.4g}, closed form {exact:.4g} N/m"
    result = solve(prob, face_only=True)
    direct = _love_sum(result.pressure, prob.grid, prob.E_star)
    error = np.max(np.abs(result.face[mask] - direct[mask])) / np.ptp(direct[mask])
    assert error < 1e-12, f"FFT face differs from the direct sum by {error:.3g}"


def test_rotation_needs_an_axis_off_the_face():
    disk = problem(GEOMETRIES["homogeneous"], [K1], n=32)
    with pytest.raises(ValueError, match=r"lies on the circle face .* unbounded at the axis"):
        _with(disk, Rotation())


def test_large_track_radius_reproduces_the_translation_steady_state():
    base = problem(GEOMETRIES["voronoi"], [K1, 10 * K1], n=32)
    flat = solve(base, geometry=GEOMETRIES["voronoi"])
    gaps = []
    for ratio in (1e2, 1e3, 1e4):
        tilted = solve(_with(base, PinOnDisk(ratio * RADIUS)), geometry=GEOMETRIES["voronoi"])
        gaps.append(abs(tilted.rms_slope / flat.rms_slope - 1.0))
    # The speed ratio is 1 + x / R: the slope changes in proportion to a / R (measured
    # 2.1e-4, 2.2e-5, 2.2e-6).
    assert gaps[2] < 5e-6 and gaps[1] < 5e-5, f"rms slope gaps {gaps} at R / a = 1e2, 1e3, 1e4"
    assert 5 < gaps[0] / gaps[1] < 20 and 5 < gaps[1] / gaps[2] < 20, \
        f"gaps {gaps} do not fall like a / R"


def test_fit_refuses_non_uniform_sliding():
    prob = _with(problem(GEOMETRIES["voronoi"], [K1, 10 * K1], n=32), PinOnDisk(0.02))
    with pytest.raises(ValueError, match="the fit assumes a uniform sliding speed"):
        FaceModel(prob)


# -- the run-in ---------------------------------------------------------------
def _run(prob, tol=1e-4):
    wear = WearProblem(prob)
    flat = initial_recession("flat", wear.grid)
    return wear, run_in(wear, flat, RunOptions(tol=tol))


@pytest.mark.parametrize("sliding", [PinOnDisk(1.5 * RADIUS), "ring"])
def test_run_in_reaches_the_closed_form_steady_face(sliding):
    if sliding == "ring":
        ring = OUTLINES["annulus"]
        prob = Problem(problem(GEOMETRIES["voronoi"], [K1, 10 * K1], n=32, outline=ring).phases,
                       [K1, 10 * K1], FORCE, 1.3e6, Rotation())
    else:
        prob = _with(problem(GEOMETRIES["voronoi"], [K1, 10 * K1], n=32), sliding)
    wear, result = _run(prob)
    assert result.success, result.message
    steady = solve(prob, face_only=True)
    error = _relative_rms(result.face, steady.face, prob.face_mask)
    # Measured 2e-8 (the run's stop test); a tilt or a per-phase pressure would show as 1e-2.
    assert error < 1e-6, f"run-in face differs from the closed form by {error:.3g}"


def test_run_in_with_large_track_radius_reproduces_the_translation():
    base = problem(GEOMETRIES["voronoi"], [K1, 10 * K1], n=32)
    _, flat = _run(base, tol=1e-3)
    gaps = []
    for ratio in (1e2, 1e4):
        _, far = _run(_with(base, PinOnDisk(ratio * RADIUS)), tol=1e-3)
        gaps.append(_relative_rms(far.face, flat.face, base.face_mask))
    # The face tilts by a / R: measured 1.41 a / R of the relief, the steady faces' own gap.
    assert gaps[1] < 2e-4 and 50 < gaps[0] / gaps[1] < 200, \
        f"run-in faces differ from the translation's by {gaps} at R / a = 1e2, 1e4"


def test_stage_shift_is_the_speed_weighted_coefficient_field():
    prob = _with(problem(GEOMETRIES["voronoi"], [K1, 10 * K1], n=32), PinOnDisk(0.02))
    wear = WearProblem(prob)
    expected = prob.wear.wear_field(prob.labels) * prob.speed_ratio
    assert np.array_equal(wear.wear_field, expected)
    pressure = np.where(prob.face_mask, 1e5, 0.0)
    assert np.allclose(wear.rate(pressure), expected * 1e5, rtol=1e-15, atol=0)
    assert dataclasses.is_dataclass(prob.sliding)
    assert isinstance(prob.outline, Circle)
