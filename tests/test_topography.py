"""Faces as SurfaceTopography topographies, and the steady face's power spectrum.

The bridge (:mod:`steady.topography`) hands a face to SurfaceTopography with its size, unit and
mask, on the project's axes (``[i, j]``, ``i`` along x).  What the two compute by the same
definition must agree to rounding: the rms height about the least-squares plane (the library's
``detrend("height")`` then ``Sq``) and the radially averaged power spectral
density (:func:`steady.topography.isotropic_psd` against ``power_spectrum_from_area``, on a
face that fills its box and on a disk with the pixels off the face set to zero).  The rms slope
is the same continuum quantity by two stencils: runin's plain value differentiates the exact
half-space kernel at the pixel centres, SurfaceTopography takes forward differences between
neighbouring pixels, leaving out the face's last pixel of every row and column, where the
slope is largest.  They agree to the grid's error only, measured on the homogeneous disk, whose
limit ``grad_f0`` both approach from below, and on a cosine over the disk, where the difference
of the two stencils is known in closed form.
"""

import pathlib
import re
import sys

import h5py
import numpy as np
import pytest
import xarray as xr
from conftest import GEOMETRIES, K1, OUTLINES, RADIUS, problem, wear_problem
from scipy.special import j1

from steady import solve
from steady.fit_files import read_measured
from steady.outline import Circle
from steady.output import read_result, write_result
from steady.relief import rms_height
from steady.topography import isotropic_psd, to_topography
from transient import RunOptions, run_in

#: Relative agreement of quantities computed by the same definition (rounding of sums over
#: up to 1e4 pixels and of FFTs; measured up to 4e-14).
SAME = 1e-12


@pytest.fixture(scope="module")
def st():
    """The SurfaceTopography package (the extra ``surface``, in the ``test`` extra)."""
    return pytest.importorskip("SurfaceTopography")


def voronoi_face(n, outline=RADIUS):
    """The steady face of the gallery's Voronoi map (k_1/k_0 = 10) on ``outline``."""
    return solve(problem(GEOMETRIES["voronoi"], [K1, 10 * K1], n=n, outline=outline),
                 face_only=True)


@pytest.fixture(scope="module")
def run():
    """A run-in of the gallery's Voronoi punch from flat, with two snapshots."""
    return run_in(wear_problem("voronoi", n=32), np.zeros((32, 32)),
                  RunOptions(tol=1e-3, snapshots_s_star=(0.1, 1.0)))


def relative(a, b):
    return np.max(np.abs(np.asarray(a) / np.asarray(b) - 1.0))


@pytest.mark.parametrize("n", [40, 41])
def test_steady_face_round_trips_with_its_size_unit_and_mask(st, n):
    result = voronoi_face(n)
    topography = result.topography()
    h = result.pixel_size
    assert topography.nb_grid_pts == result.shape, f"grid {topography.nb_grid_pts}"
    assert topography.physical_sizes == (n * h, n * h), f"size {topography.physical_sizes}"
    assert topography.unit == "m" and not topography.is_periodic, "metres, not periodic"
    heights = topography.heights()
    off = np.isnan(result.face)
    assert np.array_equal(np.ma.getmaskarray(heights), off), "undefined exactly off the face"
    assert np.array_equal(heights[~off], result.face[~off]), "heights are the face's"
    x, y = topography.positions()
    grid = result.outline.grid(n)
    assert np.allclose(x[:, 0] + grid.x[0], grid.x, rtol=0, atol=1e-12 * h), "axis 0 is x"
    assert np.allclose(y[0] + grid.y[0], grid.y, rtol=0, atol=1e-12 * h), "axis 1 is y"
    micrometres = topography.to_unit("um")
    assert micrometres.physical_sizes == pytest.approx((1e6 * n * h,) * 2, rel=SAME), "in um"
    assert np.allclose(micrometres.heights()[~off], 1e6 * result.face[~off], rtol=SAME), "um"


def test_axes_of_a_tilted_rectangular_face(st):
    """``heights[i, j]`` at ``x = i dx``, ``y = j dy``: slopes along each axis come back."""
    nx, ny, dx, dy = 7, 12, 1e-4, 2.5e-4
    x, y = np.arange(nx) * dx, np.arange(ny) * dy
    face = 0.03 * x[:, None] - 0.01 * y[None, :]
    face[0, :3] = np.nan
    topography = to_topography(face, (dx, dy))
    assert topography.physical_sizes == (nx * dx, ny * dy), f"{topography.physical_sizes}"
    gx, gy = topography.derivative(1)
    assert np.allclose(gx.compressed(), 0.03) and np.allclose(gy.compressed(), -0.01), \
        "forward differences of the plane: its slopes along x and y"
    assert topography.detrend("height").Sq() < 1e-15, "a plane's relief"


def test_x3p_file_of_a_worn_face_reads_back_as_a_measured_face(st, run, tmp_path):
    """The worn face through SurfaceTopography's x3p file into the wear-ratio fit's reader."""
    run.topography().to_x3p(tmp_path / "worn.x3p")
    measured = read_measured(tmp_path / "worn.x3p")
    face = run.face
    on = np.isfinite(face)
    assert measured.pixel_size == pytest.approx((run.pixel_size,) * 2, rel=SAME), "pixel size"
    assert np.array_equal(np.isfinite(measured.heights), on), "missing exactly off the face"
    assert np.allclose(measured.heights[on], face[on], rtol=SAME, atol=0), "heights in m"


def test_rms_height_is_the_least_squares_planes_in_both(st, run):
    distance = run.history["distance"]
    for k, s in enumerate(run.snapshot_distance):
        at = int(np.argmin(np.abs(distance - s)))
        assert distance[at] == s, f"snapshot {k} at s = {s} m is a point of the history"
        ours = run.history["rms_height"][at]
        theirs = run.topography(snapshot=k).detrend("height").Sq()
        assert relative(theirs, ours) < SAME, f"snapshot {k}: {theirs} m vs {ours} m"
    final = run.topography().detrend("height").Sq()
    ours = rms_height(run.face, run.face_mask, run.pixel_size)
    assert relative(final, ours) < SAME, f"final face: {final} m vs {ours} m"
    steady = voronoi_face(41)
    theirs = steady.topography().detrend("height").Sq()
    assert relative(theirs, steady.rms_height) < SAME, f"steady: {theirs} vs {steady.rms_height}"


@pytest.mark.parametrize("n, height_tol, slope_tol", [(64, 1e-3, 6e-3), (65, 1e-3, 7e-3),
                                                      (128, 3e-4, 1e-3)])
def test_rms_height_and_slope_of_a_cosine_over_the_disk(st, n, height_tol, slope_tol):
    """A face known in closed form: ``A cos(k x)`` over a disk of radius ``a``, NaN off it.

    Continuum values (the mean of ``cos(2 k x)`` over the disk is ``J1(2 k a) / (k a)``, the
    least-squares plane is the mean, ``2 A J1(k a) / (k a)``): rms height ``A (1/2 + J1(2ka)
    / (2ka) - (2 J1(ka) / (ka))^2)^(1/2)``, rms slope ``A k (1/2 - J1(2ka) / (2ka))^(1/2)``.
    runin's rms height and SurfaceTopography's ``Sq`` after ``detrend("height")`` are one
    definition: equal to rounding; both off the continuum value by the staircase rim, measured
    7.4e-4 at n = 64, 6.5e-4 at 65, 1.5e-4 at 128 (wavelength a / 2).  runin's plain rms slope
    (the pixel rms of the exact gradient at the face's pixel centres, as ``rms_slope_plain``)
    and ``rms_gradient`` (forward differences): for a cosine a forward difference is the
    gradient at the midpoint times ``sinc(k h / 2)``, exactly; so they differ by about
    ``(k h)^2 / 24``, measured 4.9e-3 at n = 64, 6.3e-3 at 65, 7.9e-4 at 128.
    """
    a, amplitude = RADIUS, 1e-6
    k = 2 * np.pi / (a / 2)
    grid = Circle(a).grid(n)
    h, mask = grid.h, grid.mask
    face = np.where(mask, amplitude * np.cos(k * grid.x)[:, None] + 0.0 * grid.y, np.nan)
    topography = to_topography(face, h)

    theirs, ours = topography.detrend("height").Sq(), rms_height(face, mask, h)
    assert relative(theirs, ours) < SAME, f"n = {n}: Sq {theirs} m vs rms_height {ours} m"
    exact = amplitude * np.sqrt(0.5 + j1(2 * k * a) / (2 * k * a) - (2 * j1(k * a) / (k * a)) ** 2)
    assert relative(ours, exact) < height_tol, f"n = {n}: rms height {ours} vs {exact} m"

    theirs = topography.rms_gradient()
    gx, gy = topography.derivative(1)
    kept = ~np.ma.getmaskarray(gx * gx + gy * gy)
    midpoint = np.abs(np.sin(k * (grid.x[:-1] + h / 2)))[:, None] + 0.0 * grid.y[:-1]
    sinc = np.sin(k * h / 2) / (k * h / 2)
    forward = amplitude * k * sinc * np.sqrt(np.mean(midpoint[kept] ** 2))
    assert relative(theirs, forward) < SAME, "forward differences of a cosine, exactly"
    plain = amplitude * k * np.sqrt(np.mean((np.sin(k * grid.x)[:, None] + 0.0 * grid.y)[mask]
                                            ** 2))
    assert relative(theirs, plain) < slope_tol, f"n = {n}: rms_gradient {theirs} vs {plain}"
    exact = amplitude * k * np.sqrt(0.5 - j1(2 * k * a) / (2 * k * a))
    assert relative(plain, exact) < height_tol, f"n = {n}: rms slope {plain} vs {exact}"


def test_a_snapshot_is_named_by_its_index(run):
    for bad in (2, -3, 1.0, True, "0"):
        with pytest.raises(ValueError, match=r"snapshot must be an index of one of the run's 2 "
                                             r"snapshots, got"):
            run.topography(snapshot=bad)


@pytest.mark.parametrize("n, rim, interior", [(64, 0.1205, 0.0140), (128, 0.0833, 0.0078)])
def test_rms_slope_agrees_to_the_grids_error_on_the_homogeneous_disk(st, n, rim, interior):
    """Two stencils of one continuum rms slope: they differ by the rim, and converge.

    SurfaceTopography's ``rms_gradient`` is the rms of forward differences over the pixels
    whose differences it can interpolate on the face, which leaves out the rim, where the
    slope is log-singular and largest.  Measured shortfall from ``rms_slope_plain`` over the
    whole face: 0.1205 at n = 64, 0.0833 at 128, 0.0554 at 256; over the pixels it keeps,
    from runin's exact-kernel slope there: 0.0140, 0.0078, 0.0044 (first order: differences
    between pixel centres against the slope at a centre).  Both tend to ``grad_f0`` (eq. 12)
    from below.
    """
    result = solve(problem(GEOMETRIES["homogeneous"], [K1], n=n), face_only=True)
    topography = result.topography()
    theirs = topography.rms_gradient()
    gx, gy = topography.derivative(1)
    kept = ~np.ma.getmaskarray(gx * gx + gy * gy)
    face, h = result.face, result.pixel_size
    fx = (face[1:, :-1] - face[:-1, :-1]) / h
    fy = (face[:-1, 1:] - face[:-1, :-1]) / h
    forward = np.sqrt(np.mean((fx * fx + fy * fy)[kept]))
    assert relative(theirs, forward) < SAME, "rms_gradient: forward differences on its pixels"
    ours = result.rms_slope_plain
    assert 0.0 < 1.0 - theirs / ours < 1.02 * rim, \
        f"n = {n}: rms_gradient {theirs:.5f} vs rms_slope_plain {ours:.5f}"
    assert theirs < ours < result.reference_slope, "both approach grad_f0 from below"
    same_pixels = np.sqrt(np.mean(result.slope[:-1, :-1][kept] ** 2))
    assert 0.0 < 1.0 - theirs / same_pixels < 1.1 * interior, \
        f"n = {n}: rms_gradient {theirs:.5f} vs runin's slope on its pixels {same_pixels:.5f}"


def test_psd_is_surface_topographys_on_a_face_that_fills_its_box(st):
    result = voronoi_face(48, OUTLINES["rectangle"])
    assert np.isfinite(result.face).all(), "the rectangle fills its grid"
    q, C = result.topography().detrend("height").power_spectrum_from_area()
    spectrum = result.face_psd
    assert len(spectrum.wavevector) == q.count() > 10, f"{q.count()} bins with wavevectors"
    assert relative(spectrum.wavevector, q.compressed()) < SAME, "the bins' mean wavevectors"
    assert relative(spectrum.density, C.compressed()) < SAME, "C^iso"


@pytest.mark.parametrize("n", [40, 41])
def test_psd_is_surface_topographys_of_the_disk_filled_with_zero(st, n):
    result = voronoi_face(n)
    q, C = (result.topography().detrend("height").fill_undefined_data(0.0)
            .power_spectrum_from_area())
    spectrum = result.face_psd
    assert len(spectrum.wavevector) == q.count(), f"{len(spectrum.wavevector)} vs {q.count()}"
    assert relative(spectrum.wavevector, q.compressed()) < SAME, "the bins' mean wavevectors"
    assert relative(spectrum.density, C.compressed()) < SAME, "C^iso"


def test_psd_of_rectangular_pixels_with_holes(st):
    """Pixels of (dx, dy), nx != ny, odd and even: the axes of the spectrum are the face's."""
    face = np.random.default_rng(6121).standard_normal((20, 33)) * 1e-6
    face[3:5, 7] = np.nan
    spectrum = isotropic_psd(face, (1e-4, 2.5e-4))
    q, C = (to_topography(face, (1e-4, 2.5e-4)).detrend("height").fill_undefined_data(0.0)
            .power_spectrum_from_area())
    assert relative(spectrum.wavevector, q.compressed()) < SAME, "wavevectors"
    assert relative(spectrum.density, C.compressed()) < SAME, "C^iso"


def test_psd_needs_no_surface_topography(monkeypatch):
    monkeypatch.setitem(sys.modules, "SurfaceTopography", None)
    result = voronoi_face(33)
    spectrum = result.face_psd
    assert spectrum.wavevector.shape == spectrum.density.shape and len(spectrum.density) > 5
    assert np.all(np.diff(spectrum.wavevector) > 0) and np.all(spectrum.density > 0), "C(q)"
    assert spectrum.wavevector[0] >= 2 * np.pi / (33 * result.pixel_size), "from 2 pi / L"
    assert spectrum.wavevector[-1] <= np.pi / result.pixel_size, "to the Nyquist wavevector"
    with pytest.raises(ModuleNotFoundError, match=r"pip install 'runin\[surface\]'"):
        result.topography()


def test_psd_of_a_plane_is_zero_and_bad_faces_are_refused():
    x = np.arange(16.0) * 1e-4
    plane = 1e-6 + 0.02 * x[:, None] - 0.01 * x[None, :]
    spectrum = isotropic_psd(plane, 1e-4)
    # C ~ (relief L)^2 for a relief of the plane's size; rounding leaves ~1e-32 of it.
    scale = (np.ptp(plane) * 16 * 1e-4) ** 2
    assert np.max(spectrum.density) < 1e-25 * scale, "the least-squares plane is removed"
    with pytest.raises(ValueError, match=r"2-d array of heights \(m\), got shape \(16,\)"):
        isotropic_psd(np.arange(16.0), 1e-4)
    with pytest.raises(ValueError, match="at least 3 pixels with a height, got 2 of 4"):
        isotropic_psd(np.array([[1.0, np.nan], [np.nan, 2.0]]), 1e-4)
    with pytest.raises(ValueError, match="pixel_size"):
        isotropic_psd(np.zeros((4, 4)), -1e-4)


def test_result_file_holds_the_psd_along_its_wavevector(tmp_path):
    result = voronoi_face(33)
    path = write_result(tmp_path / "r.h5", result)
    with h5py.File(path, "r") as f:
        group = f["face_psd"]
        assert group["wavevector"].attrs["units"] == "m-1", "wavevector in m-1"
        assert group["psd"].attrs["units"] == "m4", "C^iso in m4"
        assert np.array_equal(group["wavevector"][()], result.face_psd.wavevector), "q"
        assert np.array_equal(group["psd"][()], result.face_psd.density), "C^iso"
    with xr.open_datatree(path, engine="h5netcdf") as tree:
        psd = tree["face_psd"]["psd"]
        assert psd.dims == ("wavevector",), f"psd along {psd.dims}"
    stored = read_result(path).result
    assert np.array_equal(stored.face_psd.density, result.face_psd.density), "read back"


def test_the_files_page_example_runs(st, tmp_path, monkeypatch, capsys):
    """The example of docs/files.md, "Faces as SurfaceTopography topographies", as printed."""
    page = (pathlib.Path(__file__).resolve().parents[1] / "docs" / "files.md").read_text()
    section = page.split("## Faces as SurfaceTopography topographies", 1)[1]
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    monkeypatch.chdir(tmp_path)
    exec(compile(code, "docs/files.md", "exec"), {})
    sizes, heights = capsys.readouterr().out.splitlines()
    assert sizes == "(0.008, 0.008) m", sizes
    left, right = heights.split(" = ")
    assert left == right, f"the rms heights printed: {heights}"
    assert (tmp_path / "predicted.x3p").stat().st_size > 0, "the x3p file is written"
