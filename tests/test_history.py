"""The run-in history's friction proxy: exact start, jump, error bars, steady end, rms height.

References: the initial faces' closed forms (:func:`transient.initial_face.exact_statistics`)
and the axisymmetric run-in of the homogeneous cylinder (:mod:`transient.axisymmetric`).  The
history's end against the steady module's corrected value is in ``tests/test_runin.py``; the
convergence under refinement (slow) in ``tests/test_history_convergence.py``.
"""

import dataclasses
import math

import numpy as np
import pytest
from conftest import CRITICAL_TILT, FORCE, GEOMETRIES, RADIUS, RODS, wear_problem

from steady import reference
from steady.outline import Circle
from transient import initial_face
from transient.axisymmetric import reference_history
from transient.history import (
    SOURCE_CONTACT,
    SOURCE_INITIAL,
    SOURCE_PARTIAL_CONTACT,
    FaceEstimator,
    face_statistics,
    rim_layer_excess,
)
from transient.runin import RunOptions, run_in
from transient.solver import StageSolver

FAST = RunOptions(tol=1e-3)
VORONOI = GEOMETRIES["voronoi"]
G0 = reference.disk_reference_slope(reference.disk_mean_pressure(FORCE, RADIUS), 1.3e6)


@pytest.mark.parametrize("n", [32, 33])
def test_flat_face_starts_at_zero_then_jumps(n):
    """At s = 0 the flat face's exact 0 (error 0); just after, the rim layer's ~0.85 grad_f0.

    The axisymmetric reference gives 0.8483 at 1e-4 s* and 0.8491 at 1e-3 s*;
    the first recorded step (2e-5 s*) is 0.8567 +- 0.0300 at n = 32 and
    0.8593 +- 0.0303 at n = 33 (measured).
    """
    problem = wear_problem("homogeneous", (1.0,), n)
    result = run_in(problem, initial_face.flat(problem.grid),
                    dataclasses.replace(FAST, max_steps=3))
    h = result.history
    assert h["rms_slope"][0] == 0.0 and h["rms_slope_error"][0] == 0.0, \
        f"flat face at s = 0: {h['rms_slope'][0]} +- {h['rms_slope_error'][0]}"
    assert h["rms_slope_source"][0] == SOURCE_INITIAL, "s = 0 is the initial face's own value"
    assert h["rms_height"][0] == 0.0, "a flat face has no relief"
    ref = reference_history([1e-4], rings=200).rms_slope[0]
    first, bar = h["normalised_rms_slope"][1], h["rms_slope_error"][1] / G0
    assert abs(first - ref) <= bar, \
        f"first step {first:.4f} +- {bar:.4f} misses the jump to {ref:.4f}"
    assert h["rms_slope_source"][1] == SOURCE_CONTACT, "full contact after s = 0"
    # The plain pixel value keeps the grid's artefact: ~0.6 grad_f0 on the flat punch.
    assert 0.55 < h["rms_slope_plain"][0] / G0 < 0.65, h["rms_slope_plain"][0] / G0


@pytest.mark.parametrize("tilt", [0.5, 3.0])
def test_tilted_face_starts_at_its_tilt(tilt):
    """At s = 0 tan(angle) exactly, in full contact (0.5 x the lift-off tilt) or not (3 x)."""
    n = 33
    angle = math.atan(tilt * CRITICAL_TILT)
    problem = wear_problem(VORONOI, (1.0, 10.0), n)
    result = run_in(problem, initial_face.tilted(problem.grid, angle), dataclasses.replace(
        FAST, max_steps=3))
    h = result.history
    exact = initial_face.exact_statistics("tilted", RADIUS, angle=angle).rms_slope
    assert h["rms_slope"][0] == pytest.approx(exact, rel=1e-13), \
        f"tilted face starts at {h['rms_slope'][0]}, tan(angle) = {exact}"
    assert h["rms_slope_error"][0] == 0.0 and h["rms_height"][0] == 0.0, \
        "a plane's differences are exact and its relief about its plane is 0"
    partial = h["contact_fraction"][0] < 1
    assert partial == (tilt > 1), f"contact fraction {h['contact_fraction'][0]} at tilt {tilt}"
    assert h["rms_slope_source"][1] == (SOURCE_PARTIAL_CONTACT if partial else SOURCE_CONTACT), \
        f"source {h['rms_slope_source'][1]} after s = 0"


@pytest.mark.parametrize("n", [64, 65])
def test_crowned_face_statistics_match_the_closed_form(n):
    """Pixel differences of the sphere cap against its closed form, within the error estimate.

    Measured (R = 2a): slope errors -3.4e-4 (n = 64) and -3.3e-3 (65) with
    estimates 6.8e-3 and 5.8e-3; height errors 3.6e-3 and -1.8e-3 of the value.
    """
    sphere = 2 * RADIUS
    exact = initial_face.exact_statistics("crowned", RADIUS, sphere_radius=sphere)
    grid = Circle(RADIUS).grid(n)
    stats = face_statistics(initial_face.crowned(grid, sphere), grid.mask, 2 * RADIUS / n)
    assert abs(stats.rms_slope - exact.rms_slope) <= stats.rms_slope_error, \
        f"n={n}: {stats.rms_slope} vs {exact.rms_slope} +- {stats.rms_slope_error}"
    assert stats.rms_height == pytest.approx(exact.rms_height, rel=1e-2), \
        f"n={n}: rms height {stats.rms_height} vs {exact.rms_height}"


def test_crowned_closed_form_against_quadrature():
    """Mean-square slope of the cap, (R/a)^2 (-ln(1 - x) - x), against direct quadrature."""
    import scipy.integrate

    a, big = RADIUS, 1.5 * RADIUS
    direct = 2 / a**2 * scipy.integrate.quad(lambda r: r**3 / (big**2 - r**2), 0, a,
                                             epsrel=1e-12)[0]
    stats = initial_face.exact_statistics("crowned", a, sphere_radius=big)
    assert stats.rms_slope == pytest.approx(math.sqrt(direct), rel=1e-12), "closed form"
    assert initial_face.exact_statistics("flat", a).rms_slope == 0.0, "flat"
    assert initial_face.exact_statistics("file", a, path="x.npy") is None, \
        "a file has no closed form"


@pytest.mark.parametrize("n", [64, 65])
def test_partial_contact_estimate_is_the_face_slope(n):
    """A crowned face in Hertz-like partial contact (62 % of the face), just after s = 0.

    Off the contact the slope is the face's own (differences); on it K p's
    (corrected estimator): together the cap's closed form.  Measured relative
    errors -1.7e-3 (n = 64) and -5.2e-3 (65), error bars 1.2e-2.
    """
    sphere = 1.5 * RADIUS
    problem = wear_problem("homogeneous", (1.0,), n)
    height = initial_face.crowned(problem.grid, sphere)
    estimator = FaceEstimator(problem, height)
    contact = StageSolver(problem).contact(height)
    figures = estimator.figures(1e-12, height, contact.pressure, contact.approach)
    exact = initial_face.exact_statistics("crowned", RADIUS, sphere_radius=sphere).rms_slope
    assert figures["rms_slope_source"] == SOURCE_PARTIAL_CONTACT, "partial contact expected"
    assert abs(figures["rms_slope"] - exact) <= figures["rms_slope_error"], \
        f"n={n}: {figures['rms_slope']} vs the cap's {exact} +- {figures['rms_slope_error']}"
    assert abs(figures["rms_slope"] / exact - 1) < 1e-2, \
        f"n={n}: relative error {figures['rms_slope'] / exact - 1:.2e}"


def test_rim_layer_excess_fit():
    """The fit's ends: 0.371 grad_f0^2 for an unresolved layer, 0.132 / rho^2 for a resolved one."""
    assert rim_layer_excess(0.0) == pytest.approx(0.371), "unresolved end"
    rho = 1e3
    assert rim_layer_excess(rho) * rho**2 == pytest.approx(0.371 / 2.81, rel=1e-3), \
        "second-order end"
    values = rim_layer_excess(np.logspace(-3, 3, 50))
    assert np.all(np.diff(values) < 0), "excess must fall with the resolution"


def test_history_of_a_resumed_run_is_the_same():
    """A resumed run builds its estimator from the stored initial face: same history."""
    problem = wear_problem(RODS, (1.0, 1.7), 32)
    h0 = initial_face.tilted(problem.grid, 0.5 * CRITICAL_TILT)
    stopped = run_in(problem, h0, dataclasses.replace(FAST, max_steps=4))
    done = run_in(wear_problem(RODS, (1.0, 1.7), 32), None, FAST, resume=stopped)
    straight = run_in(wear_problem(RODS, (1.0, 1.7), 32), h0, FAST)
    for name in ("rms_slope", "rms_slope_error", "rms_height", "rms_slope_plain"):
        assert np.array_equal(done.history[name], straight.history[name]), name


def test_map_error_is_nan_free_on_small_grids():
    problem = wear_problem(VORONOI, (1.0, 10.0), 32)
    estimator = FaceEstimator(problem, np.zeros((32, 32)))
    assert np.isfinite(estimator.map_error) and estimator.map_error > 0, estimator.map_error


def test_companion_runs_give_the_grid_error(scene_file, tmp_path):
    """The same scene on 3n/4 and n/2: max |S_n - S_m| at every recorded distance, 0 at s = 0."""
    from transient.output import read_run, write_run
    from transient.scene import load_transient_scene
    from transient.spatial_error import spatial_error

    scene, options, initial = load_transient_scene(scene_file("runin", n=48))
    problem = wear_problem(scene.geometry, (1.0, 10.0), 48)
    result = run_in(problem, initial.recession(problem.grid), FAST)
    companions = spatial_error(scene, initial, FAST, result)
    assert companions.grids == (36, 24) and all(run.success for run in companions.runs), \
        f"companions on n = {companions.grids}: {[run.status for run in companions.runs]}"
    error = companions.error
    assert error.shape == result.history["distance"].shape and error[0] == 0.0, \
        "one value per recorded distance, 0 at the exact start"
    assert np.all(np.isfinite(error)), "the companions cover the whole run"
    end = max(abs(result.history["rms_slope"][-1] - run.history["rms_slope"][-1])
              for run in companions.runs)
    assert error[-1] == pytest.approx(end, rel=1e-12), "steady ends: max |S_n - S_m|"
    one = spatial_error(scene, initial, FAST, result, grids=(24,))
    assert np.all(one.error <= error), "the larger of two differences bounds either"
    attached = companions.attach(result)
    path = tmp_path / "run.h5"
    write_run(path, attached)
    back, _, _ = read_run(path)
    assert np.array_equal(back.history["rms_slope_spatial_error"], error), "round trip"
    with pytest.raises(ValueError, match="not the same run"):
        companions.attach(run_in(wear_problem(scene.geometry, (1.0, 10.0), 48),
                                 initial.recession(problem.grid), dataclasses.replace(
                                     FAST, max_steps=2)))


@pytest.mark.slow
def test_docs_spatial_error_example(tmp_path, monkeypatch):
    """The README's run-in example, then the companion-run example of docs/library.md."""
    import pathlib
    import re

    root = pathlib.Path(__file__).resolve().parents[1]
    first = (root / "README.md").read_text().split("### A run-in", 1)[1]
    then = (root / "docs" / "library.md").read_text().split(
        "### The history: friction against sliding distance", 1)[1]
    blocks = [re.search(r"```python\n(.*?)```", text, re.S) for text in (first, then)]
    assert None not in blocks, "the README's run-in or the library's companion run is missing"
    monkeypatch.chdir(tmp_path)
    namespace = {}
    for block, where in zip(blocks, ("README.md", "docs/library.md"), strict=True):
        exec(compile(block.group(1), where, "exec"), namespace)
    history = namespace["result"].history
    assert history["rms_slope_spatial_error"].shape == history["rms_slope"].shape, \
        "the companion's error has one value per recorded step"
    assert namespace["companion"].grids == (48,), \
        f"companions on n = {namespace['companion'].grids}"


@pytest.mark.parametrize("n", [48, 49])
def test_single_precision_figures_are_the_double_ones(n):
    """The history's figures in single precision: within a few 1e-7 of double precision.

    On a worn Voronoi face (0.1 s*) and the flat face's first step, n = 48,
    49, measured: rms slope 2.3e-7 (at the first step, where the rim
    layer's excess is taken off the corrected mean square), plain value and
    error bar 1.3e-7 of themselves, the rms slope 5.3e-6 of its error bar.
    The rms height and the map's error involve no transform of the face.
    """
    problem = wear_problem(VORONOI, (1.0, 10.0), n)
    h0 = initial_face.flat(problem.grid)
    single, double = FaceEstimator(problem, h0), FaceEstimator(problem, h0, precision="double")
    assert single.map_error == double.map_error, "the map's error is double precision"
    result = run_in(problem, h0, dataclasses.replace(
        FAST, snapshots_s_star=(0.1,), distance_limit=0.1 * problem.distance_scale))
    height = np.where(problem.face_mask, result.snapshot_recession[0], 0.0)
    states = [(result.snapshot_distance[0], height, result.snapshot_pressure[0])]
    first = StageSolver(problem).contact(h0)
    states.append((1e-5 * result.distance_scale, h0, first.pressure))
    for distance, height, pressure in states:
        a = double.figures(distance, height, np.nan_to_num(pressure), 0.0)
        b = single.figures(distance, height, np.nan_to_num(pressure), 0.0)
        for key, tol in (("rms_slope", 6e-7), ("rms_slope_plain", 4e-7),
                         ("rms_slope_error", 4e-7)):
            assert abs(b[key] / a[key] - 1) < tol, \
                f"n={n}, s={distance:.3g}: {key} {b[key]} vs {a[key]} ({b[key] / a[key] - 1:.1e})"
        assert b["rms_height"] == a["rms_height"], "no transform in the rms height"
        assert abs(b["rms_slope"] - a["rms_slope"]) < 2e-5 * a["rms_slope_error"], \
            f"n={n}, s={distance:.3g}: against the error bar"


def test_a_companion_that_jumped_at_once_is_read_at_every_distance():
    """A companion whose history is its start only (it jumped to its steady state at s = 0)."""
    from transient.spatial_error import _at, _decay_at

    targets = np.array([0.0, 5.0, 50.0])
    assert np.array_equal(_at([0.0], [0.3], targets, steady=True), [0.3, 0.3, 0.3])
    assert np.array_equal(_at([0.0], [0.3], targets, steady=False), [0.3, np.nan, np.nan],
                          equal_nan=True)
    assert np.array_equal(_decay_at([0.0], [1.0], targets, steady=True), [1.0, 1.0, 1.0])
    # Two points: log-linear between them, exact at both.
    got = _decay_at([0.0, 10.0], [1.0, 0.01], np.array([0.0, 5.0, 10.0]), steady=True)
    assert np.allclose(got, [1.0, 0.1, 0.01], rtol=1e-14), got
