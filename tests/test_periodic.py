"""The periodic cell: its operator against closed forms, its contact, steady face and run-in.

Tolerances are the measured errors with a margin (each test says what was measured):
the operator integrates each pixel exactly, so the closed forms of a pressure constant on
pixels are met to round-off and the alias sum's accuracy; the contact of a wavy face is
limited by the grid.
"""

import math

import numpy as np
import pytest
from conftest import GEOMETRIES, K1, RODS, one_error_line, problem, run_cli, scene_text

import steady.cli.solve as steady_cli
import transient.__main__ as transient_cli
from steady.counterbody import Counterbody
from steady.fit import FaceBasis
from steady.load_programme import LoadProgramme
from steady.outline import OUTLINES, Circle, PeriodicCell, outline_from_table
from steady.periodic import PeriodicHalfSpace
from steady.phases import Homogeneous, Voronoi
from steady.problem import FacePhases, Problem
from steady.sliding import PinOnDisk
from steady.solution import solve
from steady.wear import PowerLaw
from transient.comparison import compare_with_steady
from transient.contact import solve_contact
from transient.output import read_run
from transient.preconditioners import PRECONDITIONERS
from transient.problem import WearProblem
from transient.runin import RunOptions, run_in

E_STAR = 1.3e6
CELL = PeriodicCell(8e-3, 8e-3)


def _brute_symbol(shape, h, cutoff, gradient=False, factor=None):
    """The alias sum of 2 c / |Q| s(Qx) s(Qy) (times Qx) over |m|, |l| <= cutoff, E* = 1."""
    nx, ny = shape
    qx = 2 * np.pi * np.fft.fftfreq(nx, d=h)
    qy = 2 * np.pi * np.fft.rfftfreq(ny, d=h)
    m = np.arange(-cutoff, cutoff + 1)
    # The boundary aliases at half weight: the alternating series' first end correction.
    w = np.where(np.abs(m) == cutoff, 0.5, 1.0)
    Qx = qx[:, None] + 2 * np.pi * m[None, :] / h
    Qy = qy[:, None] + 2 * np.pi * m[None, :] / h
    sx = np.sinc(Qx * h / (2 * np.pi)) * w
    sy = np.sinc(Qy * h / (2 * np.pi)) * w
    Q = np.hypot(Qx[:, None, :, None], Qy[None, :, None, :])
    c = 1.0 if factor is None else factor(np.where(Q > 0, Q, 1.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        term = np.where(Q > 0, 2.0 * c / Q, 0.0) * sx[:, None, :, None] * sy[None, :, None, :]
    if gradient:
        term = term * Qx[:, None, :, None]
    out = term.sum(axis=(2, 3))
    out[0, 0] = 0.0
    return out


@pytest.mark.parametrize("shape", [(12, 12), (11, 14)])
def test_symbol_is_the_alias_sum(shape):
    """The Ewald-type sum against the brute-force alias sum, extrapolated in its cut-off.

    The brute sum's error falls as cutoff^-4 (displacement) and cutoff^-2 (gradient);
    extrapolated from cut-offs 32 and 64 the two agree to 3e-12 and 1.1e-8 of the largest
    value (to 4e-14 and 6e-10 from 64 and 128), the brute sum's own error: bounds 1e-11
    and 3e-8.
    """
    h = 1e-4
    hs = PeriodicHalfSpace(shape, h, 1.0)
    for gradient, order, tol in ((False, 4, 1e-11), (True, 2, 3e-8)):
        coarse, fine = (_brute_symbol(shape, h, c, gradient) for c in (32, 64))
        reference = fine + (fine - coarse) / (2**order - 1)
        ours = (hs._gradient_q[0] if gradient else hs.influence_symbol).copy()
        ours[0, 0] = 0.0  # the arbitrary mean's S_0, no alias sum
        error = np.abs(ours - reference).max() / np.abs(reference).max()
        what = "gradient" if gradient else "displacement"
        assert error < tol, f"{what} symbol off by {error:.2e}"


def test_compliance_factor_enters_each_alias():
    """A factor ``c(|q|) = 1 + exp(-|q| H)`` (a layer-like correction) inside the alias sum.

    Against the brute-force sum of ``2 c / |Q| s s`` (cut-offs 32 and 64, extrapolated):
    measured 3e-12 of the largest value, the brute sum's error (as without a factor);
    bound 1e-11; the gradient's as without a factor (bound 3e-8).  ``c = 1`` given as a
    callable is the half-space to round-off; a factor that does not tend to 1 is refused.
    """
    shape, h, depth = (12, 13), 1e-4, 2e-4

    def layer(q):
        return 1.0 + np.exp(-q * depth)

    hs = PeriodicHalfSpace(shape, h, 1.0, compliance_factor=layer)
    coarse, fine = (_brute_symbol(shape, h, c, factor=layer) for c in (32, 64))
    reference = fine + (fine - coarse) / 15
    ours = hs.influence_symbol.copy()
    ours[0, 0] = 0.0  # the arbitrary mean's S_0, no alias sum
    error = np.abs(ours - reference).max() / np.abs(reference).max()
    assert error < 1e-11, f"symbol with a compliance factor off by {error:.2e}"
    coarse, fine = (_brute_symbol(shape, h, c, True, layer) for c in (32, 64))
    reference = fine + (fine - coarse) / 3
    error = np.abs(hs._gradient_q[0] - reference).max() / np.abs(reference).max()
    assert error < 3e-8, f"gradient symbol with a compliance factor off by {error:.2e}"
    plain = PeriodicHalfSpace(shape, h, 1.0)
    unit = PeriodicHalfSpace(shape, h, 1.0, compliance_factor=np.ones_like)
    assert np.allclose(unit.influence_symbol, plain.influence_symbol, rtol=1e-14, atol=0), \
        "c = 1 must be the half-space"
    rng = np.random.default_rng(3313)
    p = rng.uniform(size=shape)
    assert unit.mean_square_slope(p) == pytest.approx(plain.mean_square_slope(p), rel=1e-12)
    with pytest.raises(ValueError, match="must tend to 1"):
        PeriodicHalfSpace(shape, h, 1.0, compliance_factor=lambda q: 2.0 + 0 * q)


@pytest.mark.parametrize("n", [32, 33])
def test_stripes_give_the_square_wave_series(n):
    """Two phases in stripes: the displacement is the square wave's Fourier series, exactly.

    Pressure ``p0 + dp`` on ``0 < x < W / 2`` (whole pixels of an even n; for odd n the
    stripe is 16 of 33 pixels, a general two-level wave), ``p0`` on the rest: the continuum
    displacement ``sum_k 2 P_k cos(k q0 x + phi_k) / (E* k q0)`` at the pixel centres.  The
    series summed to k = 2e6: measured agreement 7e-13 of the relief (n = 32), the series'
    truncation (7e-11 at k = 2e5); bound 1e-11.
    """
    width = 4e-3
    hs = PeriodicHalfSpace((n, 8), width / n, E_STAR)
    h = width / n
    stripe = n // 2
    p0, dp = 2e4, 5e4
    pressure = np.full((n, 8), p0)
    pressure[:stripe] += dp
    x = (np.arange(n) + 0.5) * h
    # Fourier coefficients of the indicator of [0, stripe h) of period W.
    k = np.arange(1, 2_000_001)
    q = 2 * np.pi * k / width
    c = dp * (np.exp(-1j * q * stripe * h) - 1) / (-1j * q * width)  # complex amplitude
    u = np.zeros(n)
    for block in range(0, k.size, 50_000):
        sl = slice(block, block + 50_000)
        u += np.real(2 * (c[sl, None] * 2 / (E_STAR * q[sl, None]))
                     * np.exp(1j * q[sl, None] * x[None, :])).sum(axis=0)
    ours = hs.displacement(pressure)[:, 3]
    amplitude = np.ptp(u)
    error = np.abs((ours - ours.mean()) - (u - u.mean())).max() / amplitude
    assert error < 1e-11, f"stripe cell off the square-wave series by {error:.2e} of the relief"


@pytest.mark.parametrize("n", [64, 63])
def test_cosine_pressure(n):
    """``P cos(q x)`` at the pixel centres: displacement ``2 P / (E* q)`` up to the pixels.

    Constant on pixels, the cosine's fundamental is ``P sinc(q h / 2 pi)`` and the symbol
    carries it once more, less its aliases: relative deviation from ``2 P / (E* q)`` about
    ``(q h)^2 / 24`` for the first mode (measured 3.9e-4 at n = 64, 4.0e-4 at 63); bound 1e-3.
    The zero-mean displacement is exactly the cosine (no other mode).
    """
    width, P = 5e-3, 1e4
    hs = PeriodicHalfSpace((n, n), width / n, E_STAR)
    x = (np.arange(n) + 0.5) * width / n
    q = 2 * np.pi / width
    u = hs.displacement(np.repeat((P * np.cos(q * x))[:, None], n, axis=1))
    amplitude = 2 * np.sum(u[:, 0] * np.cos(q * x)) / n
    assert abs(amplitude / (2 * P / (E_STAR * q)) - 1) < 1e-3, "cosine amplitude off 2P/(E* q)"
    shape_error = np.abs(u[:, 0] - amplitude * np.cos(q * x)).max() / amplitude
    assert shape_error < 1e-12, f"the displacement of a cosine is not a cosine ({shape_error:.1e})"
    assert abs(u.mean()) < 1e-15 * np.abs(u).max() * n * n, "the displacement's mean is not 0"


@pytest.mark.parametrize("n", [128, 129])
@pytest.mark.parametrize("load", [0.2, 0.5])
def test_wavy_face_partial_contact_is_westergaards(n, load):
    """A 1-d wavy face ``h (1 - cos(2 pi x / lambda))`` pressed flat: Westergaard's contact.

    Half-width ``a``: ``sin^2(pi a / lambda) = pbar / p*``, ``p* = pi E* h / lambda``
    (Westergaard 1939; Johnson, Int. J. Solids Struct. 32 (1995) 423, eq. 4).  The
    pixels in contact span ``2 a`` to within one pixel (measured: within 0.5); the
    load is met to round-off.
    """
    wavelength, amplitude = 4e-3, 2e-6
    grid = PeriodicCell(wavelength, wavelength / 8).grid(n if n % 8 == 0 else 128)
    if n % 8:  # an odd grid: a cell of n x 8 pixels along the wave
        grid = PeriodicCell(wavelength, 8 * wavelength / n).grid(n)
    x = grid.x - grid.x[0] + 0.5 * grid.h
    recession = np.repeat((amplitude * (1 - np.cos(2 * np.pi * x / wavelength)))[:, None],
                          grid.shape[1], axis=1)
    p_star = np.pi * E_STAR * amplitude / wavelength
    force = load * p_star * wavelength * grid.shape[1] * grid.h
    hs = Counterbody(E_STAR).operator(grid)
    res = solve_contact(hs, grid.mask, recession, force, rtol=1e-10)
    assert res.success, res.message
    assert res.pressure.sum() * grid.h**2 == pytest.approx(force, rel=1e-12), "load not met"
    width = np.count_nonzero(res.pressure[:, 0] > 0) * grid.h
    a = wavelength / np.pi * math.asin(math.sqrt(load))
    assert abs(width - 2 * a) <= grid.h, \
        f"contact width {width / grid.h:.1f} pixels, Westergaard {2 * a / grid.h:.2f}"
    assert 0 < res.contact_fraction < 1, "not a partial contact"


def test_outline_contract():
    """Whole-cell face, exact area, square pixels tiling the cell; every outline says periodic."""
    cell = outline_from_table({"shape": "periodic", "width": 6e-3, "length": 2e-3})
    grid = cell.grid(96)
    assert grid.shape == (96, 32) and grid.mask.all(), "the grid must tile the cell"
    assert grid.face_area == pytest.approx(cell.area, rel=1e-14) == 12e-6, "cell area"
    assert grid.h == pytest.approx(6e-3 / 96, rel=1e-15), "pixels must be square"
    assert cell.periodic and cell.exact_rim_distance(0.0, 0.0) is None, "a cell has no rim"
    for kind in OUTLINES:
        assert OUTLINES[kind].periodic is (kind == "periodic"), f"{kind}: periodic attribute"
    assert type(Counterbody(E_STAR).operator(grid)) is PeriodicHalfSpace, "the seam's choice"
    assert type(Counterbody(E_STAR).operator(Circle(4e-3).grid(32))).__name__ == "HalfSpace"


def test_refusals():
    """Sides that are not whole pixels, non-uniform sliding and the fit refused with the reason."""
    with pytest.raises(ValueError, match=r"not whole pixels at n = 64.*width 0.004 m and "
                                         r"length 0.0031 m"):
        PeriodicCell(4e-3, 3.1e-3).grid(64)
    with pytest.raises(ValueError, match="periodic cell slides in translation only"):
        p = problem(GEOMETRIES["voronoi"], PowerLaw([K1, 10 * K1]), n=32, outline=CELL)
        type(p)(p.phases, p.wear, p.normal_force, p.E_star, sliding=PinOnDisk(0.05))
    p = problem(GEOMETRIES["voronoi"], PowerLaw([K1, 10 * K1]), n=32, outline=CELL)
    with pytest.raises(ValueError, match="the wear-ratio fit needs a face with a rim"):
        FaceBasis(p.phases, E_STAR)


@pytest.mark.parametrize("geometry", ["homogeneous", "voronoi", "rods"])
def test_steady_face_and_its_exact_slope(geometry):
    """Eq. 7 on the cell; the face's mean the operator's ``S_0 pbar``; Parseval's rms slope.

    ``2 std(p) / E*`` for the half-space, to round-off (its ladder measures only the
    rasterisation of the map); for the homogeneous cell a flat face.
    """
    geometry = {"rods": RODS}.get(geometry, GEOMETRIES[geometry])
    wear = PowerLaw([K1, 10 * K1][:geometry.n_phases])
    p = problem(geometry, wear, n=64, outline=CELL)
    result = solve(p)
    pressure = result.pressure
    assert np.sum(pressure) * CELL.grid(64).pixel_area == pytest.approx(10.0, rel=1e-12)
    s0 = p.halfspace.influence_symbol[0, 0]
    assert s0 == p.halfspace.influence_symbol.max() > 0, "S_0: the longest wave's compliance"
    assert np.nanmean(result.face) == pytest.approx(s0 * pressure.mean(), rel=1e-12)
    relief = result.face - np.nanmean(result.face)
    exact = 2 * np.std(pressure) / E_STAR
    if geometry.n_phases == 1:
        assert np.nanmax(np.abs(relief)) < 1e-12 * np.nanmean(result.face)
        assert result.rms_slope == 0.0 and result.rms_height == 0.0, "a flat cell"
    else:
        assert result.rms_slope == pytest.approx(exact, rel=1e-12), "not Parseval's slope"
        assert math.isfinite(result.rms_slope_error), "no error bar"
        assert result.rms_height == pytest.approx(np.sqrt(np.nanmean(relief**2)), rel=1e-9)


def _run(geometry, ratios, *, exponent=1.0, programme=None):
    wear = PowerLaw([K1 * r for r in ratios], exponent=exponent)
    wp = WearProblem(problem(geometry, wear, n=32, outline=CELL), load_programme=programme)
    return wp, run_in(wp, np.zeros(wp.shape), RunOptions(tol=1e-3))


@pytest.mark.parametrize("case", ["voronoi", "rods", "power_law", "programme"])
def test_run_in_reaches_the_steady_face(case):
    """From flat to the closed-form face on the periodic operator.

    Face error (max of the difference, mean removed, over the steady relief) measured
    1.1e-8 .. 2.7e-8, the final jump's error of order s*/ds; bound 1e-7.  Pressures and
    the rms slope to round-off (1e-12).  Under a programme, against the closed form at
    its last force.
    """
    programme = LoadProgramme(10.0, ((2e4, 15.0),)) if case == "programme" else None
    geometry = RODS if case == "rods" else GEOMETRIES["voronoi"]
    exponent = 2.0 if case == "power_law" else 1.0
    wp, result = _run(geometry, (1.0, 10.0), exponent=exponent, programme=programme)
    assert result.status == "steady", result.message
    force = 15.0 if programme else 10.0
    steady_problem = WearProblem(problem(geometry, wp.wear, n=32, outline=CELL, force=force))
    cmp = compare_with_steady(result, steady_problem.solve_steady(), steady_problem)
    assert cmp.face_error < 1e-7, f"{case}: face error {cmp.face_error:.2e}"
    assert cmp.phase_pressure_error < 1e-12, f"{case}: pressures {cmp.phase_pressure_error:.2e}"
    assert cmp.rms_slope == pytest.approx(cmp.steady_rms_slope, rel=1e-12), cmp.summary()
    assert np.all(np.isnan(result.history["rim_worn_depth"])), "a cell has no rim"


def test_homogeneous_cell_stays_flat():
    """A homogeneous cell wears uniformly: no relief, no slope, no deviation to measure."""
    wp = WearProblem(problem(Homogeneous(), PowerLaw([K1]), n=32, outline=CELL))
    result = run_in(wp, np.zeros(wp.shape), RunOptions(tol=1e-3))
    assert result.status == "steady", result.message
    slopes = np.asarray(result.history["rms_slope"])
    assert np.all(slopes[1:] < 1e-12), f"a flat cell tilts: rms slope up to {slopes.max():.2e}"
    assert np.all(np.isnan(result.history["face_deviation"])), "no steady relief to compare"


def test_partial_contact_history_does_not_depend_on_the_cells_origin():
    """The phase map and a wavy initial face rolled together: the same run-in history.

    The wave ``(1 - cos 2 pi x / W)`` of 1 mm lifts 59 % of the cell off at the start, so the
    history's figures take differences of the gap across the cell's edges.  Rolled by (5, 11)
    pixels, the slopes, heights and distances moved by at most 2.1e-9 of their largest values
    and the step's slope error by 2.3e-8 (the contact solves' round-off through the step
    control); with one-sided differences at the edges the rms slope moved by 1.0e-2.  Not
    compared: ``rms_slope_error``, whose map error resamples the label map on coarser grids,
    which take other pixels after a roll.
    """
    wear = PowerLaw([K1, 10 * K1])
    grid = CELL.grid(32)
    labels = GEOMETRIES["voronoi"].labels(grid)
    wave = 1e-3 * (1 - np.cos(2 * np.pi * grid.x / CELL.width))[:, None] * np.ones(grid.shape)
    histories = []
    for shift in [(0, 0), (5, 11)]:
        wp = WearProblem(problem(np.roll(labels, shift, (0, 1)), wear, outline=CELL))
        result = run_in(wp, np.roll(wave, shift, (0, 1)), RunOptions(tol=1e-3))
        assert result.status == "steady", result.message
        histories.append(result.history)
    first, rolled = histories
    assert 0 < first["contact_fraction"][0] < 0.5, "not a partial contact at the start"
    assert len(first["distance"]) == len(rolled["distance"]), "another number of steps"
    for name in ("rms_slope", "rms_slope_plain", "rms_height", "distance", "contact_fraction"):
        a, b = np.asarray(first[name]), np.asarray(rolled[name])
        error = np.max(np.abs(a - b)) / np.max(np.abs(a))
        assert error < 1e-8, f"{name} moved by {error:.1e} with the cell's origin"
    a, b = np.asarray(first["rms_slope_step_error"]), np.asarray(rolled["rms_slope_step_error"])
    error = np.max(np.abs(a - b)) / np.max(np.abs(a))
    assert error < 1e-6, f"the step's slope error moved by {error:.1e}"


def _scene(tmp_path, load=None, extra=""):
    """A Voronoi cell of 8 x 4 mm under 5 N (``load``: further ``[load]`` keys), written."""
    path = tmp_path / "cell.toml"
    path.write_text(scene_text(
        "runin", punch=dict(shape="periodic", width=0.008, length=0.004), normal_force=5.0,
        load=load or {}, n=48, n_seeds=60, seed=3301, transient=None, extra=extra))
    return path


def test_steady_command_on_a_cell(tmp_path, capsys):
    """A scene of a periodic cell through the steady command; sliding refused with its reason."""
    status, out, err = run_cli(steady_cli, [_scene(tmp_path), "-o", tmp_path / "s.h5"], capsys)
    assert status == 0, err
    assert "periodic face (width 8 mm, length 4 mm), n = 48 (48 x 24 pixels)" in out, out
    scene = _scene(tmp_path, extra='[sliding]\nkind = "pin_on_disk"\ntrack_radius = 0.05')
    status, _, err = run_cli(steady_cli, [scene, "-o", tmp_path / "p.h5"], capsys)
    assert status != 0 and "a periodic cell slides in translation only" in one_error_line(err)


def test_run_in_command_with_depth_layers_and_a_wavy_face(tmp_path, capsys):
    """A coating over a Voronoi cell, from a wavy face read from a file, under a programme.

    The wave ``0.4 mm (1 - cos 2 pi x / W)`` repeats with the cell; its start is in partial
    contact on the cell (two thirds of it touch: a periodic face's partial contact); the
    coating is worn through before the end depth.
    """
    grid = PeriodicCell(8e-3, 4e-3).grid(48)
    wave = 4e-4 * (1 - np.cos(2 * np.pi * grid.x / 8e-3))[:, None] * np.ones(grid.shape)
    np.save(tmp_path / "wave.npy", wave)
    extra = """
[depth]
kind = "layers"
[[depth.layers]]
thickness = 1e-4
phase = 0
[initial_face]
kind = "file"
path = "wave.npy"
[transient]
tol = 1e-3
end_depth = 6e-4
"""
    scene = _scene(tmp_path, load=dict(programme=((2e3, 7.0),)), extra=extra)
    status, out, err = run_cli(transient_cli, [scene, "-o", tmp_path / "r.h5"], capsys)
    assert status == 0, err
    assert "periodic face" in out and "nan" not in out and "+- inf" not in out, out
    contact = read_run(tmp_path / "r.h5")[0].history["contact_fraction"][0]
    assert 0 < contact < 1, f"not a partial contact at the start: {contact}"


@pytest.mark.parametrize("kind, keys", [("crowned", "sphere_radius = 0.05"),
                                        ("tilted", "angle = 1e-3")])
def test_run_in_command_refuses_a_face_that_does_not_repeat(tmp_path, capsys, kind, keys):
    """A crowned or tilted face on a cell: one error line naming the kind and the shape."""
    scene = _scene(tmp_path, extra=f"[initial_face]\nkind = \"{kind}\"\n{keys}")
    status, _, err = run_cli(transient_cli, [scene, "-o", tmp_path / "r.h5"], capsys)
    line = one_error_line(err)
    assert status != 0 and f"initial face kind '{kind}' on [punch] shape = \"periodic\"" in line
    assert str(scene) in line and "seam" in line, line
    assert not (tmp_path / "r.h5").exists(), "nothing written"


def test_periodic_voronoi_repeats():
    """On a cell the tessellation wraps: each pixel takes the nearest image of a seed.

    No seam at the cell's sides: grains run across them.
    """
    cell = PeriodicCell(2.0, 2.0)
    grid = cell.grid(64)
    labels = Voronoi(40, (0.5, 0.5), 3307).labels(grid)
    # Grains cross the sides: some label runs wrap around both axes.
    assert np.any(labels[0] == labels[-1]) and np.any(labels[:, 0] == labels[:, -1])
    points, phases = Voronoi(40, (0.5, 0.5), 3307).seeds(cell)
    x, y = np.meshgrid(grid.x, grid.y, indexing="ij")
    d = np.full(grid.shape, np.inf)
    out = np.empty(grid.shape, dtype=int)
    for (px, py), phase in zip(points, phases, strict=True):
        for sx in (-2.0, 0.0, 2.0):
            for sy in (-2.0, 0.0, 2.0):
                r = np.hypot(x - px - sx, y - py - sy)
                closer = r < d
                d[closer], out[closer] = r[closer], phase
    assert np.array_equal(labels, out), "the cell's map is not the nearest image seed's"


@pytest.mark.parametrize("name", sorted(PRECONDITIONERS))
def test_every_preconditioner_solves_a_cell(name):
    """Each preconditioner on the periodic operator: the same partial contact, load met.

    A wavy face at pbar = 0.3 p* with a non-uniform shift (a wear step of two phases):
    pressures agree with the ``"none"`` solve to 1e-6 of their peak (rtol 1e-10; measured
    below 1e-8).
    """
    grid = PeriodicCell(4e-3, 2e-3).grid(64)
    x = grid.x[:, None] + 0 * grid.y[None, :]
    recession = 2e-6 * (1 - np.cos(2 * np.pi * x / 4e-3))
    shift = np.where(grid.y[None, :] + 0 * x > 0, 1e-11, 3e-11)
    force = 0.3 * np.pi * E_STAR * 2e-6 / 4e-3 * 8e-6
    hs = Counterbody(E_STAR).operator(grid)
    kw = dict(shift=shift, rtol=1e-10)
    reference = solve_contact(hs, grid.mask, recession, force, preconditioner="none", **kw)
    res = solve_contact(hs, grid.mask, recession, force, preconditioner=name, **kw)
    assert res.success, f"{name}: {res.message}"
    assert res.pressure.sum() * grid.h**2 == pytest.approx(force, rel=1e-12), f"{name}: load"
    assert 0 < res.contact_fraction < 1, f"{name}: not a partial contact"
    error = np.abs(res.pressure - reference.pressure).max() / reference.pressure.max()
    assert error < 1e-6, f"{name}: pressure off the plain solve by {error:.1e}"


def _layered_stripes(n, thickness, poisson):
    """A cell of two phases in stripes across x (whole pixels) on a layer."""
    grid = CELL.grid(n)
    labels = np.zeros(grid.shape, dtype=np.int8)
    labels[n // 2:] = 1
    return Problem(FacePhases(grid, labels, 2), PowerLaw([K1, 10 * K1]), 10.0, E_STAR,
                   thickness=thickness, poisson=poisson)


@pytest.mark.parametrize("thickness, poisson", [(1e-3, 0.5), (4e-4, 0.3), (1e-2, 0.5)])
def test_layered_cell_stripes_give_the_layer_series(thickness, poisson):
    """A layered cell: each mode's compliance times the layer's factor, and the exact slope.

    The stripes' pressure is a two-level square wave whose harmonics ``k q0`` the layer
    scales by ``phi(k q0 t)``: the mean-square slope is the half-space's, ``(2 std p /
    E*)^2``, less ``sum_k 2 |c_k|^2 (2 / E*)^2 (1 - phi_k^2)``, a series that converges
    exponentially (summed to k = 2e4).  Measured agreement of the steady solve's rms slope
    2e-16 .. 1.6e-15 relative; bound 1e-12 (its slope is 0.41, 0.32 and 0.99997 of the
    half-space cell's).  The layer's relief is smaller than the
    half-space's, and its face is the layered operator's displacement.
    """
    p = _layered_stripes(32, thickness, poisson)
    assert type(p.halfspace) is PeriodicHalfSpace, "a cell's operator on a layer"
    result = solve(p)
    pressure = result.pressure[:, 0]
    dp = pressure[0] - pressure[-1]
    width, n = CELL.width, 32
    k = np.arange(1, 20_001)
    q = 2 * np.pi * k / width
    c = dp * (np.exp(-1j * q * width / 2) - 1) / (-1j * q * width)
    phi = p.counterbody.fourier_factor(q)
    half_space = (2 * np.std(result.pressure) / E_STAR) ** 2
    exact = half_space - np.sum(2 * np.abs(c) ** 2 * (2 / E_STAR) ** 2 * (1 - phi**2))
    assert result.rms_slope == pytest.approx(math.sqrt(exact), rel=1e-12), \
        f"layered cell's rms slope {result.rms_slope!r} against the series {math.sqrt(exact)!r}"
    bare = solve(_layered_stripes(n, None, None))
    assert result.rms_slope < bare.rms_slope, "a layer on a rigid flat is stiffer"
    face = result.face - np.nanmean(result.face)
    u = p.halfspace.displacement(result.pressure)
    assert np.allclose(face, u - u.mean(), rtol=0, atol=1e-12 * np.ptp(face)), \
        "the face is not the layered displacement"


def test_run_in_on_a_layered_cell_reaches_its_closed_form():
    """From flat to the layered cell's closed form.

    Face error measured 6.7e-8 of the relief (n = 32, tol 1e-3, t = 1 mm, nu = 0.5), the
    final jump's, as on the half-space cell; bound 2e-7.
    """
    wp = WearProblem(_layered_stripes(32, 1e-3, 0.5))
    result = run_in(wp, np.zeros(wp.shape), RunOptions(tol=1e-3))
    assert result.status == "steady", result.message
    cmp = compare_with_steady(result, wp.solve_steady(), wp)
    assert cmp.face_error < 2e-7, f"face error {cmp.face_error:.2e}"
    assert cmp.rms_slope == pytest.approx(cmp.steady_rms_slope, rel=1e-12), cmp.summary()


@pytest.mark.parametrize("thickness, poisson, bound", [(2e-3, 0.5, 1e-6), (1e-3, 0.3, 5e-10),
                                                       (4e-4, 0.5, 3e-8)])
def test_finite_punch_on_a_layer_is_a_large_cell_with_zero_pressure_around(thickness, poisson,
                                                                           bound):
    """The layer's real-space coefficients against the layered cell's modes.

    A disk of radius 4 mm (n = 32) carrying a paraboloid of pressure, alone on the layer
    (zero padded) and in the middle of a periodic cell five times wider with zero pressure
    around it: the layer's response decays over a few thicknesses, so the images do not
    interact.  Face displacements, mean removed (a cell's is arbitrary), measured apart by
    2.1e-7 (t = a / 2, the images 16 thicknesses apart; 1.0e-4 in a cell three times wider),
    7.3e-11 and 5.8e-9 (t = 0.4 mm, the real-space quadrature's floor) of their relief.
    """
    counterbody = Counterbody(E_STAR, thickness, poisson)
    grid = Circle(4e-3).grid(32)
    r2 = (grid.x[:, None] ** 2 + grid.y[None, :] ** 2) / 4e-3**2
    pressure = np.where(grid.mask, 1e4 * (1.2 - r2), 0.0)
    alone = counterbody.operator(grid).displacement(pressure)
    side = 5 * 32
    cell = PeriodicCell(side * grid.h, side * grid.h).grid(side)
    padded = np.zeros(cell.shape)
    start = (side - 32) // 2
    padded[start:start + 32, start:start + 32] = pressure
    among = counterbody.operator(cell).displacement(padded)[start:start + 32, start:start + 32]
    difference = (alone - among)[grid.mask]
    error = np.abs(difference - difference.mean()).max() / np.ptp(alone[grid.mask])
    assert error < bound, f"finite punch against the cell: {error:.2e} of the relief"


@pytest.mark.parametrize("outline", [CELL, Circle(4e-3)], ids=["cell", "punch"])
def test_a_coating_takes_the_map_error_of_the_section_it_wears_down_to(outline):
    """A surface of one phase has no boundary to rasterise: the section below it counts too.

    A coating of phase 0 over a Voronoi section: the history's relative map error is the
    larger of the coating's and of the Voronoi section's own ladders.  On a cell the
    coating's face is flat, slope 0 known exactly (error 0, not an unbounded one).
    """
    from steady.depth import DepthColumns
    from steady.rms_slope import estimate_map_rms_slope
    from transient.history import FaceEstimator

    voronoi = problem(GEOMETRIES["voronoi"], PowerLaw([K1, 10 * K1]), n=48, outline=outline)
    face = voronoi.face_mask
    coat = np.where(face, 0, -1)
    columns = DepthColumns(np.where(face, 1e-5, np.inf)[None],
                           np.stack([coat, np.where(face, voronoi.labels, -1)]), 2)
    coated = Problem(FacePhases(voronoi.grid, coat, 2, columns=columns), voronoi.wear,
                     voronoi.normal_force, voronoi.E_star)
    wear = WearProblem(coated)
    estimator = FaceEstimator(wear, np.zeros(face.shape))

    def relative(section):
        labels, law = section.present_phases()
        e = estimate_map_rms_slope(labels, law, section.normal_force, section.outline,
                                   section.E_star)
        return e.error / e.rms_slope if e.rms_slope > 0 else (0.0 if e.error == 0 else math.inf)

    surface, below = relative(coated), relative(coated.section(1e-5))
    assert math.isfinite(below) and (surface == 0.0) is outline.periodic
    assert estimator.map_error == pytest.approx(max(surface, below), rel=1e-12, abs=1e-15)
    assert math.isfinite(estimator.map_error)
