"""Energy-corrected rms slope: accuracy against closed forms and fine grids."""

import numpy as np
import pytest
import scipy.fft

from steady import reference
from steady.halfspace import pixel_integral_gradient
from steady.outline import UNIT_DISK, Circle
from steady.phases import ArrayMap, Homogeneous, Voronoi
from steady.rms_slope import (
    SlopeEnergy,
    edge_jumps,
    estimate_map_rms_slope,
    estimate_rms_slope,
    grid_ladder,
    mean_chord,
    monopole_tail,
    resample_labels,
)
from steady.wear import pressure_field

G0 = 4 / np.pi  # grad_f0 for pbar = 1 Pa, E* = 1 Pa


def _integrals(geometry, n, k, radius=1.0):
    labels = geometry.labels(n)
    h = Circle(radius).grid(n).h
    pressure, _, _ = pressure_field(labels, k, np.pi * radius**2, h * h)
    return SlopeEnergy(n, h, 1.0)(pressure, labels >= 0)


@pytest.mark.parametrize("n", [255, 256, 511, 512])
def test_homogeneous_rms_slope_matches_continuum(n):
    """Eq. 10 face: the corrected rms slope is the quadrature value 1 (x grad_f0).

    Measured errors: 5.9e-4 (255), 9.0e-5 (256), 7.6e-5 (511), 1.3e-5 (512),
    against 1.0e-2 .. 5.4e-3 for the plain pixel estimate.  The residual
    is the rim's staircase, irregular in n; 1e-3 bounds every n >= 255
    measured (the 0.1 % aim).
    """
    r = _integrals(Homogeneous(), n, [1.0])
    exact = reference.disk_normalised_rms_slope()
    err = abs(r.rms_slope / G0 - exact)
    plain = abs(r.rms_slope_plain / G0 - exact)
    assert err < 1e-3, f"n={n}: corrected rms slope off by {err:.2e}"
    assert err < plain / 8, f"n={n}: correction gains too little ({err:.2e} vs plain {plain:.2e})"


def test_quadratures_converge_to_the_exact_total():
    """Parseval: the plane integral of |grad u|^2 is (4/E*^2) sum p^2 h^2.

    For a smooth (Gaussian) pressure the face and exterior quadratures
    together converge to that exact total; the defect comes from the
    pixel-edge jumps of the piecewise-constant pressure and is first
    order.  Measured defects 8.8 %, 4.4 %, 2.2 % at n = 64, 128, 256:
    order 1.00.
    """
    ns = np.array([64, 128, 256])
    defects = []
    for n in ns:
        grid = UNIT_DISK.grid(n)
        r, _ = grid.polar()
        p = np.exp(-((r / 0.2) ** 2))
        s = SlopeEnergy(n, 2.0 / n, 1.0)(p, grid.mask)
        defects.append(abs(s.defect) / s.total)
    order = -np.polyfit(np.log(ns), np.log(defects), 1)[0]
    assert 0.9 < order < 1.1, f"defect order {order:.3f}, defects {defects}"


def test_monopole_tail_of_a_centred_square():
    """Outside [-L, L]^2 about the centroid: (F / (pi E*))^2 (pi/2 + 1) / L^2."""
    L = 3.0
    got = monopole_tail(2.0, (0.0, 0.0), (-L, L, -L, L), 1.0)
    want = (2.0 / np.pi) ** 2 * (np.pi / 2 + 1) / L**2
    assert got == pytest.approx(want, rel=1e-14), f"tail {got} != {want}"


def test_edge_jumps_split_rim_and_interior():
    labels = Voronoi(64, (0.5, 0.5), 5150).labels(40)
    on_face = labels >= 0
    p = np.where(on_face, np.where(labels == 1, 3.0, 1.0), 0.0)
    interior, rim = edge_jumps(p, on_face)
    boundary = 0
    for axis in (0, 1):
        a = np.moveaxis(np.pad(labels, 1, constant_values=-1), axis, 0)
        boundary += np.sum((a[1:] != a[:-1]) & (a[1:] >= 0) & (a[:-1] >= 0))
    assert interior == pytest.approx(4.0 * boundary), "interior edges carry jump 2 each"
    assert rim > 0, "the rim must carry the face pressure's jump to zero"


@pytest.mark.parametrize("seeds", [20**2, 160**2])
def test_voronoi_corrected_converges_faster_than_plain(seeds):
    """rho_2 = 0.5, k_2/k_1 = 10: corrected at n = 512 agrees with n = 1024.

    Measured (seed 4321): 20^2 seeds 1.6004 / 1.5999 / 1.5996 and 160^2
    seeds 1.6275 / 1.6259 / 1.6257 (x grad_f0) at n = 512 / 1024 / 2048,
    where the plain grid gives 1.539 / 1.565 / 1.580 and 1.371 / 1.469 /
    1.533.  The corrected change 512 -> 1024 is below 0.2 %; the plain
    one is 1.6 % and 7 %.
    """
    geometry = Voronoi(seeds, (0.5, 0.5), 4321)
    coarse = _integrals(geometry, 512, [1.0, 10.0])
    fine = _integrals(geometry, 1024, [1.0, 10.0])
    change = abs(coarse.rms_slope / fine.rms_slope - 1)
    plain_change = abs(coarse.rms_slope_plain / fine.rms_slope_plain - 1)
    assert change < 2e-3, f"corrected rms slope moved {change:.2%} from n=512 to 1024"
    assert change < plain_change / 8, f"corrected {change:.2%} vs plain {plain_change:.2%}"


def test_error_estimate_bounds_the_error():
    """The reported error bounds the true error (homogeneous, closed form)."""
    for n in (256, 384, 512):
        est = estimate_rms_slope(Homogeneous(), [1e-9], np.pi, 1.0, 1.0, n)
        err = abs(est.rms_slope / G0 - reference.disk_normalised_rms_slope())
        assert err <= est.error / G0, f"n={n}: error {err:.2e} above estimate {est.error / G0:.2e}"
        assert est.error / G0 < 5e-3, f"n={n}: estimate {est.error / G0:.2e} uselessly large"


def test_error_estimate_uses_a_finer_grid_for_a_pixel_map():
    labels = Voronoi(100, (0.3, 0.7), 2718).labels(64)
    est = estimate_rms_slope(ArrayMap(labels), [1.0, 5.0], np.pi, 1.0, 1.0, 64)
    assert est.grids == (64, 128), f"a pixel map refines by replication, got {est.grids}"
    assert est.error == pytest.approx(abs(est.values[1] - est.values[0])), "error is the change"


@pytest.mark.parametrize("n0, n, expected", [
    (20, 100, [20, 100]),   # n/4 = 25 and n/2 = 50 are not multiples of 20; nor is 24
    (20, 60, [20, 60]),
    (20, 80, [20, 40, 80]),
    (20, 20, [20, 40]),     # the map's own size: refine
    (12, 36, [12, 36]),
])
def test_grid_ladder_of_a_pixel_map_is_admissible(n0, n, expected):
    """A map of n0 x n0 pixels exists only at multiples of n0, and so must every grid."""
    geometry = ArrayMap(Voronoi(36, (0.3, 0.7), 2718).labels(n0))
    grids = grid_ladder(geometry, n)
    assert grids == expected, f"{n0} x {n0} map at n = {n}: ladder {grids}"
    for m in grids:
        assert geometry.check_grid(m) == m, f"grid {m} of the ladder refused"


def test_error_estimate_of_a_pixel_map_whose_size_is_not_a_multiple_of_8():
    """A 20 x 20 map at n = 100: the estimate runs on the grids 20 and 100 (not 24)."""
    geometry = ArrayMap(Voronoi(100, (0.3, 0.7), 2718).labels(20))
    est = estimate_rms_slope(geometry, [1.0, 5.0], np.pi, 1.0, 1.0, 100)
    assert est.grids == (20, 100), f"grids {est.grids}"
    assert np.all(np.isfinite(est.values)) and est.rms_slope > 0, f"values {est.values}"
    # First order from n = 20 to 100, carried to 100: a quarter of the change.
    assert est.error == pytest.approx(abs(est.values[1] - est.values[0]) / 4), \
        f"error {est.error} from values {est.values}"


@pytest.mark.slow
def test_rms_slope_is_independent_of_grain_size():
    """Paper's main claim, at converged resolution (corrected, n = 512).

    rho_2 = 0.5, k_2/k_1 = 10, ten realisations per coarseness level.
    Measured means (sd): 20^2 1.606 (0.047), 40^2 1.616 (0.017),
    80^2 1.627 (0.011), 160^2 1.627 (0.004).  Each level's mean agrees
    with the finest level's within three standard errors of the
    difference; the plain grid's levels (1.548 .. 1.368) do not.
    """
    means, ses, plain = [], [], []
    for seeds in (20**2, 40**2, 80**2, 160**2):
        vals, pl = [], []
        for r in range(10):
            integrals = _integrals(Voronoi(seeds, (0.5, 0.5), 1000 + r), 512, [1.0, 10.0])
            vals.append(integrals.rms_slope / G0)
            pl.append(integrals.rms_slope_plain / G0)
        means.append(np.mean(vals))
        ses.append(np.std(vals, ddof=1) / np.sqrt(len(vals)))
        plain.append(np.mean(pl))
    for level in range(3):
        diff = abs(means[level] - means[3])
        bound = 3 * np.hypot(ses[level], ses[3])
        assert diff < bound, f"level {level}: mean {means[level]:.4f} vs {means[3]:.4f}"
    assert plain[0] - plain[3] > 0.1, f"plain grid should lose slope on fine grains: {plain}"


@pytest.mark.parametrize("n", [64, 65])
def test_single_field_path_is_the_gram_path(n):
    """SlopeEnergy(p) (the run-in's every-step path) equals gram([p]) to round-off."""
    labels = Voronoi(100, (0.7, 0.3), 2718).labels(n)
    h = UNIT_DISK.grid(n).h
    pressure, _, _ = pressure_field(labels, [1.0, 10.0], np.pi, h * h)
    energy = SlopeEnergy(n, h, 1.0)
    fast = energy(pressure, labels >= 0)
    slow = energy.gram([pressure], labels >= 0).integrals([1.0])
    for name in ("total", "face_sum", "exterior", "rim_share"):
        a, b = getattr(fast, name), float(getattr(slow, name))
        assert a == pytest.approx(b, rel=1e-12), f"n={n}: {name} {a} vs {b}"


@pytest.mark.parametrize("n, m", [(64, 32), (65, 32), (40, 64)])
def test_resample_labels_is_the_rasterisation_up_to_half_a_pixel(n, m):
    """Resampling a rasterised map differs from rasterising at m only along its boundaries.

    Measured: 4.6 %, 2.5 % and 5.0 % of the face pixels (64 -> 32, 65 -> 32,
    40 -> 64), a boundary strip about half a pixel of the finer grid wide, for
    100 seeds.
    """
    geometry = Voronoi(100, (0.7, 0.3), 2718)
    resampled = resample_labels(geometry.labels(n), m)
    direct = geometry.labels(m)
    face = UNIT_DISK.grid(m).mask
    assert np.array_equal(resampled >= 0, face), "face of the new grid"
    differ = np.mean(resampled[face] != direct[face])
    assert differ < 0.08, f"{differ:.1%} of the pixels differ from the rasterisation"


def test_map_ladder_without_geometry():
    """The error of a pixel map's corrected rms slope from its own resampled ladder.

    Measured against 1024^2 rasterisations (docs/benchmarks.md, "Run-in history"):
    the estimate is 0.13 to 127 times the error; for this map at n = 256 it is 1.09
    times (0.00187 against 0.00172, grad_f0 units; before the coarse box carried its
    blocks' first moments, 0.00248 against 0.00182).
    """
    geometry = Voronoi(400, (0.7, 0.3), 2029)
    est = estimate_map_rms_slope(geometry.labels(256), [1.0, 10.0], np.pi, 1.0, 1.0)
    assert est.grids == (64, 128, 256), f"grids {est.grids} (mean chord 23.7 pixels)"
    assert est.error / G0 == pytest.approx(0.00187, rel=0.05), f"error {est.error / G0}"
    assert mean_chord(geometry.labels(256)) == pytest.approx(23.66, rel=1e-3), "mean chord"
    assert mean_chord(Homogeneous().labels(32)) == np.inf, "one phase has no boundary"
    coarse = estimate_map_rms_slope(geometry.labels(64), [1.0, 10.0], np.pi, 1.0, 1.0)
    assert coarse.grids == (48, 64), f"n = 64: the coarsest admitted multiple of 8, {coarse.grids}"


@pytest.mark.parametrize("shape", [(24, 24), (23, 30)])
def test_box_gradient_kernels_are_the_pixel_integral_gradient(shape):
    # The kernels come from one lattice of pixel corners; the closed form of
    # steady.halfspace evaluates four corners per offset.  Same sums, other
    # rounding (and an FFT round trip here): measured 8e-16 of the largest entry
    # in double precision; the spectra are kept in single precision, which
    # leaves 1.2e-7 and 9.2e-8 (float32's epsilon is 6e-8 of each spectral entry).
    energy = SlopeEnergy(shape, 2e-4, 1.3e6)
    box = energy._fine
    h = energy.h
    assert box.scale == 1.0 / (np.pi * energy.E_star), "the factor applied to the output"
    ox, oy = (np.arange(l0 - a + 1, l0 + b) for a, l0, b in zip(box.ns, box.lo, box.m,
                                                              strict=True))
    ix, iy = np.mod(ox, box.size[0]), np.mod(oy, box.size[1])
    for spectrum, kernel in ((box.gx_q, pixel_integral_gradient(ox * h, oy * h, h)),
                             (box.gy_q, pixel_integral_gradient(oy * h, ox * h, h).T)):
        got = scipy.fft.irfft2(spectrum, s=box.size)[np.ix_(ix, iy)]
        error = np.max(np.abs(got - kernel)) / np.max(np.abs(kernel))
        assert spectrum.dtype == np.complex64, f"{shape}: spectrum kept as {spectrum.dtype}"
        assert error < 3e-7, f"{shape}: kernel differs by {error:.2g} of its largest entry"


def _disk_pressures(n):
    """Flat punch, Hertz and a two-phase Voronoi pressure on the unit disk's grid n."""
    grid = UNIT_DISK.grid(n)
    r, _ = grid.polar()
    voronoi, _, _ = pressure_field(Voronoi(100, (0.7, 0.3), 2718).labels(n), [1.0, 10.0],
                                   np.pi, grid.h**2)
    fields = {"flat punch": reference.flat_punch_pressure(r, 1.0, 1.0),
              "Hertz": np.sqrt(np.clip(1.0 - r**2, 0.0, None)), "Voronoi": voronoi}
    return grid, {k: np.where(grid.mask, p, 0.0) for k, p in fields.items()}


@pytest.mark.parametrize("n", [127, 128])
def test_single_precision_is_double_to_a_few_1e7(n):
    """Transforms in single precision: every integral within a few 1e-7 of double precision.

    Measured at n = 63 .. 256 (flat punch, Hertz, Voronoi): at most 1.9e-7
    (face_sum), 9.7e-8 (exterior and corrected), 4.9e-8 (rms_slope); on
    run-in pressures of the shipped Voronoi scene up to n = 1024, up to
    3.4e-7 (corrected, the flat punch at s = 0) and 1.7e-7 (rms_slope;
    docs/benchmarks.md).  ``total`` and the jump sums involve no transform:
    equal to round-off.
    """
    grid, fields = _disk_pressures(n)
    double = SlopeEnergy(n, grid.h, 1.0)
    single = double.in_precision("single")
    assert single._fine is double._fine, "the two share their spectra"
    for name, p in fields.items():
        a, b = double(p, grid.mask), single(p, grid.mask)
        for key, tol in (("face_sum", 5e-7), ("exterior", 3e-7), ("corrected", 3e-7),
                         ("rms_slope", 1.5e-7), ("total", 1e-15), ("rim_share", 1e-14)):
            x, y = float(getattr(a, key)), float(getattr(b, key))
            assert abs(y / x - 1) < tol, f"n={n} {name}: {key} {y} vs {x} ({y / x - 1:.1e})"
        assert b.face_sum != a.face_sum, f"n={n} {name}: the single path was not taken"


@pytest.mark.parametrize("n", [255, 256])
def test_single_precision_homogeneous_face_matches_continuum(n):
    """Eq. 10 face in single precision: the closed form as closely as double (within 1e-3)."""
    labels = Homogeneous().labels(n)
    h = Circle(1.0).grid(n).h
    pressure, _, _ = pressure_field(labels, [1.0], np.pi, h * h)
    energy = SlopeEnergy(n, h, 1.0, precision="single")
    double = float(energy.in_precision("double")(pressure, labels >= 0).rms_slope)
    single = float(energy(pressure, labels >= 0).rms_slope)
    exact = reference.disk_normalised_rms_slope()
    assert abs(single / G0 - exact) < 1e-3, f"n={n}: single {single / G0} vs {exact}"
    assert abs(single / double - 1) < 1e-7, f"n={n}: single {single} vs double {double}"


def test_double_precision_is_the_default_path():
    """Default and explicit double precision give the same numbers, bit for bit."""
    grid, fields = _disk_pressures(64)
    p = fields["Voronoi"]
    default = SlopeEnergy(64, grid.h, 1.0)(p, grid.mask)
    double = SlopeEnergy(64, grid.h, 1.0, precision="single").in_precision("double")(p, grid.mask)
    assert default == double, f"{default} vs {double}"


def test_bad_precision_is_refused():
    with pytest.raises(ValueError, match="precision must be one of 'double', 'single', got 'half'"):
        SlopeEnergy(16, 0.1, 1.0, precision="half")
    energy = SlopeEnergy(16, 0.1, 1.0)
    with pytest.raises(ValueError, match="got 'float32'"):
        energy.in_precision("float32")
    assert energy.precision == "double", "a refused precision leaves it as it was"


@pytest.mark.parametrize("n", [40, 41])
def test_jump_sums_are_the_edge_jumps(n):
    """The single path's sums of squared jumps are edge_jumps' in another order (measured 2e-15)."""
    from steady.rms_slope import _jump_sums

    grid, fields = _disk_pressures(n)
    for name, p in fields.items():
        want, got = edge_jumps(p, grid.mask), _jump_sums(p, grid.mask)
        assert got == pytest.approx(want, rel=1e-13), f"n={n} {name}: {got} vs {want}"
