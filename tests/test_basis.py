"""Phase basis: sweeps over wear coefficients without new transforms."""

import numpy as np
import pytest

from steady.basis import PhaseBasis
from steady.outline import Circle
from steady.phases import Voronoi
from steady.problem import FacePhases, Problem
from steady.rms_slope import SlopeEnergy
from steady.solution import solve


def face_phases(labels, radius=1.0):
    """Labels on the grid of the disk of ``radius`` (``n`` their side), phases 0..max."""
    labels = np.asarray(labels)
    return FacePhases(Circle(radius).grid(max(labels.shape)), labels, int(labels.max()) + 1)


@pytest.mark.parametrize("n", [95, 96])
def test_basis_matches_direct_solves(n):
    """Face, plain and corrected rms slope equal the direct solve to round-off."""
    labels = Voronoi(300, (0.2, 0.3, 0.5), 8128).labels(n)
    radius, E_star, force = 0.004, 1.3e6, 10.0
    phases = face_phases(labels, radius)
    basis = PhaseBasis(phases, E_star)
    rng = np.random.default_rng(1729)
    ks = 10.0 ** rng.uniform(-12, -6, size=(4, 3))
    sweep = basis.rms_slopes(ks, force)
    energy = SlopeEnergy(n, phases.grid.h, E_star)
    for row, k in enumerate(ks):
        direct = solve(Problem(phases, k, force, E_star))
        face = basis.face(k, force)
        on = labels >= 0
        err = np.max(np.abs(face[on] - direct.face[on])) / np.max(np.abs(direct.face[on]))
        assert err < 1e-13, f"row {row}: face differs by {err:.1e}"
        # The solve's plain value comes from the estimator's single-precision kernel
        # spectra: measured 2.2e-10 to 1.9e-9 of it at n = 95 and 96.
        assert sweep.rms_slope_plain[row] == pytest.approx(direct.rms_slope_plain, rel=5e-9), \
            f"row {row}: plain rms slope"
        corrected = energy(direct.pressure, on).rms_slope
        assert sweep.rms_slope[row] == pytest.approx(corrected, rel=1e-12), \
            f"row {row}: corrected rms slope"
        assert direct.rms_slope == pytest.approx(corrected, rel=1e-12), \
            f"row {row}: the solve's corrected rms slope"
        assert np.allclose(sweep.phase_pressures[row], direct.phase_pressures, rtol=1e-14), \
            f"row {row}: phase pressures"


def test_equal_coefficients_give_the_homogeneous_slope():
    """k_1 = k_2: the phase map no longer matters (eq. 7 gives p = pbar)."""
    n = 128
    basis = PhaseBasis(face_phases(Voronoi(400, (0.5, 0.5), 6174).labels(n)), 1.0)
    homogeneous = PhaseBasis(face_phases(np.where(basis.labels >= 0, 0, -1)), 1.0)
    a = basis.rms_slopes([[2.0, 2.0]], np.pi).normalised[0]
    b = homogeneous.rms_slopes([[2.0]], np.pi).normalised[0]
    assert a == pytest.approx(b, rel=1e-12), f"{a} vs homogeneous {b}"


def test_wrong_number_of_coefficients():
    basis = PhaseBasis(face_phases(Voronoi(100, (0.5, 0.5), 9001).labels(32)), 1.0,
                       faces=False)
    with pytest.raises(ValueError, match="2 wear coefficients"):
        basis.rms_slopes([[1.0, 2.0, 3.0]], 1.0)
    with pytest.raises(ValueError, match="faces=False"):
        basis.face([1.0, 2.0], 1.0)


@pytest.mark.parametrize("rho", [0.05, 0.2])
def test_pillars_limit_over_the_whole_face(rho):
    """k_2/k_1 -> 0: whole-face rms slope -> sqrt(1 + (pi^2/4)(1/rho - 1)) grad_f0.

    Measured (corrected, n = 256, Voronoi 40^2 seeds): 6.829 vs 6.894
    (rho = 0.05) and 3.250 vs 3.279 (rho = 0.2), both -0.9 %: the share of
    the field outside the punch is that of the homogeneous punch only
    approximately.  Eq. 18's 1/rho (19.9, 5.0) holds over the pillars only.
    """
    from steady import reference

    basis = PhaseBasis(face_phases(Voronoi(1600, (1 - rho, rho), 31).labels(256)), 1.0,
                       faces=False)
    got = basis.rms_slopes([[1.0, 1e-8]], np.pi).normalised[0]
    want = reference.fine_grain_rms_slope(basis.fill_factors, [1.0, 1e-8])
    assert got == pytest.approx(want, rel=0.015), f"rho={rho}: {got} vs asymptote {want}"
    over_pillars = reference.pillars_rms_slope(1.0, 1.0, basis.fill_factors[1]) / (4 / np.pi)
    # (pi/2) sqrt(rho) of eq. 18: 0.35 at rho = 0.05, 0.70 at 0.2.
    assert got < 0.75 * over_pillars, f"the whole face lies below eq. 18 ({over_pillars})"
