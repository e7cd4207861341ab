"""Local wear laws beyond the power law: the threshold law and a tabulated rate.

Steady state: the threshold law's closed form (eq. 7 for the load the
thresholds leave) against Brent's method on the phase balance written
directly; with every threshold 0 it is the power law bit for bit (steady
pressures, faces, and the run-in for ``m != 1``, whose Newton path is the
same arithmetic).  A table sampled from ``k p^m`` reproduces the power law
within its interpolation error: measured on the ``voronoi`` gallery map at
n = 32, ``m = 2``, points evenly spaced on ``[0, 4 pbar]``, the steady phase
pressures' largest relative error is 2.5e-3 (17 points), 7.2e-4 (33) and
7.6e-5 (65), an order of 2.5; the tests assert an order above 2 and twice
the measured error at 33 points.

Run-in: each law's run reaches its steady face (same bounds as
``tests/test_runin.py``: face within 1e-3 of the relief, rms slope within
0.5 %, pressures within 1e-3; measured 1e-9 .. 1e-8, 1e-16 and 1e-16).  The
threshold run starts from the flat punch, whose central pressure (about
``pbar / 2``) lies below both thresholds: its pressures cross ``p_th``.
"""

import pathlib
import re

import h5py
import numpy as np
import pytest
from conftest import (
    FORCE,
    GEOMETRIES,
    K1,
    RADIUS,
    benchmark,
    one_error_line,
    problem,
    run_cli,
    scene_text,
)
from scipy.optimize import brentq

import steady.cli.solve as steady_cli
import transient.__main__ as transient_cli
from steady.fit import FaceModel
from steady.safe_files import OutputExistsError
from steady.scene import parse_scene
from steady.solution import solve, solve_scene
from steady.wear import (
    WEAR_LAWS,
    ArchardLaw,
    PowerLaw,
    TableLaw,
    ThresholdLaw,
    same_wear_law,
    wear_file_attributes,
    wear_law_from_file,
    wear_law_from_table,
)
from transient.comparison import compare_with_steady
from transient.problem import WearProblem
from transient.runin import RunOptions, run_in

PBAR = FORCE / (np.pi * RADIUS ** 2)
VORONOI = GEOMETRIES["voronoi"]
FAST = RunOptions(tol=1e-3)


def steady_problem(wear, n=32):
    return problem(VORONOI, wear, n=n)


def assert_reaches_steady(wear, what, n=32):
    wp = WearProblem(steady_problem(wear, n))
    result = run_in(wp, np.zeros(wp.shape), FAST)
    assert result.status == "steady", f"{what}: {result.message}"
    cmp = compare_with_steady(result, wp.solve_steady(), wp)
    assert cmp.face_error < 1e-3, f"{what}: face error {cmp.face_error:.3g} of the relief"
    assert abs(cmp.rms_slope_error) < 5e-3, f"{what}: rms slope error {cmp.rms_slope_error:.3g}"
    assert cmp.phase_pressure_error < 1e-3, \
        f"{what}: phase pressure error {cmp.phase_pressure_error:.3g}"
    return result, wp


# -- the threshold law: steady state -------------------------------------------
@pytest.mark.parametrize("exponent", [0.5, 1.0, 2.0])
def test_threshold_steady_pressures_solve_the_phase_balance(exponent):
    k = np.array([K1, 7 * K1]) / PBAR ** (exponent - 1)
    p_th = np.array([0.3 * PBAR, 0.9 * PBAR])
    law = ThresholdLaw(k, p_th, exponent)
    counts, area = np.array([613, 211]), 1e-8
    F = 4.0
    p = law.phase_pressures(counts, F, area)

    # Independent: the rate C by Brent's method on sum_i A_i p_i(C) = F.
    def balance(c):
        return float(np.dot(counts * area, p_th + (c / k) ** (1 / exponent))) - F

    c = brentq(balance, 0.0, float(k.max() * (F / area) ** exponent), xtol=1e-300, rtol=1e-15)
    expected = p_th + (c / k) ** (1 / exponent)
    assert np.allclose(p, expected, rtol=1e-12, atol=0), f"{p} against {expected}"
    assert np.dot(counts * area, p) == pytest.approx(F, rel=1e-14), "load"
    rates = law.rate(p, law.wear_field(np.arange(2)))
    assert rates[0] == pytest.approx(rates[1], rel=1e-12), f"equal wear rates {rates}"


def test_threshold_zero_is_the_power_law_bit_for_bit():
    k = (K1, 10 * K1)
    for m in (0.5, 1.0, 2.0):
        power, threshold = PowerLaw(k, m), ThresholdLaw(k, (0.0, 0.0), m)
        a = solve(steady_problem(power), face_only=True)
        b = solve(steady_problem(threshold), face_only=True)
        assert np.array_equal(a.phase_pressures, b.phase_pressures), f"m={m}: pressures"
        assert np.array_equal(a.face, b.face, equal_nan=True), f"m={m}: face"


def test_threshold_zero_runs_in_as_the_power_law():
    # m = 2: both take the Newton path, the same arithmetic: bit for bit.
    k = (K1 / PBAR, 10 * K1 / PBAR)
    runs = [run_in(WearProblem(steady_problem(law)), np.zeros((32, 32)), FAST)
            for law in (PowerLaw(k, 2.0), ThresholdLaw(k, (0.0, 0.0), 2.0))]
    assert runs[0].steps == runs[1].steps, f"steps {runs[0].steps} and {runs[1].steps}"
    assert runs[0].distance == runs[1].distance, f"distance {runs[0].distance}, {runs[1].distance}"
    assert np.array_equal(runs[0].state.recession, runs[1].state.recession, equal_nan=True), "face"
    # m = 1: Archard's linear path against Newton's, both to the steady face.
    assert_reaches_steady(ThresholdLaw((K1, 10 * K1), (0.0, 0.0)), "threshold 0, m=1")


def test_thresholds_that_hold_the_load_are_refused():
    law = ThresholdLaw((K1, 10 * K1), (0.9 * PBAR, 1.2 * PBAR))
    with pytest.raises(ValueError, match=r"wear thresholds p_th = \[.*\] Pa hold sum_i A_i "
                                         r"p_th,i = .* N at or above the load F_N = 10 N"):
        solve(steady_problem(law))


# -- the threshold law: run-in ---------------------------------------------------
@pytest.mark.parametrize("exponent", [1.0, 2.0])
def test_threshold_run_in_crosses_the_thresholds_and_reaches_steady(exponent):
    k = (K1 / PBAR ** (exponent - 1), 10 * K1 / PBAR ** (exponent - 1))
    law = ThresholdLaw(k, (0.6 * PBAR, 0.8 * PBAR), exponent)
    result, wp = assert_reaches_steady(law, f"threshold m={exponent}")
    p = wp.wear.phase_pressures(wp.counts, wp.normal_force, wp.halfspace.h ** 2)
    assert np.all(p > law.thresholds), f"steady pressures {p} above the thresholds"
    assert result.failures == 0 and result.rejected <= 3, \
        f"{result.failures} failed and {result.rejected} rejected steps"


@pytest.mark.slow
def test_threshold_below_exponent_one_reaches_steady():
    # m = 0.5: an infinite slope at the threshold; the chord linearisation
    # (measured at n = 32: 15 steps, 713 solves, no failure; the tangent's
    # Newton iteration failed 349 times on the same run).
    law = ThresholdLaw((K1 * PBAR ** 0.5, 10 * K1 * PBAR ** 0.5), (0.6 * PBAR, 0.8 * PBAR), 0.5)
    result, _ = assert_reaches_steady(law, "threshold m=0.5")
    assert result.failures == 0, f"{result.failures} failed steps"


@pytest.mark.slow
def test_threshold_near_the_load_reaches_steady():
    # sum_i A_i p_th,i = 0.95 F: the phases wear on 5 % of the load.
    law = ThresholdLaw((K1, 10 * K1), (0.95 * PBAR, 0.95 * PBAR))
    result, _ = assert_reaches_steady(law, "threshold 0.95 pbar", n=48)
    assert result.failures == 0, f"{result.failures} failed steps"


# -- the tabulated law ---------------------------------------------------------
def sampled_table(points, m=2.0, top=4.0):
    k = np.array([K1, 10 * K1]) / PBAR ** (m - 1)
    p = np.linspace(0.0, top * PBAR, points)
    return TableLaw([p, p], [ki * p ** m for ki in k]), PowerLaw(k, m)


def test_table_of_the_power_law_converges_to_it():
    errors = []
    sizes = (17, 33, 65)
    for points in sizes:
        table, power = sampled_table(points)
        prob = steady_problem(power)
        args = (prob.phases.counts, prob.normal_force, prob.grid.h ** 2)
        errors.append(float(np.max(np.abs(table.phase_pressures(*args)
                                          / power.phase_pressures(*args) - 1))))
    order = -np.polyfit(np.log(np.array(sizes) - 1), np.log(errors), 1)[0]
    assert order > 2.0, f"order {order:.2f} from errors {errors}"
    assert errors[1] < 1.5e-3, f"33 points: pressure error {errors[1]:.3g}"


def test_table_extrapolates_linearly_and_inverts():
    law = TableLaw(((0, 1e5, 2e5),), ((0, 1e-9, 4e-9),))
    slope = float(law.phase_slope(0, 2e5))
    assert slope > 0, "end slope"
    assert float(law.phase_rate(0, 5e5)) == pytest.approx(4e-9 + 3e5 * slope, rel=1e-14)
    assert float(law.phase_rate(0, -1.0)) == 0.0, "no wear below 0 Pa"
    for rate in (1e-12, 1e-9, 2.5e-9, 1e-8):
        p = law.phase_pressure(0, rate)
        assert float(law.phase_rate(0, p)) == pytest.approx(rate, rel=1e-12), f"rate {rate}"


def test_table_run_in_reaches_steady():
    table, _ = sampled_table(9)
    assert_reaches_steady(table, "table of 9 points")


def test_table_with_a_zero_rate_start_acts_as_a_threshold():
    p = np.array([0.0, 0.5 * PBAR, 4 * PBAR])
    table = TableLaw([p, p], [[0.0, 0.0, 3.5 * K1 * PBAR], [0.0, 0.0, 35 * K1 * PBAR]])
    result, wp = assert_reaches_steady(table, "table with a zero start")
    pressures = table.phase_pressures(wp.counts, wp.normal_force, wp.halfspace.h ** 2)
    assert np.all(pressures > 0.5 * PBAR), f"steady pressures {pressures}"


def test_table_flat_at_pbar_reaches_its_steady_face():
    # Phase 1 (30 %) wears at 2 K1 pbar from 0.8 to 1.2 pbar, a plateau around pbar where the
    # slope is 0; its steady pressure, 2.42 pbar, lies beyond it.
    r = K1 * PBAR
    table = TableLaw(((0, PBAR, 4 * PBAR), (0, 0.8 * PBAR, 1.2 * PBAR, 4 * PBAR)),
                     ((0, 10 * r, 40 * r), (0, 2 * r, 2 * r, 10 * r)))
    assert float(table.phase_slope(1, PBAR)) == 0.0, "test setup: flat at pbar"
    rate_constants = table.rate_constant(table.wear_field(np.arange(2)), PBAR)
    assert np.allclose(rate_constants, [10 * K1, 2 * K1], rtol=1e-14, atol=0), \
        f"the secants g_i(pbar) / pbar: {rate_constants}"
    _, wp = assert_reaches_steady(table, "table flat at pbar")
    pressures = table.phase_pressures(wp.counts, wp.normal_force, wp.halfspace.h ** 2)
    assert pressures[1] > 1.2 * PBAR, f"steady pressures {pressures / PBAR} pbar"


def test_a_load_on_a_flat_part_names_the_table(tmp_path, capsys):
    # Phase 0's rate stays 1e-9 from 1e5 Pa on; 10 N on the disk needs more of it.
    law = ('[wear]\nlaw = "table"\npressures = [[0, 1e5, 2e5], [0, 1e5, 2e5]]\n'
           "rates = [[0, 1e-9, 1e-9], [0, 1e-8, 3e-8]]\n")
    for force, status_wanted in ((2.0, 0), (10.0, 2)):
        path = tmp_path / f"scene_{force:g}.toml"
        path.write_text(re.sub(r"^\[wear\]\ncoefficients = .*\n", law,
                               scene_text("steady", normal_force=force), flags=re.M))
        status, _, err = run_cli(steady_cli, [path, "-o", tmp_path / "out.h5", "--force",
                                              "--no-slope-error"], capsys)
        assert status == status_wanted, f"{force} N: {err}"
    line = one_error_line(err)
    assert ("falls on a flat part of the wear table of phase 0 (pressures [0.0, 100000.0, "
            "200000.0] Pa, rates [0.0, 1e-09, 1e-09]): its rate is 1e-09 at every pressure from "
            "100000 Pa on, so the steady pressures are not unique" in line), line


def test_table_scales_are_named_in_the_table_s_terms(tmp_path):
    # Phase 0 wears 1e-40 at 1e5 Pa: its secant at pbar = 2e5 Pa is 1e-45 1/Pa.
    law = ('[wear]\nlaw = "table"\npressures = [[0, 1e5], [0, 1e5]]\n'
           "rates = [[0, 1e-40], [0, 1e-8]]\n")
    text = re.sub(r"^\[wear\]\ncoefficients = .*\n", law, scene_text("steady"), flags=re.M)
    with pytest.raises(ValueError) as err:
        parse_scene(text, tmp_path)
    message = str(err.value)
    assert message.startswith("[wear] law = 'table', pressures = [[0.0, 100000.0], [0.0, "
                              "100000.0]], rates = [[0.0, 1e-40], [0.0, 1e-08]] and"), message
    assert ("the rate constant of phase 0, the secant g_i(z_i + pbar) / pbar above the last "
            "zero rate z_i = 1e-45 1/Pa is outside" in message), message
    assert "power law" not in message and "coefficients" not in message, message


@pytest.mark.parametrize("pressures, rates, fragment", [
    ([[0, 1]], [[0, 1, 2]], "must be lists of the same length"),
    ([[0]], [[0]], "needs at least 2 points, got 1"),
    ([[0, 2, 1]], [[0, 1, 2]], "pressures must increase, got [0.0, 2.0, 1.0] Pa"),
    ([[0, 1, 2]], [[0, 2, 1]], "rates must not decrease, got [0.0, 2.0, 1.0]"),
    ([[1, 2]], [[0, 1]], "must start at p = 0 Pa with rate 0"),
    ([[0, 1]], [[0, 0]], "the phase never wears"),
    ([[0, 1]], [[0, float("nan")]], "must be finite"),
])
def test_bad_tables_are_refused(pressures, rates, fragment):
    with pytest.raises(ValueError) as err:
        TableLaw(pressures, rates)
    assert fragment in str(err.value), str(err.value)


# -- scenes and commands --------------------------------------------------------
def test_scene_keys_build_the_laws(tmp_path):
    text = scene_text("steady").replace("[wear]\n", '[wear]\nlaw = "threshold"\n'
                                        "thresholds = [0.0, 1.0e4]\n")
    scene = parse_scene(text, tmp_path)
    assert scene.wear == ThresholdLaw((1e-9, 1e-8), (0.0, 1e4)), scene.wear
    table = wear_law_from_table({"law": "table", "pressures": [[0, 1e5], [0, 1e5]],
                                 "rates": [[0, 1e-9], [0, 1e-8]]}, n_phases=2)
    assert isinstance(table, TableLaw) and table.n_phases == 2, table
    with pytest.raises(ValueError, match=r"\[wear\] pressures has 1 lists \[\[0.0, 100000.0\]\] "
                                         r"but the phase map has 2 phases"):
        wear_law_from_table({"law": "table", "pressures": [[0, 1e5]], "rates": [[0, 1e-9]]},
                            n_phases=2)
    with pytest.raises(ValueError, match=r"\[wear\] thresholds must be an array of numbers"):
        wear_law_from_table({"law": "threshold", "coefficients": [1e-9],
                             "thresholds": 3.0}, n_phases=1)
    with pytest.raises(ValueError, match=r"\[wear\] thresholds must be an array of numbers each "
                                         r">= 0 \(Pa\), got \[-1.0\]"):
        wear_law_from_table({"law": "threshold", "coefficients": [1e-9],
                             "thresholds": [-1.0]}, n_phases=1)
    with pytest.raises(ValueError, match=r"wear thresholds must be an array of numbers each "
                                         r">= 0 \(Pa\), got \[0.0, -1.0\]"):
        ThresholdLaw([1e-9, 1e-9], [0.0, -1.0])
    solved = solve_scene(scene, face_only=True)
    assert solved.phase_pressures[1] > 1e4, solved.phase_pressures


def test_steady_command_refuses_thresholds_above_the_load(tmp_path, capsys):
    path = tmp_path / "scene.toml"
    path.write_text(scene_text("steady").replace(
        "[wear]\n", '[wear]\nlaw = "threshold"\nthresholds = [1.0e6, 1.0e6]\n'))
    status, _, err = run_cli(steady_cli, [str(path), "-o", str(tmp_path / "out.h5")], capsys)
    assert status == 2, err
    assert "Traceback" not in err and "wear thresholds p_th = [1000000.0, 1000000.0] Pa" in err, err


def test_the_fit_refuses_other_laws():
    for law in (ThresholdLaw((K1, K1), (1e3, 1e3)), sampled_table(5)[0]):
        with pytest.raises(ValueError, match="the fit supports the power law k p\\^m, not the "):
            FaceModel(steady_problem(law, n=16))


def test_bench_wear_laws_smoke(tmp_path):
    module = benchmark("bench_wear_laws")
    out = tmp_path / "bench.h5"
    rows = module.main(["--sizes", "40", "--out", str(out)])
    assert [r["law"] for r in rows] == ["archard", "threshold"], rows
    assert all(r["status"] == "steady" and r["failures"] == 0 for r in rows), rows
    with h5py.File(out) as f:
        assert f.attrs["format"] == "runin.bench_wear_laws" and len(f) == 2, dict(f.attrs)
    with pytest.raises(OutputExistsError):
        module.main(["--sizes", "40", "--out", str(out)])


def test_resume_refuses_other_thresholds(tmp_path, capsys):
    def scene(thresholds):
        path = tmp_path / f"scene_{thresholds[1]:g}.toml"
        path.write_text(scene_text("runin").replace(
            "[wear]\n", f'[wear]\nlaw = "threshold"\nthresholds = {list(thresholds)}\n'))
        return str(path)

    out = str(tmp_path / "run.h5")
    status, _, err = run_cli(transient_cli, [scene((1e5, 1.2e5)), "-o", out], capsys)
    assert status == 0, err
    status, _, err = run_cli(transient_cli, [scene((1e5, 1.3e5)), "-o", out, "--resume"],
                             capsys)
    assert status == 2 and "was run with another wear law" in err and "130000.0" in err, err
    status, _, err = run_cli(transient_cli, [scene((1e5, 1.2e5)), "-o", out, "--resume"],
                             capsys)
    assert status == 0, err


# -- the contract: every shipped law answers it ----------------------------------------------
SHIPPED = {
    "power": PowerLaw((K1, 3 * K1, 10 * K1), 1.5),
    "archard": ArchardLaw((K1, 3 * K1, 10 * K1)),
    "threshold": ThresholdLaw((K1, 3 * K1, 10 * K1), (0.0, 0.3 * PBAR, 0.1 * PBAR), 2.0),
    "table": TableLaw(((0, PBAR, 2 * PBAR), (0, PBAR), (0, 0.5 * PBAR, 3 * PBAR)),
                      ((0, 1e-9, 4e-9), (0, 1e-8), (0, 1e-9, 2e-8))),
}


def test_every_registered_law_is_tested():
    assert set(SHIPPED) == set(WEAR_LAWS), f"registered {sorted(WEAR_LAWS)}"
    for kind, law in SHIPPED.items():
        assert type(law) is WEAR_LAWS[kind] and law.kind == kind, kind


@pytest.mark.parametrize("kind", sorted(SHIPPED))
def test_file_attributes_read_back_the_same_law(kind):
    law = SHIPPED[kind]
    attrs = {name: value for name, (value, _) in wear_file_attributes(law).items()}
    back = wear_law_from_file(attrs)
    assert back == law and same_wear_law(back, law), f"{kind}: {back} != {law}"
    assert attrs["wear_law_kind"] == kind and attrs["wear_law"] == law.describe(), attrs


@pytest.mark.parametrize("kind", sorted(SHIPPED))
def test_restriction_keeps_the_phases_steady_state(kind):
    law = SHIPPED[kind]
    counts = np.array([60, 0, 40])  # a section without phase 1
    kept = law.restrict([0, 2])
    assert kept.n_phases == 2 and type(kept) is type(law), kept
    full = law.phase_pressures(counts, FORCE, 1e-8)
    restricted = kept.phase_pressures(counts[[0, 2]], FORCE, 1e-8)
    assert np.allclose(full[[0, 2]], restricted, rtol=1e-12, atol=0), (full, restricted)
    with pytest.raises(ValueError, match=r"phases \[0, 3\] must be a non-empty subset of 0..2"):
        law.restrict([0, 3])


@pytest.mark.parametrize("kind", sorted(SHIPPED))
def test_scene_words_read_back_through_the_scene_keys(kind):
    law = SHIPPED[kind]
    table = dict(law.scene_values(), law=kind)
    assert wear_law_from_table(table, n_phases=3) == law, kind
    words = law.scene_words()
    assert "np.float64" not in words and words.startswith("[wear] "), words
    assert ("law = " in words) == (kind != "power"), words


def test_only_the_power_family_factorises_and_only_archard_is_linear():
    capabilities = {kind: (law.linear, law.factor is not None,
                           None if law.factor is None else law.factor.exponent)
                    for kind, law in SHIPPED.items()}
    assert capabilities == {"power": (False, True, 1.5), "archard": (True, True, 1.0),
                            "threshold": (False, False, None), "table": (False, False, None)}, \
        capabilities


def test_same_wear_law_tells_equal_laws_from_others():
    assert same_wear_law(ArchardLaw((K1, 2 * K1)), PowerLaw((K1, 2 * K1), 1.0)), \
        "Archard's law is the power law with m = 1"
    assert not same_wear_law(ThresholdLaw((K1, 2 * K1), (0.0, 0.0)), PowerLaw((K1, 2 * K1))), \
        "a threshold law is another law, even with thresholds 0"
    assert not same_wear_law(None, PowerLaw((K1, 2 * K1))), "an unknown law is no law"


def test_no_law_class_is_asked_for_outside_the_law_module():
    """Callers ask the law (its methods and capabilities), never which class it is."""
    import ast

    names = {"WearLaw", *(cls.__name__ for cls in (WEAR_LAWS[kind] for kind in WEAR_LAWS))}
    root = pathlib.Path(__file__).resolve().parents[1]
    found = []
    for package in ("steady", "transient"):
        for path in (root / package).rglob("*.py"):
            if path == root / "steady" / "wear.py":
                continue
            for node in ast.walk(ast.parse(path.read_text())):
                if (isinstance(node, ast.Call) and getattr(node.func, "id", "") in (
                        "isinstance", "issubclass") and len(node.args) == 2):
                    classes = ast.walk(node.args[1])
                    found += [f"{path.relative_to(root)}:{node.lineno}" for c in classes
                              if isinstance(c, (ast.Name, ast.Attribute))
                              and getattr(c, "id", getattr(c, "attr", "")) in names]
    assert not found, f"isinstance of a wear law class: {found}"
