"""Load programmes: ``[load] programme``, a normal force that changes in steps.

A programme with one constant force is today's run bit for bit; the steps
land on the breakpoints, where the history's force changes; the run ends on
the steady face of the last force (eq. 9 under it: for the linear law the
face scales with the load); a resumed run repeats the uninterrupted one bit
for bit across a breakpoint; a bad programme is refused with its value.
"""

import importlib
import pathlib

import h5py
import numpy as np
import pytest
from conftest import run_cli, scene_text

from steady.load_programme import LoadProgramme
from steady.scene import parse_scene, problem_of
from transient import RunOptions, compare_with_steady, run_in
from transient.cli import runin as runin_cli
from transient.output import read_run, write_run
from transient.result import HISTORY_UNITS
from transient.scene import wear_problem_of
from transient.stepping import SCHEMES

STUDIES = pathlib.Path(__file__).resolve().parent.parent / "studies"

#: The gallery run-in scene's distance scale s* = a / (k_min E*), m.
S_STAR = 0.004 / (1.0e-13 * 1.3e6)

#: Options of the runs here: a loose step tolerance, tight stop tests.
OPTIONS = RunOptions(tol=1e-3)


def programme_text(programme, **overrides):
    """The gallery's run-in scene with ``[load] programme`` (a list of [s, F] pairs)."""
    text = scene_text("runin", **overrides)
    pairs = ", ".join(f"[{s!r}, {f!r}]" for s, f in programme)
    return text.replace("normal_force = 10.0\n", f"normal_force = 10.0\nprogramme = [{pairs}]\n")


def run(programme=None, *, options=OPTIONS, **kwargs):
    """A run of the gallery scene under ``programme`` (None: none) and its wear problem."""
    text = scene_text("runin") if programme is None else programme_text(programme)
    problem = wear_problem_of(parse_scene(text, "."))
    return run_in(problem, np.zeros(problem.shape), options, **kwargs), problem


def _same_run(a, b, what):
    assert a.status == b.status and a.steps == b.steps, \
        f"{what}: {a.status} in {a.steps} steps against {b.status} in {b.steps}"
    assert np.array_equal(a.recession, b.recession, equal_nan=True), f"{what}: face differs"
    assert np.array_equal(a.pressure, b.pressure), f"{what}: pressure differs"
    assert a.distance == b.distance and a.offset == b.offset, f"{what}: distance or offset"
    for name in HISTORY_UNITS:
        assert np.array_equal(a.history[name], b.history[name], equal_nan=True), \
            f"{what}: history {name} differs"


def test_one_constant_force_is_todays_run_bit_for_bit():
    plain, _ = run()
    constant, _ = run([(0.0, 10.0)])
    _same_run(constant, plain, "programme [[0, 10 N]]")
    assert "force" not in plain.history, "a run without programme records no force"
    assert np.all(constant.history["force"] == 10.0), "the force history is the constant force"


def test_steps_land_on_the_breakpoints_and_the_force_follows():
    breaks = (0.05 * S_STAR, 0.4 * S_STAR)
    result, problem = run([(breaks[0], 20.0), (breaks[1], 5.0)])
    assert result.status == "steady", result.message
    distance, force = result.history["distance"], result.history["force"]
    for s in breaks:
        assert s in distance, f"no history point exactly at the breakpoint {s!r} m"
    expected = np.where(distance < breaks[0], 10.0, np.where(distance < breaks[1], 20.0, 5.0))
    assert np.array_equal(force, expected), f"force history {force} against {expected}"
    assert result.distance > breaks[1], "the run ended before the last breakpoint"
    # The contact carries the force of each point: the pressure's integral.
    area = problem.halfspace.h ** 2
    assert abs(float(np.sum(result.pressure[problem.face_mask])) * area - 5.0) < 1e-9 * 5.0, \
        "the final pressure does not carry the last force"


def test_before_a_step_up_the_history_is_the_constant_load_one():
    # With the same fixed steps the run up to a step up of the load is the run at constant
    # load: the face, and the rms slope, whose rim layer the estimator weighs by
    # (10 N / 20 N)^2 against the final force's grad_f0 (equal to round-off, measured
    # 2.2e-16; the worn depth 9.2e-16).  At the breakpoint the face has not moved.
    options = RunOptions(scheme="bdf2", fixed_step=0.02 * S_STAR, distance_limit=0.1 * S_STAR)
    plain, _ = run(options=options)
    result, _ = run([(0.1 * S_STAR, 20.0)], options=options)
    assert result.history["force"][-1] == 20.0, "the run did not reach the breakpoint"
    slope, expected = result.history["rms_slope"], plain.history["rms_slope"]
    assert slope.shape == expected.shape, f"{slope.shape} points against {expected.shape}"
    assert np.allclose(slope, expected, rtol=1e-12, atol=0.0), \
        f"rms slope {slope} against {expected} at constant load"
    mask = np.isfinite(plain.worn_depth)
    worn, expected = result.worn_depth[mask], plain.worn_depth[mask]
    error = np.max(np.abs(worn - expected)) / np.max(np.abs(expected))
    assert error < 1e-12, f"worn depth differs by {error:.3g} (the last step lands by round-off)"


def test_no_steady_state_and_no_jump_before_the_last_breakpoint():
    # The same force from 6 s* on: nothing changes but the run must get there,
    # well beyond the distance (about 4 s*) at which it is steady without it.
    plain, _ = run()
    held, _ = run([(6.0 * S_STAR, 10.0)])
    assert plain.distance < 6.0 * S_STAR, f"plain run steady at {plain.distance / S_STAR} s*"
    assert held.status == "steady", held.message
    assert 6.0 * S_STAR in held.history["distance"], "no history point at the breakpoint"
    assert held.distance >= 6.0 * S_STAR, f"steady at {held.distance / S_STAR:.3g} s*"


def test_final_face_is_the_steady_face_of_the_last_force():
    result, problem = run([(0.1 * S_STAR, 20.0)])
    assert problem.normal_force == 20.0, "the problem's load is the programme's last force"
    steady = problem.solve_steady()
    comparison = compare_with_steady(result, steady, problem)
    assert comparison.face_error < 1e-6, f"face error {comparison.face_error:.3g}"
    # The linear law's steady face scales with the load: twice that of 10 N.
    plain, plain_problem = run()
    first = plain_problem.solve_steady()
    mask = problem.face_mask
    ratio = np.ptp(steady.face[mask]) / np.ptp(first.face[mask])
    assert abs(ratio - 2.0) < 1e-12, f"steady relief ratio {ratio!r}, expected 2"
    worn = np.ptp(result.face[mask]) / np.ptp(plain.face[mask])
    assert abs(worn - 2.0) < 1e-5, f"run-in relief ratio {worn!r}, expected 2"


@pytest.mark.parametrize("name", sorted(SCHEMES))
@pytest.mark.parametrize("exponent", [1.0, 2.0])
def test_every_scheme_ends_on_the_steady_face_of_the_last_force(name, exponent):
    # Up, then down below the first force; a power law's rate constant at the mean
    # pressure kept near the linear law's (k 2 pbar with pbar about 2e5 Pa).
    k = (1.0e-13, 1.0e-12) if exponent == 1.0 else (1.0e-13 / 2.6e5, 1.0e-12 / 2.6e5)
    text = programme_text([(0.05 * S_STAR, 20.0), (0.2 * S_STAR, 5.0)], exponent=exponent,
                          coefficients=k)
    problem = wear_problem_of(parse_scene(text, "."))
    result = run_in(problem, np.zeros(problem.shape), RunOptions(tol=1e-3, scheme=name))
    assert result.status == "steady", result.message
    assert result.history["force"][-1] == 5.0, "the run did not end under the last force"
    comparison = compare_with_steady(result, problem.solve_steady(), problem)
    # Measured 6e-9 (m = 2) and 1.1e-8 (m = 1) for every scheme: the jump's precision.
    assert comparison.face_error < 1e-6, f"{name}, m = {exponent}: face error " \
                                         f"{comparison.face_error:.3g}"


def _from_steady_face(programme, options):
    """A run under ``programme`` from the steady face of 10 N (eq. 9), and its problem."""
    problem = wear_problem_of(parse_scene(programme_text(programme), "."))
    first = wear_problem_of(parse_scene(scene_text("runin"), ".")).solve_steady()
    return run_in(problem, -np.where(problem.face_mask, first.face, 0.0), options)


def test_a_load_step_from_the_steady_face_is_the_run_in_from_flat_scaled():
    # The linear law's dynamics is linear in the deviation e = f - f_inf(F) as long as the
    # whole face stays in contact.  From f_inf(F_1) under F_2 the deviation starts at
    # (F_1 / F_2 - 1) f_inf(F_2), from flat at -f_inf(F_2): with the same fixed steps the
    # face deviations after a step up from 10 N to 20 N are the flat run's times
    # |1 - F_1 / F_2| = 1/2, to the contact solves' tolerance (measured 3.9e-9).  BDF2
    # restarts at the breakpoint as at s = 0; without the restart the two would differ.
    s_b = 0.2
    step = _from_steady_face([(s_b * S_STAR, 20.0)],
                             RunOptions(scheme="bdf2", fixed_step=0.02 * S_STAR,
                             distance_limit=(s_b + 0.4) * S_STAR))
    problem = wear_problem_of(parse_scene(scene_text("runin", normal_force=20.0), "."))
    flat = run_in(problem, np.zeros(problem.shape),
                  RunOptions(scheme="bdf2", fixed_step=0.02 * S_STAR, distance_limit=0.4 * S_STAR))
    distance = step.history["distance"]
    at = int(np.flatnonzero(distance == s_b * S_STAR)[0])
    after, reference = step.history["face_deviation"][at:], flat.history["face_deviation"]
    assert after.shape == reference.shape, f"{after.shape} points against {reference.shape}"
    error = np.max(np.abs(after - 0.5 * reference) / (0.5 * reference))
    assert error < 1e-7, f"relative difference {error:.3g} from half the run-in from flat"
    assert np.all(step.history["contact_fraction"] == 1.0), "the face lost contact"


def test_a_load_step_down_lifts_the_rim_off():
    # Halving the load of the steady face: the pressure increment is the flat punch's
    # under -F/2, singular at the rim, so the rim lifts off (measured: 61 % of the face in
    # contact right after the step) and the response is no longer the scaled run-in.
    s_b = 0.2
    step = _from_steady_face([(s_b * S_STAR, 5.0)],
                             RunOptions(scheme="bdf2", fixed_step=0.02 * S_STAR,
                             distance_limit=(s_b + 0.1) * S_STAR))
    distance, contact = step.history["distance"], step.history["contact_fraction"]
    before = distance < s_b * S_STAR
    assert np.all(contact[before] == 1.0), "contact lost before the step"
    assert contact[~before][0] < 0.8, f"contact fraction {contact[~before][0]:.3g} after it"


def test_steady_problem_of_a_programme_scene_takes_the_last_force():
    scene = parse_scene(programme_text([(0.0, 12.0), (1.0, 7.5)]), ".")
    assert scene.normal_force == 10.0 and scene.final_force == 7.5, \
        (scene.normal_force, scene.final_force)
    assert scene.load_programme == LoadProgramme(10.0, ((0.0, 12.0), (1.0, 7.5))), \
        scene.load_programme
    assert problem_of(scene).normal_force == 7.5, "steady problem not at the last force"


def test_resume_across_a_breakpoint_is_bit_for_bit(tmp_path):
    programme = [(0.05 * S_STAR, 20.0), (0.3 * S_STAR, 15.0)]
    checkpoints = []
    full, _ = run(programme, options=RunOptions(tol=1e-3, checkpoint_interval=0.0),
                  on_checkpoint=checkpoints.append)
    assert full.status == "steady", full.message
    distances = [c.distance for c in checkpoints]
    at = distances.index(programme[0][0])
    for index in (at - 1, at, at + 1):
        path = tmp_path / f"ckpt{index}.h5"
        write_run(path, checkpoints[index])
        saved, _, _ = read_run(path)
        assert saved.load_programme == checkpoints[index].load_programme, \
            "the run file does not keep the programme"
        text = programme_text(programme)
        problem = wear_problem_of(parse_scene(text, "."))
        resumed = run_in(problem, None, RunOptions(tol=1e-3, checkpoint_interval=0.0),
                         resume=saved)
        _same_run(resumed, full, f"resumed from checkpoint {index}")
        assert np.array_equal(resumed.history["force"], full.history["force"]), \
            f"force history differs after resuming from checkpoint {index}"


def test_run_file_marks_the_breakpoints(tmp_path, capsys):
    programme = [(0.05 * S_STAR, 20.0)]
    scene = tmp_path / "scene.toml"
    scene.write_text(programme_text(programme, transient={"tol": 1e-3,
                                                          "snapshots_s_star": (0.01, 0.1)}))
    out = tmp_path / "run.h5"
    status, _, err = run_cli(runin_cli, [scene, "-o", out], capsys)
    assert status == 0, err
    with h5py.File(out) as f:
        hist = f["history"]
        assert hist["force"].attrs["units"] == "N", dict(hist["force"].attrs)
        assert np.array_equal(hist["load_breakpoints"][()], [programme[0][0]]), \
            hist["load_breakpoints"][()]
        assert hist["load_breakpoints"].attrs["units"] == "m", dict(hist["load_breakpoints"].attrs)
        assert np.array_equal(hist["load_forces"][()], [programme[0][1]]), hist["load_forces"][()]
        assert [d[0].name for d in hist["load_forces"].dims] == ["/history/load_breakpoints"], \
            "one force per breakpoint"
        assert np.array_equal(f["snapshots/force"][()], [10.0, 20.0]), f["snapshots/force"][()]


def test_resume_refuses_another_programme(tmp_path, capsys):
    scene = tmp_path / "scene.toml"
    scene.write_text(programme_text([(0.05 * S_STAR, 20.0)],
                                    transient={"tol": 1e-3, "distance_limit": 0.1 * S_STAR}))
    out = tmp_path / "run.h5"
    status, _, err = run_cli(runin_cli, [scene, "-o", out], capsys)
    assert status == 1, f"a stopped run exits 1, got {status}: {err}"
    scene.write_text(programme_text([(0.05 * S_STAR, 30.0)],
                                    transient={"tol": 1e-3, "distance_limit": 0.2 * S_STAR}))
    status, _, err = run_cli(runin_cli, [scene, "-o", out, "--resume"], capsys)
    assert status == 2 and "was run with another [load] programme" in err, (status, err)


@pytest.mark.parametrize("value, match", [
    ("[]", "[load] programme must hold at least one [distance, force] pair, got []"),
    ("[[1.0, 5.0], [0.5, 6.0]]", "distances must increase, got 0.5 m after 1.0 m"),
    ("[[1.0, 5.0], [1.0, 6.0]]", "distances must increase, got 1.0 m after 1.0 m"),
    ("[[-1.0, 5.0]]", "[load] programme pair 0 distance must be a number >= 0 (m), got -1.0"),
    ("[[0.0, 5.0], [2.0, 0.0]]", "[load] programme pair 1 force must be a number > 0 (N), got 0.0"),
    ("[[0.0, -3.0]]", "[load] programme pair 0 force must be a number > 0 (N), got -3.0"),
    ("[[0.0, inf]]", "[load] programme must be an array of [x, y] pairs (m, N), got"),
    ("[[0.0, 5.0, 1.0]]", "[load] programme must be an array of [x, y] pairs (m, N), got"),
    ("5.0", "[load] programme must be an array of [x, y] pairs (m, N), got 5.0"),
    ("[[0.0, 1e40]]", "[load] programme force 1e+40 N is outside [1e-30, 1e+30] N"),
])
def test_bad_programmes_are_refused_naming_the_value(value, match):
    text = scene_text("runin").replace("normal_force = 10.0\n",
                                       f"normal_force = 10.0\nprogramme = {value}\n")
    with pytest.raises(ValueError) as info:
        parse_scene(text, ".")
    assert match in str(info.value), f"message {str(info.value)!r} lacks {match!r}"


def test_bad_programme_on_the_command_line_exits_2(tmp_path, capsys):
    scene = tmp_path / "scene.toml"
    scene.write_text(programme_text([(1.0, 5.0), (0.5, 6.0)]))
    status, _, err = run_cli(runin_cli, [scene, "-o", tmp_path / "run.h5"], capsys)
    assert status == 2, f"exit status {status}"
    assert "distances must increase, got 0.5 m after 1.0 m" in err and "Traceback" not in err, \
        err


def test_load_step_study_quick(tmp_path, monkeypatch):
    monkeypatch.syspath_prepend(str(STUDIES))
    study = importlib.import_module("load_step")
    h5, png = tmp_path / "load_step.h5", tmp_path / "load_step.png"
    assert study.main(["--quick", "-o", str(h5), "--png", str(png)]) == 0, "study failed"
    assert png.stat().st_size > 10000, "no figure"
    with h5py.File(h5) as f:
        up, flat = f.attrs["factor_2_resettle"], f.attrs["constant_resettle"]
        # Half the deviation of the run from flat: within 1 % sooner (quick: 0.86 vs 1.14 s*).
        assert 0.5 * flat < up < flat, f"re-settled after {up:.3g} s*, from flat {flat:.3g}"
        assert f["factor_0.5/contact_fraction"][()].min() < 0.8, "the rim did not lift off"
        final = f["factor_2/rms_slope"][-1] / f["constant/rms_slope"][-1]
        assert abs(final - 2.0) < 0.01, f"final rms slope ratio {final:.4g}, expected 2"
