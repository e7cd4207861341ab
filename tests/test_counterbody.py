"""The counter-body of finite thickness: its mode factor, its operator, scenes, files and run-in.

The factor is checked against two independent evaluations of the layer: the boundary-value
problem of each mode (Navier's equations in plane strain, a 4 x 4 linear system) and the
published closed form in 60-digit arithmetic.  The finite punch's real-space operator is checked
against a periodic cell built here from the factor alone (numpy FFTs, pixel aliases summed),
and against the half-space for a thick layer.
"""

import dataclasses
import math

import mpmath
import numpy as np
import pytest
import scipy.linalg
from conftest import E_STAR, FORCE, K1, RADIUS, scene_text

from steady.counterbody import Counterbody, LayeredHalfSpace, correction_kernel, fourier_factor
from steady.halfspace import HalfSpace
from steady.outline import Circle
from steady.output import read_result, write_result
from steady.phases import Voronoi
from steady.problem import FacePhases, Problem
from steady.scene import parse_scene
from steady.solution import solve
from transient.comparison import compare_with_steady
from transient.contact import solve_contact
from transient.problem import WearProblem
from transient.runin import RunOptions, run_in

POISSONS = (0.0, 0.25, 0.3, 0.45, 0.499)


def layer_mode(k, nu):
    """Surface compliance of a layer of thickness 1 under ``cos(k x)``, over the half-space's.

    Plane strain, ``u_x = U(z) sin kx``, ``u_z = W(z) cos kx``, z down from the surface; the
    state ``(U, W, U', W')`` obeys Navier's equations ``y' = A y``; frictionless loaded top,
    base clamped at z = 1.  Shear modulus 1.
    """
    lam = 2 * nu / (1 - 2 * nu)
    mu = 1.0
    A = np.zeros((4, 4))
    A[0, 2] = A[1, 3] = 1.0
    A[2, 0] = (lam + 2 * mu) * k * k / mu
    A[2, 3] = (lam + mu) * k / mu
    A[3, 1] = mu * k * k / (lam + 2 * mu)
    A[3, 2] = -(lam + mu) * k / (lam + 2 * mu)
    base = scipy.linalg.expm(A)
    system = np.array([[0.0, -k, 1.0, 0.0],              # shear stress 0 on top
                       [lam * k, 0.0, 0.0, lam + 2 * mu],  # normal stress -p on top
                       base[0], base[1]])                  # U = W = 0 at the base
    y0 = np.linalg.solve(system, [0.0, -1.0, 0.0, 0.0])
    E_star = 2 * mu / (1 - nu)  # E / (1 - nu^2) with E = 2 mu (1 + nu)
    return y0[1] / (2 / (E_star * k))


@pytest.mark.parametrize("nu", POISSONS)
def test_factor_solves_the_layer_boundary_value_problem(nu):
    # Measured: 4e-15 (nu <= 0.3), 4e-14 (0.45), 1.4e-10 (0.499: lambda / mu = 499 makes the
    # layer solve ill-conditioned), relative, for qt up to 8.
    tol = 1e-9 if nu > 0.49 else 1e-12
    for k in (0.05, 0.3, 1.0, 3.0, 8.0):
        ref = layer_mode(k, nu)
        assert abs(fourier_factor(k, nu) - ref) <= tol * ref, \
            f"nu {nu}, qt {k}: factor {fourier_factor(k, nu)!r}, layer solve {ref!r}"


@pytest.mark.parametrize("nu", (0.0, 0.3, 0.5))
def test_factor_matches_the_closed_form_in_high_precision(nu):
    # Measured: 5e-16 relative at most, from qt = 1e-8 (cancellation) to 1e5 (overflow of
    # cosh); every value finite.
    mpmath.mp.dps = 60
    s, off = 3 - 4 * mpmath.mpf(nu), 5 - 12 * mpmath.mpf(nu) + 8 * mpmath.mpf(nu) ** 2
    for k in (1e-8, 1e-4, 0.01, 0.5, 0.999, 1.0, 1.001, 3.0, 20.0, 400.0, 1e5):
        x = mpmath.mpf(k)
        ref = float((s * mpmath.sinh(2 * x) - 2 * x) / (s * mpmath.cosh(2 * x) + 2 * x * x + off))
        got = fourier_factor(k, nu)
        assert math.isfinite(got) and abs(got - ref) <= 2e-15 * ref, \
            f"nu {nu}, qt {k}: {got!r} vs {ref!r}"


def test_factor_small_thickness_limits():
    # Compressible: (1 - 2 nu) k / (2 (1 - nu)^2) + O(k^2); incompressible 2 k^3 / 3 + O(k^5).
    # Measured relative deviation at k = 1e-3: 1.2e-3 (nu = 0.3; linear in k), 1.8e-6 (nu = 1/2;
    # 1.8 k^2).
    k = 1e-3
    for nu in (0.0, 0.3):
        slope = (1 - 2 * nu) / (2 * (1 - nu) ** 2)
        assert abs(fourier_factor(k, nu) / (slope * k) - 1) < 3 * k, f"nu {nu}"
    assert abs(fourier_factor(k, 0.5) / (2 * k ** 3 / 3) - 1) < 3e-6, "nu 0.5"
    assert fourier_factor(0.0, 0.3) == 0.0 and fourier_factor(0.0, 0.5) == 0.0


def test_factor_is_continuous_at_incompressibility():
    # d phi / d nu is bounded: the step to nu = 0.5 shrinks with the gap (measured 2.5 eps
    # at k = 0.1 .. 5).
    k = np.array([0.01, 0.1, 1.0, 5.0])
    for eps in (1e-3, 1e-6, 1e-9):
        step = np.abs(fourier_factor(k, 0.5 - eps) - fourier_factor(k, 0.5))
        assert np.all(step < 5 * eps), f"eps {eps}: steps {step}"


def test_correction_kernel_limits():
    # c(0) finite, -1/rho far out (the layer's total kernel vanishes): measured 3e-16 at rho 50.
    for nu in (0.3, 0.5):
        value, slope = correction_kernel(np.array([0.0, 50.0]), nu)
        assert math.isfinite(value[0]) and value[0] < 0 and slope[0] == 0.0, f"nu {nu}"
        assert abs(value[1] + 1 / 50) < 1e-12, f"nu {nu}: C(50) = {value[1]!r}"


@pytest.mark.parametrize("n", [24, 25])
def test_thick_layer_is_the_half_space(n):
    # The correction is -C(0) h^2 / (pi E* t) per unit pressure, so the difference falls as
    # 1 / t: measured 6.9e-3 and 6.9e-4 of the largest displacement at t = 100 and 1000 a.
    grid = Circle(RADIUS).grid(n)
    p = np.where(grid.mask, 1e4, 0.0)
    u_hs = HalfSpace(grid.shape, grid.h, E_STAR).displacement(p)
    errors = []
    for t in (100 * RADIUS, 1000 * RADIUS):
        u = LayeredHalfSpace(grid.shape, grid.h, E_STAR, t, 0.3).displacement(p)
        errors.append(float(np.abs(u - u_hs).max() / u_hs.max()))
    assert errors[1] < 1e-3 and errors[0] / errors[1] > 9, f"errors {errors}"


def periodic_symbol(N, h, E_star, t, nu, M):
    """Displacement symbol of a pixel-constant pressure on an N x N periodic layer, at pixels.

    ``sum over aliases |m| <= M of G(q + 2 pi m / h) sinc sinc``, ``G = 2 phi / (E* q)``; the
    mode q = 0 is the layer's uniaxial compliance.
    """
    qx = 2 * np.pi * np.fft.fftfreq(N, h)
    qy = 2 * np.pi * np.fft.rfftfreq(N, h)
    S = np.zeros((N, qy.size))
    for mx in range(-M, M + 1):
        Qx = qx + 2 * np.pi * mx / h
        sx = np.sinc(Qx * h / (2 * np.pi))
        for my in range(-M, M + 1):
            Qy = qy + 2 * np.pi * my / h
            Q = np.hypot(Qx[:, None], Qy[None, :])
            with np.errstate(divide="ignore", invalid="ignore"):
                G = 2 * fourier_factor(Q * t, nu) / (E_star * Q)
            if mx == 0 and my == 0:
                G[0, 0] = (1 - 2 * nu) * t / ((1 - nu) ** 2 * E_star)
            S += G * sx[:, None] * np.sinc(Qy * h / (2 * np.pi))[None, :]
    return S


@pytest.mark.parametrize("n, thickness, nu", [(24, 2.0, 0.5), (25, 1.0, 0.3)])
def test_finite_punch_on_a_layer_is_a_large_periodic_cell(n, thickness, nu):
    # The punch alone in a cell of 3n pixels; the aliases' sum truncated at M = 16 and 32 and
    # extrapolated as M^-3 (its measured order).  Faces agree to 1e-7 of the largest
    # displacement (measured 9.7e-8 and 7.1e-8), up to a constant: the periodic images' mean
    # compression.
    grid = Circle(RADIUS).grid(n)
    t = thickness * grid.h
    p = np.where(grid.mask, 1e4, 0.0)
    u = LayeredHalfSpace(grid.shape, grid.h, E_STAR, t, nu).displacement(p)
    N = 3 * n
    cell = np.zeros((N, N))
    cell[:n, :n] = p
    S = (8 * periodic_symbol(N, grid.h, E_STAR, t, nu, 32)
         - periodic_symbol(N, grid.h, E_STAR, t, nu, 16)) / 7
    u_cell = np.fft.irfft2(np.fft.rfft2(cell) * S, s=(N, N))[:n, :n]
    d = (u - u_cell)[grid.mask]
    d -= d.mean()
    assert np.abs(d).max() < 3e-7 * np.abs(u).max(), \
        f"deviation {np.abs(d).max() / np.abs(u).max():.3g} of the largest displacement"


def test_flat_punch_on_a_thin_incompressible_layer():
    # Thin-layer limit (squeeze flow, t << a): F / delta = 3 pi E* a^4 / (32 t^3).  The ratio
    # to it rises as 1 - O(t / a): measured 0.758 and 0.874 at t/a = 0.05 and 0.025 (n =
    # 128); linear extrapolation to t = 0 gives 0.989.
    grid = Circle(RADIUS).grid(128)
    ratios = []
    for ta in (0.05, 0.025):
        t = ta * RADIUS
        layer = LayeredHalfSpace(grid.shape, grid.h, E_STAR, t, 0.5)
        res = solve_contact(layer, grid.mask, np.zeros(grid.shape), FORCE, rtol=1e-10)
        ratios.append(res.approach / (32 * FORCE * t ** 3 / (3 * math.pi * E_STAR * RADIUS ** 4)))
    limit = 2 * ratios[1] - ratios[0]
    assert ratios[0] < ratios[1] < 1 and abs(limit - 1) < 0.03, f"ratios {ratios}, {limit}"


def test_thin_layers_are_refused_by_the_operator():
    with pytest.raises(ValueError, match="not resolved by pixels"):
        LayeredHalfSpace(16, 1e-4, E_STAR, 1e-6, 0.3)


def layered_problem(thickness, poisson, n=32):
    grid = Circle(RADIUS).grid(n)
    phases = FacePhases(grid, Voronoi(64, (0.7, 0.3), 2029).labels(grid), 2)
    return Problem(phases, [K1, 10 * K1], FORCE, E_STAR, thickness=thickness, poisson=poisson)


@pytest.mark.parametrize("thickness, nu", [(1e-3, 0.5), (3e-4, 0.3)])
def test_run_in_on_a_layer_reaches_its_closed_form(thickness, nu):
    # Measured at n = 32: face 4.4e-8 and 1.4e-7 of the relief (the final jump's error), phase
    # pressures to round-off.
    problem = WearProblem(layered_problem(thickness, nu))
    result = run_in(problem, np.zeros(problem.shape), RunOptions(tol=1e-3))
    assert result.status == "steady", result.message
    cmp = compare_with_steady(result, problem.solve_steady(), problem)
    assert cmp.face_error < 1e-6, f"face error {cmp.face_error:.3g}"
    assert cmp.phase_pressure_error < 1e-9, f"pressures {cmp.phase_pressure_error:.3g}"


def test_steady_face_is_the_layered_displacement():
    problem = layered_problem(1e-3, 0.5)
    result = solve(problem)
    layer = LayeredHalfSpace(problem.shape, problem.grid.h, E_STAR, 1e-3, 0.5)
    expected = layer.displacement(problem.steady_pressure())[problem.face_mask]
    assert np.array_equal(result.face[problem.face_mask], expected), "face"
    half = solve(layered_problem(None, None))
    assert result.rms_slope < half.rms_slope, "a thin incompressible layer flattens the face"


def test_result_file_records_the_layer(tmp_path):
    problem = layered_problem(1e-3, 0.5)
    result = solve(problem, face_only=True)
    write_result(tmp_path / "layer.h5", result)
    stored = read_result(tmp_path / "layer.h5").result
    assert (stored.thickness, stored.poisson) == (1e-3, 0.5), "thickness and poisson"
    write_result(tmp_path / "half.h5", solve(layered_problem(None, None), face_only=True))
    stored = read_result(tmp_path / "half.h5").result
    assert (stored.thickness, stored.poisson) == (None, None), "a half-space has no layer"


def layered_scene(**layer):
    """The gallery's run-in scene (without its run-in section), with ``[counterbody]`` keys."""
    return scene_text("runin", transient=None, counterbody=layer)


def test_scene_reads_the_layer():
    scene = parse_scene(layered_scene(thickness=0.002, poisson=0.5), ".")
    assert scene.counterbody == Counterbody(1.3e6, 0.002, 0.5), scene.counterbody
    assert parse_scene(layered_scene(), ".").counterbody.layered is False


@pytest.mark.parametrize("layer, words", [
    (dict(thickness=-0.002, poisson=0.3), "thickness must be a number > 0"),
    (dict(thickness=0, poisson=0.3), "thickness must be a number > 0"),
    (dict(thickness=0.002, poisson=-0.1), "poisson must be a number in [0, 0.5]"),
    (dict(thickness=0.002, poisson=0.6), "poisson must be a number in [0, 0.5]"),
    (dict(poisson=0.3), "poisson = 0.3 is for a layer: give its thickness"),
    (dict(thickness=0.002), "thickness = 0.002 needs poisson"),
])
def test_bad_layer_inputs_are_refused_in_one_line(layer, words):
    with pytest.raises(ValueError) as err:
        parse_scene(layered_scene(**layer), ".")
    message = str(err.value)
    assert words in message and "\n" not in message, message


def test_counterbody_in_python_checks_its_layer():
    with pytest.raises(ValueError, match="needs poisson"):
        layered_problem(1e-3, None)
    with pytest.raises(ValueError, match=r"in \[0, 0.5\]"):
        Counterbody(1.3e6, 1e-3, 0.7)
    assert dataclasses.replace(Counterbody(1.3e6, 1e-3, 0.5), thickness=None,
                               poisson=None).fourier_factor(10.0) == 1.0
