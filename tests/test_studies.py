"""Smoke tests of the study scripts: each runs at a small size (``--quick``).

Every study computes into HDF5 and draws its PNG from that file; the tests
check the files, a physics figure of each study, and that ``--plot-only``
redraws the figure from the HDF5 file alone.
"""

import importlib
import pathlib
import sys

import h5py
import numpy as np
import pytest

STUDIES = pathlib.Path(__file__).resolve().parent.parent / "studies"

SERIAL = ["fig2_homogeneous", "fig3_biphasic", "fig6_epoxy", "fig78_rods", "rods_both_ways",
          "three_phases", "wear_exponent", "random_inclusions", "runin_distance",
          "face_outlines", "pin_on_disk", "coating_wear_through", "particles_3d",
          "calibrate_error_bar", "counterbody_thickness", "periodic_patch"]
PARALLEL = ["fig4_coarseness", "fig5_collapse", "scale_independence", "claims",
            "design_table", "runin_history", "runin_convergence"]


@pytest.fixture(scope="module")
def studies():
    sys.path.insert(0, str(STUDIES))
    try:
        yield {name: importlib.import_module(name) for name in SERIAL + PARALLEL}
    finally:
        sys.path.remove(str(STUDIES))


@pytest.fixture(scope="module")
def runs(studies, tmp_path_factory):
    """Run every study once in quick mode; the parallel ones share one quick sweep."""
    tmp = tmp_path_factory.mktemp("studies")
    out = {}
    for name, module in studies.items():
        h5, png = tmp / f"{name}.h5", tmp / f"{name}.png"
        args = ["--quick", "-o", str(h5), "--png", str(png)]
        if name in PARALLEL:
            args += ["--workers", "1"]
        status = module.main(args)
        out[name] = (status, h5, png)
    return out


@pytest.mark.parametrize("name", SERIAL + PARALLEL)
def test_quick_run_writes_hdf5_and_png(runs, name):
    status, h5, png = runs[name]
    assert status == 0, f"{name} exited with {status}"
    assert h5.is_file() and png.is_file(), f"{name}: missing outputs"
    assert png.stat().st_size < 300e3, f"{name}: PNG of {png.stat().st_size} bytes"
    with h5py.File(h5, "r") as f:
        assert str(f.attrs["format"]).startswith("runin."), f"{name}: format attribute"
        assert int(f.attrs["format_version"]) == 1, f"{name}: version attribute"
        units = [ds.attrs.get("units") for ds in f.values() if isinstance(ds, h5py.Dataset)]
        assert all(u is not None for u in units), f"{name}: a dataset without units"


@pytest.mark.parametrize("name", ["fig2_homogeneous", "fig4_coarseness", "claims"])
def test_plot_only_redraws_from_the_file(studies, runs, name, tmp_path):
    _, h5, _ = runs[name]
    png = tmp_path / "again.png"
    assert studies[name].main(["--plot-only", "-o", str(h5), "--png", str(png)]) == 0, \
        f"{name}: --plot-only failed"
    assert png.stat().st_size > 10e3, f"{name}: redrawn figure is empty"


def test_plot_only_without_file_is_an_error(studies, tmp_path, capsys):
    status = studies["fig2_homogeneous"].main(["--plot-only", "-o", str(tmp_path / "no.h5")])
    assert status == 2, "missing study file must exit with status 2"
    assert "does not exist" in capsys.readouterr().err, "message names the problem"


def attrs_of(path):
    with h5py.File(path, "r") as f:
        return dict(f.attrs)


def test_fig2_face_matches_eq10(runs):
    """N = 64: face within 2 % of eq. 10 (f_bar is about 1 .. 1.57); corrected rms near 1."""
    a = attrs_of(runs["fig2_homogeneous"][1])
    assert a["max_face_error"] < 0.02, f"face error {a['max_face_error']}"
    with h5py.File(runs["fig2_homogeneous"][1], "r") as f:
        s = f["rms_slope"][()]
    assert abs(s[-1] - 1) < 5e-3, f"corrected rms slope {s[-1]} at n = 64"


def test_fig3_error_bar_and_pressures(runs):
    """k_2/k_1 = 10: phase 2 carries a tenth of phase 1's pressure (eq. 7)."""
    with h5py.File(runs["fig3_biphasic"][1], "r") as f:
        p = f["phase_pressures"][()]
        a = dict(f.attrs)
    assert p[0] / p[1] == pytest.approx(10.0, rel=1e-12), f"pressures {p}"
    assert 1.0 < a["rms_slope"] < 2.0 and a["rms_slope_error"] < 0.05, a


def test_fig6_profile_height(runs):
    """Centre 445 um above the rim: 4 pbar a / (pi E*) (pi/2 - 1) for the epoxy scene.

    At n = 64 the sections deviate from eq. 10 by 2.3 um (0.5 %) inside r < 0.9 a and by
    33 um (7.5 %) at the rim, where the slope is log-singular and the last pixel centre
    sits h/2 inside.
    """
    a = attrs_of(runs["fig6_epoxy"][1])
    pbar = 10.0 / (np.pi * 0.004**2)
    expected = 4 * pbar * 0.004 / (np.pi * 1.3e6) * (np.pi / 2 - 1)
    assert a["centre_height"] == pytest.approx(expected, rel=1e-9), "eq. 10 centre height"
    assert a["max_deviation_inner"] < 0.01 * expected, f"solver vs eq. 10 at n = 64: {a}"
    assert a["max_deviation"] < 0.1 * expected, f"solver vs eq. 10 at the rim: {a}"


def test_fig78_rods_signs(runs):
    """k_steel/k_brass = 1.7: steel wears faster, so steel rods sit low, brass rods high."""
    a = attrs_of(runs["fig78_rods"][1])
    assert a["steel_in_brass_side_rods"] < 0 < a["brass_in_steel_side_rods"], a


def test_counterbody_thickness_quick(runs):
    """A thin layer flattens the rods' face and shortens their run-in; a thick one does not.

    Quick run (n = 32, run-ins at n = 24, nu = 0.5): measured 0.62 and 0.99 of the half-space's
    rms slope at t = 0.5 a and 5 a, run-in distances 0.59 and 1.00 of the half-space's.
    """
    h5 = runs["counterbody_thickness"][1]
    a = attrs_of(h5)
    with h5py.File(h5, "r") as f:
        slopes = f["rods/nu0.5/rms_slope"][()]
        distances = f["rods/nu0.5/run_in_distance"][()]
    half = a["rods_halfspace_rms_slope"]
    assert slopes[0] < 0.8 * half and abs(slopes[1] / half - 1) < 0.03, (slopes, half)
    assert distances[0] < 0.8 and abs(distances[1] - 1) < 0.05, distances


def test_rods_both_ways(runs):
    """Steel proud only with the inverse ratio; each scene's inverse is the other's printed.

    Steel rods in brass at 1/1.7 and brass rods in steel at 1.7 both have rods at 1.7 times
    the matrix pressure: the same face up to the labels, so the same rms slope to round-off.
    """
    a = attrs_of(runs["rods_both_ways"][1])
    for key in ("steel_in_brass", "brass_in_steel"):
        assert a[f"{key}_printed_steel_relief"] < 0 < a[f"{key}_inverse_steel_relief"], a
    assert a["steel_in_brass_inverse_rms_slope"] == pytest.approx(
        a["brass_in_steel_printed_rms_slope"], rel=1e-12), "rods at 1.7 x the matrix pressure"


@pytest.mark.parametrize("n", [63, 64])
def test_three_phases_reduce_to_two(studies, n):
    """k_soft = k_matrix: the three-phase map is the two-phase map of the same pixels.

    Round-off only: over the 250 maps of the full study (n = 512) the largest relative
    difference was 6.7e-16.
    """
    from steady.phases import Voronoi

    geometry = Voronoi(100, (0.5, 0.2, 0.3), 4409)
    three, merged, voronoi = studies["three_phases"].reduction(geometry, n, [10.0, 100.0])
    assert np.allclose(three, merged, rtol=1e-12, atol=0), f"{three} vs {merged}"
    assert np.all(three > 1.0) and np.all(voronoi > 1.0), "a biphasic face is rougher"


def test_three_phases_quick(runs):
    with h5py.File(runs["three_phases"][1], "r") as f:
        assert f.attrs["reduction_max_relative_difference"] < 1e-12, "reduction to two phases"
        rel = f["rms_slope"][()][..., :2] / f["closed_form_realised"][()][..., :2] - 1
    # 10^2 seeds at n = 64: within 15 % of the fine-grain form (measured: 7 %).
    assert np.all(np.abs(rel) < 0.15), f"three-phase map off the closed form: {rel}"


def test_wear_exponent_is_an_effective_ratio(runs):
    """Exponent m at k_2/k_1 is Archard's law at (k_2/k_1)^(1/m): the same pressures (eq. 7).

    Round-off only (2.2e-16 in the quick run; the same in the full one).
    """
    a = attrs_of(runs["wear_exponent"][1])
    assert a["map_max_difference_from_effective_ratio"] < 1e-12, a
    assert a["collapse_max_difference_from_effective_ratio"] < 1e-12, a
    peaks = a["map_max_mean"]
    assert np.all(np.diff(peaks[1:]) < 0), f"larger m flattens the map: peaks {peaks}"


def test_random_inclusions_quick(runs):
    with h5py.File(runs["random_inclusions"][1], "r") as f:
        rel = f["relative_to_closed_form"][()]
        face, bound = f["face"][()], f["realised_fill"][()]
    # Inclusions of 0.08 and 0.16 a at n = 96 against the fine-grain form: within 15 %
    # (measured: 3.6 % for the realisation means, 8 % for single maps).
    assert np.all(np.abs(rel) < 0.15), f"off the fine-grain form: {rel}"
    # Parseval bound on the face, pillars case k_2/k_1 = 1e-3 (first ratio).
    assert np.all(face[..., 0] <= 0.5 * np.pi / np.sqrt(bound) + 1e-9), "above the bound"


def test_particles_3d_quick(runs):
    """Particles larger than f* (4 f* against 0.5 f*) keep the face closer to its sections."""
    with h5py.File(runs["particles_3d"][1], "r") as f:
        tracking, ratio = f["tracking"][()], f["mean_ratio"][()]
    # Measured at n = 32: 2.4 % and 0.44 % (a ratio of 0.18); the mean slopes 0.978 and 1.0006 of
    # the sections'.  Bounds: about twice the measured ratio and departure from 1.
    assert tracking[1] < 0.4 * tracking[0], f"tracking {tracking}"
    assert np.all(np.abs(ratio - 1) < 0.05), f"mean rms slope over the sections' {ratio}"


def test_runin_distance_quick(runs):
    """Every quick run-in has a run-in distance of order s*, bracketed by its bounds."""
    a = attrs_of(runs["runin_distance"][1])
    s1 = {k: v for k, v in a.items() if k.endswith("_s1")}
    assert s1, "no run-in distances"
    for key, value in s1.items():
        low = a[key + "_low"]
        assert 0 < low <= value < 10, f"{key}: {value} (low {low})"


def test_calibrate_error_bar_quick(runs):
    """Every quick row has a bar, a reference and their ratio; the disk's is the axisymmetric.

    Its run-in distances are 2.156 s* (1 %) and 3.273 s* (0.1 %), here in metres.
    """
    path = runs["calibrate_error_bar"][1]
    with h5py.File(path, "r") as f:
        bar, ref, s = f["bar"][()], f["reference"][()], f["distance"][()]
        ratio, kind = f["ratio"][()], [k.decode() if isinstance(k, bytes) else k
                                       for k in f["reference_kind"][()]]
        assert f["bar"].attrs["units"] == "m" and f["ratio"].attrs["units"] == "1"
    assert np.all(bar > 0) and np.all(np.isfinite(ref)), (bar, ref)
    finite = np.isfinite(bar)
    assert np.allclose(ratio[finite], bar[finite] / np.abs(s[finite] - ref[finite])), ratio
    disk = [i for i, k in enumerate(kind) if k.startswith("axisymmetric")]
    s_star = 0.004 / (1e-13 * 1.3e6)  # the epoxy scene: a / (k E*)
    assert np.allclose(ref[disk] / s_star, [2.1561, 3.2735], atol=2e-4), ref[disk] / s_star


def test_face_outlines_quick(runs):
    """Each face normalised by its own homogeneous closed form; the biphasic face is rougher."""
    from steady import reference

    a = attrs_of(runs["face_outlines"][1])
    assert a["disk_reference_factor"] == pytest.approx(4 / np.pi, rel=1e-15)
    assert a["tread_reference_factor"] == pytest.approx(reference.rectangle_rms_slope(1 / 3),
                                                        rel=1e-15)
    assert a["seal_reference_factor"] == pytest.approx(reference.annulus_rms_slope(0.625),
                                                       rel=1e-15)
    with h5py.File(runs["face_outlines"][1], "r") as f:
        for name in ("disk", "tread", "seal"):
            value, error = f[f"{name}/rms_slope"][()], f[f"{name}/rms_slope_error"][()]
            # k_2/k_1 = 10 at fill 0.5: 1.5-1.7 reference slopes in the quick run.
            assert np.all(value - error > 1.0), f"{name}: {value} +- {error}"
            assert np.all(error < 0.05 * value), f"{name}: error bars {error}"
            face, labels = f[f"{name}/face"][()], f[f"{name}/labels"][()]
            assert np.array_equal(np.isfinite(face), labels >= 0), f"{name}: face off its map"


def test_pin_on_disk_tilt_falls_like_the_inverse_track_radius(runs):
    """The face tilts by about a / R: tilt times R / a within 10 % of one value.

    Measured in the quick run (R / a = 5, 50): spreads of 1.5 % and 0.4 %.
    """
    with h5py.File(runs["pin_on_disk"][1], "r") as f:
        ratio = f["track_ratio"][()]
        for name in ("voronoi", "homogeneous"):
            scaled = np.abs(f[f"{name}/tilt"][()]) * ratio
            assert np.ptp(scaled[1:]) < 0.1 * scaled.mean(), f"{name}: tilt R/a {scaled}"


def test_periodic_patch_is_parsevals_closed_form(runs):
    _, h5, _ = runs["periodic_patch"]
    with h5py.File(h5) as f:
        values, closed = f["patch/rms_slope"][()], f["patch/closed_form"][()]
        punch = f["punch/rms_slope"][()]
        road = f["road/rms_slope"][()]
    # Parseval's identity on the cell: 2 std(p) / E*, to round-off (measured 7e-16).
    assert np.abs(values - closed).max() < 1e-12, "the patch is not Parseval's closed form"
    assert np.all(punch > values.max()), "the punch's rim must add to the patch's slope"
    # A tread on a rigid belt is stiffer than the half-space at the grain's wavelengths.
    assert np.all(road[:, 1] < road[:, 0]), f"the tread does not lower the road's slope: {road}"


def test_fig4_map_is_symmetric_in_the_mean(runs):
    with h5py.File(runs["fig4_coarseness"][1], "r") as f:
        mean = f["mean"][()]
    assert np.all(mean >= 0.98), f"normalised rms slope below 1: {mean.min()}"
    assert np.allclose(mean[:, mean.shape[1] // 2], mean[0, mean.shape[1] // 2], rtol=1e-12), \
        "k_2 = k_1 must give one value for every fill factor"


def test_claims_quick(runs):
    a = attrs_of(runs["claims"][1])
    assert a["symmetry_swapped_max_relative_difference"] < 1e-12, \
        "the same map with phases swapped must give the same rms slope"
    assert a["pillars_max_over_bound"] <= 1e-9, "a value above the Parseval bound"


def test_runin_reaches_the_steady_face(runs):
    a = attrs_of(runs["runin_history"][1])
    for case in ("voronoi_k10", "rods_brass_in_steel"):
        assert a[f"{case}_face_error"] < 1e-4, f"{case}: face error {a[f'{case}_face_error']}"
        assert a[f"{case}_agrees"] == 1.0, f"{case}: last rms slope outside the error bars"
    with h5py.File(runs["runin_history"][1], "r") as f:
        slope = f["voronoi_k10/normalised_rms_slope"][()]
        spatial = f["voronoi_k10/spatial_error"][()]
    assert slope[0] == 0.0, f"the flat face starts at {slope[0]}"
    assert spatial.shape == slope.shape and spatial[0] == 0.0, "companion error per step"


def test_runin_convergence_quick(runs):
    """On n = 40, 64, 80 the homogeneous history is within its error bars of the reference."""
    with h5py.File(runs["runin_convergence"][1], "r") as f:
        ref = f["reference/rms_slope"][()]
        value = f["homogeneous/rms_slope"][()]
        error = f["homogeneous/rms_slope_error"][()]
    assert np.all(np.abs(value - ref) <= error), \
        f"homogeneous history off the reference: {value - ref} (error bars {error})"


def test_work_precision_spatial_quick(tmp_path):
    """The spatial axis: every implicit scheme of the registry against the reference."""
    import subprocess

    from transient.stepping import SCHEMES

    proc = subprocess.run([sys.executable, str(STUDIES / "work_precision.py"), "--quick",
                           "--spatial", "--out", str(tmp_path)], capture_output=True, text=True,
                          timeout=600)
    assert proc.returncode == 0, proc.stderr
    h5 = tmp_path / "work_precision_spatial.h5"
    assert (tmp_path / "work_precision_spatial.png").stat().st_size > 10e3, "no figure"
    with h5py.File(h5, "r") as f:
        assert f.attrs["format"] == "runin.work_precision_spatial", f.attrs["format"]
        names = {g.attrs["scheme"] for g in f["runs"].values()}
        # The quick reference (n = 40, 80, 160) converges at no distance: the error
        # over the resolved distances is NaN, the one over all of them is not.
        errors = [g.attrs["error_all"] for g in f["runs"].values()]
    implicit = {name for name, scheme in SCHEMES.items() if not scheme.explicit}
    assert names == implicit, f"schemes run {names}, registry {implicit}"
    assert all(np.isfinite(errors)), f"errors {errors}"


def test_scale_independence_quick(runs):
    with h5py.File(runs["scale_independence"][1], "r") as f:
        resid = f["residual_mean"][()]
        sem = f["residual_sem"][()]
    assert np.all(np.abs(resid) < 0.15), f"residual against the closed form {resid}"
    assert np.all(sem > 0), "scatter of the realisations"


def test_fit_rods_tells_the_ratio_from_its_inverse(tmp_path):
    """Quick run of the inverse fit on the rods: 1.7 and 1/1.7 recovered and told apart.

    At 1 % noise every case's 95 % interval holds its own k_steel/k_brass and
    excludes the inverse; the figure is redrawn from the HDF5 file alone.
    """
    sys.path.insert(0, str(STUDIES))
    try:
        module = importlib.import_module("fit_rods")
    finally:
        sys.path.remove(str(STUDIES))
    h5, png = tmp_path / "fit_rods.h5", tmp_path / "fit_rods.png"
    assert module.main(["--quick", "-o", str(h5), "--png", str(png)]) == 0, "quick run failed"
    assert png.stat().st_size < 300e3, f"PNG of {png.stat().st_size} bytes"
    with h5py.File(h5, "r") as f:
        assert f.attrs["format"] == "runin.study.fit_rods" and f.attrs["format_version"] == 1
        assert all("units" in ds.attrs for ds in f["steel_in_brass/1.7"].values()), "units"
        levels = list(f["levels"][()])
        first = levels.index(0.01)
        for key in ("steel_in_brass", "brass_in_steel"):
            for label in ("1.7", "1_over_1.7"):
                g = f[f"{key}/{label}"]
                assert g["covers_truth"][first] and g["excludes_other"][first], \
                    f"{key}, true {label}: interval [{g['lower'][first]}, {g['upper'][first]}]"
    again = tmp_path / "again.png"
    assert module.main(["--plot-only", "-o", str(h5), "--png", str(again)]) == 0, "--plot-only"


def test_a_quick_run_writes_into_its_output_directory_only(studies, tmp_path, monkeypatch):
    """Without -o and --png a study writes under ./runin-studies-out/quick; docs/ untouched."""
    docs = STUDIES.parent / "docs"
    before = {p: p.stat().st_mtime_ns for p in docs.rglob("*")}
    monkeypatch.chdir(tmp_path)
    assert studies["fig6_epoxy"].main(["--quick"]) == 0, "quick run failed"
    written = sorted(str(p.relative_to(tmp_path)) for p in tmp_path.rglob("*") if p.is_file())
    assert written == ["runin-studies-out/quick/fig6_epoxy.h5",
                       "runin-studies-out/quick/fig6_epoxy.png"], f"written {written}"
    after = {p: p.stat().st_mtime_ns for p in docs.rglob("*")}
    assert after == before, "a quick run changed files under docs/"


def test_docs_figures_is_refused_with_quick(studies, tmp_path, capsys):
    status = studies["fig2_homogeneous"].main(["--quick", "--docs-figures", "--out",
                                              str(tmp_path)])
    assert status == 2, "--docs-figures with --quick must exit with status 2"
    assert capsys.readouterr().err == ("error: --docs-figures redraws the committed figures "
                                       "from full runs; not with --quick\n"), "message"
    assert not any(tmp_path.iterdir()), "something was written"


def test_full_runs_write_the_committed_files_only_when_asked(studies):
    """Where a full run writes, from the shared arguments (no run)."""
    import argparse

    study_io = sys.modules["study_io"]
    parser = argparse.ArgumentParser()
    study_io.add_output_arguments(parser)

    def paths(*argv, **kwargs):
        args = parser.parse_args(list(argv))
        args.quick, args.output, args.png = False, None, None
        return study_io.output_paths(args, "fig2_homogeneous", **kwargs)

    out = study_io.DEFAULT_OUT
    assert paths() == (out / "fig2_homogeneous.h5", out / "fig2_homogeneous.png"), paths()
    assert paths("--out", "elsewhere") == (pathlib.Path("elsewhere/fig2_homogeneous.h5"),
                                           pathlib.Path("elsewhere/fig2_homogeneous.png"))
    docs = STUDIES.parent / "docs" / "figures" / "fig2_homogeneous.png"
    assert paths("--docs-figures") == (out / "fig2_homogeneous.h5", docs), "--docs-figures"
    table = studies["design_table"].TABLE
    assert paths(committed_output=table) == (out / "fig2_homogeneous.h5",
                                             out / "fig2_homogeneous.png"), "the table kept"
    assert paths("--docs-figures", committed_output=table) == (table, docs), "the table"


def test_sweep_files_go_to_the_output_directory(studies):
    voronoi_study = sys.modules["voronoi_study"]
    name = voronoi_study.SWEEP.format(n=512)
    assert name == "voronoi_sweep_n512.h5", name
    assert voronoi_study.sweep_path({"n": 64, "quick": True}, "d/fig4.h5") == \
        pathlib.Path("d/voronoi_sweep_quick_n64.h5"), "quick sweep beside the output"
    assert voronoi_study.sweep_path({"n": 512, "sweep": "s.h5"}, "d/fig4.h5") == \
        pathlib.Path("s.h5"), "a given sweep file"


def test_map_file_makers_write_the_shipped_files_into_the_output_directory(tmp_path,
                                                                           monkeypatch):
    """The scripts that make the examples' map files: the same bytes, under ./runin-studies-out."""
    sys.path.insert(0, str(STUDIES))
    try:
        makers = [importlib.import_module(name) for name in ("make_face_mask", "make_micrograph")]
    finally:
        sys.path.remove(str(STUDIES))
    monkeypatch.chdir(tmp_path)
    for module in makers:
        assert module.main([]) == 0, f"{module.__name__} failed"
        made = tmp_path / "runin-studies-out" / module.SHIPPED.name
        assert made.read_bytes() == module.SHIPPED.read_bytes(), \
            f"{module.__name__}: {made.name} differs from the shipped file"
