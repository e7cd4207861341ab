"""Scales out of range are bad input (exit 2, naming the key), never an overflow or garbage.

Huge or tiny lengths, forces and moduli and extreme wear exponents or
coefficients ended in ``unexpected OverflowError`` with exit status 1
("resumable"), in a run that failed at its first step, or in a result of 0
with exit 0.  Every scale of a problem -- its inputs, and the pixel, mean
pressure, reference slope, depth scale, phase pressures, wear rate and rate
constants that follow from them, for a run-in its distances -- must lie in
``steady.problem.SCALE_RANGE`` (SI units); within it the normalised results do
not depend on the units.
"""

import dataclasses
import math

import numpy as np
import pytest
from conftest import scene_text

import steady.cli.fit as fit_cli
import steady.cli.solve as steady_cli
import transient.__main__ as transient_cli
from steady.outline import Circle, Rectangle
from steady.phases import Voronoi
from steady.problem import SCALE_RANGE, FacePhases, Problem
from steady.rms_slope import estimate_rms_slope
from steady.scene import load_scene
from steady.solution import solve, solve_scene
from steady.wear import PowerLaw
from transient.problem import WearProblem
from transient.scene import wear_problem_of

PRECIOUS = b"a result someone cares about"
RANGE = "is outside [1e-30, 1e+30]"

#: An exponent of 50 with coefficients that keep the rate at pbar that of the
#: base scene: finite everywhere but at the pressures of a few pixels.
K50 = (1e-13 * (4e5) ** -49, 1e-12 * (4e5) ** -49)


def _mask(d):
    np.save(d / "m.npy", np.ones((8, 8), dtype=bool))


CASES = [
    # name, scene overrides, fragment, commands
    ("radius 1e200", dict(radius=1e200), f"[punch] radius = 1e+200 m {RANGE} m", None),
    ("radius 1e-200", dict(radius=1e-200), f"[punch] radius = 1e-200 m {RANGE} m", None),
    ("semi-axes 1e300", dict(punch={"shape": "ellipse", "semi_axis_x": 1e300,
                                    "semi_axis_y": 1e300}),
     f"[punch] semi_axis_x = 1e+300 m {RANGE} m", None),
    ("rectangle 1e300", dict(punch={"shape": "rectangle", "width": 1e300, "length": 2e300}),
     f"[punch] width = 1e+300 m {RANGE} m", None),
    ("mask pixel 1e300", dict(punch={"shape": "mask", "path": "m.npy", "pixel_size": 1e300},
                              map="homogeneous", coefficients=(1e-13,), n=64),
     f"[punch] pixel_size = 1e+300 m {RANGE} m", None),
    ("force 1e300", dict(normal_force=1e300), f"[load] normal_force = 1e+300 N {RANGE} N", None),
    ("force 1e-300", dict(normal_force=1e-300), f"[load] normal_force = 1e-300 N {RANGE} N",
     None),
    ("E* 1e300", dict(E_star=1e300), f"[counterbody] E_star = 1e+300 Pa {RANGE} Pa", None),
    ("E* 1e-300", dict(E_star=1e-300), f"[counterbody] E_star = 1e-300 Pa {RANGE} Pa", None),
    ("pixel 1e-32", dict(radius=2e-30, normal_force=1e-30, E_star=1e-30),
     f"[punch] radius = 2e-30 and [grid] n = 32: the pixel h = 2 L / n = 1.25e-31 m {RANGE} m",
     ("transient",)),
    ("pbar 1e-30", dict(radius=10.0, normal_force=1e-28),
     f"[load] normal_force = 1e-28 and [punch] radius = 10.0: the mean pressure pbar = F_N / A "
     f"= 3.18e-31 Pa {RANGE} Pa", None),
    ("exponent 1e6", dict(exponent=1e6),
     f"exponent = 1000000.0 and [load] normal_force = 10.0 and [punch] radius = 0.004: the rate "
     f"constant of phase 0, dg/dp at pbar = k m pbar^(m-1) = inf 1/Pa {RANGE} "
     f"1/Pa", None),
    ("k 5e-324", dict(coefficients=(5e-324, 1e-12)),
     "[wear] coefficients = [5e-324, 1e-12], exponent = 1.0 and [load] normal_force = 10.0 and "
     "[punch] radius = 0.004: the rate constant of phase 0", None),
    ("ratio 1e300", dict(coefficients=(1e-150, 1e150)),
     "[wear] coefficients = [1e-150, 1e+150], exponent = 1.0 and [load] normal_force = 10.0",
     None),
    ("ratio 1e40", dict(coefficients=(1e-13, 1e27)),
     f"the steady pressure of phase 1 (eq. 7) = 2.84e-35 Pa {RANGE} Pa", ("transient",)),
    ("exponent 0.01", dict(exponent=0.01, coefficients=(1e-13, 1e-12)),
     f"the steady pressure of phase 1 (eq. 7) = 2.84e-95 Pa {RANGE} Pa", ("transient",)),
    ("rod radius 1e-300", dict(map="rods", centres=((0.0, 0.0), (0.002, 0.0)),
                               radii=(1e-3, 1e-300)),
     f"[phases] map radii = [0.001, 1e-300]: 1e-300 m {RANGE} m", None),
    ("sphere radius 1e300", dict(initial_face={"kind": "crowned", "sphere_radius": 1e300}),
     f"[initial_face] sphere_radius = 1e+300 m {RANGE} m", ("transient",)),
    ("aspect 1e-58", dict(punch={"shape": "ellipse", "semi_axis_x": 1e-29,
                                 "semi_axis_y": 1e29}),
     "grid too coarse for the ellipse face (semi_axis_x 1e-26 mm, semi_axis_y 1e+32 mm): "
     "n = 32, the minimum is n = 8e+58", ("transient",)),
    ("exponent 50, run-in", dict(exponent=50.0, coefficients=K50),
     "[grid] n = 32: the wear rate of a pixel carrying the whole load, g(F_N / h^2) of the "
     "fastest phase, is inf, above 1e+200", ("transient",)),
]


def _params():
    for name, overrides, fragment, commands in CASES:
        for command in commands or ("steady", "transient"):
            yield pytest.param(overrides, fragment, command, id=f"{command}: {name}")


@pytest.mark.parametrize("overrides, fragment, command", list(_params()))
def test_a_scale_out_of_range_is_bad_input(tmp_path, capsys, overrides, fragment, command):
    _mask(tmp_path)
    scene = tmp_path / "s.toml"
    scene.write_text(scene_text("steady" if command == "steady" else "runin", **overrides))
    (tmp_path / "out.h5").write_bytes(PRECIOUS)
    module = steady_cli if command == "steady" else transient_cli
    status = module.main([str(scene), "-o", str(tmp_path / "out.h5"), "--force"])
    out, err = capsys.readouterr()
    lines = err.splitlines()
    assert status == 2, f"exit {status} (1 would call it resumable): {err!r}"
    assert len(lines) == 1 and lines[0].startswith(f"error: {scene}: "), \
        f"expected one 'error:' line naming the scene: {err!r}"
    assert fragment in lines[0], f"{lines[0]!r} lacks {fragment!r}"
    assert "unexpected" not in err and "resume" not in err, err
    assert out == "", f"stdout after a refusal: {out!r}"
    assert (tmp_path / "out.h5").read_bytes() == PRECIOUS, "the output was replaced"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m.npy", "out.h5", "s.toml"], \
        "a file was left behind"


@pytest.mark.parametrize("command, flag, fragment", [
    # A length flag is a scale like a scene's length: its range, named with the flag.
    ("transient", "--distance-limit", f"error: argument --distance-limit: 1e+300 m {RANGE} m"),
    ("fit", "--rim-margin", f"error: argument --rim-margin: 1e+300 m {RANGE} m"),
    ("fit", "--max-shift", f"error: argument --max-shift: 1e+300 m {RANGE} m"),
    # A step tolerance above 1 f* (more than the face's relief) is refused, not run to a failure.
    ("transient", "--tol", "error: argument --tol: expected a number in (2.22045e-16, 1] (f*), "
                           "got '1e300'"),
])
def test_a_flag_out_of_range_is_bad_input_named(tmp_path, capsys, command, flag, fragment):
    scene = tmp_path / "s.toml"
    scene.write_text(scene_text("runin"))
    np.save(tmp_path / "measured.npy", np.zeros((32, 32)))
    argv = ([str(scene), "-o", str(tmp_path / "out.h5")] if command == "transient" else
            [str(scene), str(tmp_path / "measured.npy"), "-o", str(tmp_path / "fit.h5"),
             "--pixel-size", "2.5e-4", "--shift"])
    try:
        status = (transient_cli if command == "transient" else fit_cli).main(
            [*argv, flag, "1e300"])
    except SystemExit as done:  # argument errors exit from the parser
        status = done.code
    out, err = capsys.readouterr()
    lines = err.splitlines()
    assert status == 2, f"exit {status}: {err!r}"
    assert len(lines) == 1 and lines[0].startswith(fragment), f"{lines!r} lacks {fragment!r}"
    assert out == "", f"stdout after a refusal: {out!r}"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["measured.npy", "s.toml"], \
        "a file was written"


def test_a_fit_length_out_of_range_is_refused_in_python_too(tmp_path):
    from steady.fit import fit_scene
    from steady.fit_files import read_measured

    (tmp_path / "s.toml").write_text(scene_text("runin"))
    np.save(tmp_path / "m.npy", np.zeros((32, 32)))
    measured = read_measured(tmp_path / "m.npy", pixel_size=2.5e-4)
    with pytest.raises(ValueError, match=r"rim_margin = 1e\+300 m is outside \[1e-30, 1e\+30\]"):
        fit_scene(load_scene(tmp_path / "s.toml"), measured, rim_margin=1e300)


def test_an_inclusion_radius_out_of_range_is_named(tmp_path, capsys):
    text = scene_text("steady", map="homogeneous").replace(
        'map = { kind = "homogeneous" }',
        'map = { kind = "inclusions", radius = 1e-300, fill_factor = 0.1, seed = 2417 }')
    (tmp_path / "s.toml").write_text(text)
    status = steady_cli.main([str(tmp_path / "s.toml"), "-o", str(tmp_path / "out.h5")])
    _, err = capsys.readouterr()
    assert status == 2, f"exit {status}: {err!r}"
    assert f"[phases] map radius = 1e-300 m {RANGE} m" in err, err


# -- from Python: the same checks, naming the arguments or the scene's keys ---------------
GRID = Circle(4e-3).grid(32)
LABELS = Voronoi(64, (0.6, 0.4), 2029).labels(GRID)


def problem(outline=None, force=10.0, E_star=1.3e6, wear=(1e-13, 1e-12)):
    grid = GRID if outline is None else outline.grid(32)
    labels = LABELS if outline is None else Voronoi(64, (0.6, 0.4), 2029).labels(grid)
    return Problem(FacePhases(grid, labels, 2), wear, force, E_star)


@pytest.mark.parametrize("kwargs, fragment", [
    (dict(force=1e300), f"normal_force = 1e+300 N {RANGE} N"),
    (dict(E_star=5e-324), f"E_star = 5e-324 Pa {RANGE} Pa"),
    (dict(outline=Circle(1e200)), f"Circle radius = 1e+200 m {RANGE} m"),
    (dict(outline=Rectangle(1e-31, 1e-31)), f"Rectangle width = 1e-31 m {RANGE} m"),
    (dict(wear=PowerLaw((1e-13, 1e-12), 1e6)),
     "the rate constant of phase 0, dg/dp at pbar = k m pbar^(m-1) = inf"),
    (dict(wear=(1e-150, 1e150)), "the rate constant of phase 0"),
])
def test_problem_refuses_scales_out_of_range(kwargs, fragment):
    with pytest.raises(ValueError) as info:
        problem(**kwargs)
    assert fragment in str(info.value), str(info.value)


def test_wear_problem_refuses_an_overflowing_peak_rate():
    steady_problem = problem(wear=PowerLaw(K50, 50.0))
    assert math.isfinite(solve(steady_problem).rms_slope), "the steady face is fine"
    with pytest.raises(ValueError, match=r"n = 32: the wear rate of a pixel carrying the whole "
                                         r"load, g\(F_N / h\^2\) of the fastest phase, is inf"):
        WearProblem(steady_problem)


def test_scene_objects_name_their_keys(tmp_path):
    """A Scene changed in Python is checked when its problem is built, naming the scene's keys."""
    (tmp_path / "s.toml").write_text(scene_text("runin"))
    scene = load_scene(tmp_path / "s.toml")
    bad = dataclasses.replace(scene, normal_force=1e-300)
    with pytest.raises(ValueError) as info:
        solve_scene(bad)
    assert str(info.value).startswith(f"{tmp_path / 's.toml'}: [load] normal_force = 1e-300 N "
                                      f"{RANGE} N"), str(info.value)
    with pytest.raises(ValueError, match=r"\[load\] normal_force = 1e-300 N is outside"):
        wear_problem_of(bad)
    stiff = dataclasses.replace(scene, wear=PowerLaw(K50, 50.0))
    with pytest.raises(ValueError, match=r"exponent = 50\.0 and \[load\] normal_force = 10\.0 and "
                                         r"\[punch\] radius = 0\.004 and \[grid\] n = 32: the "
                                         r"wear rate of a pixel"):
        wear_problem_of(stiff)


# -- within the range the units do not matter ----------------------------------------------
def test_normalised_results_do_not_depend_on_the_units_within_the_range():
    """Random scales over the whole range: every problem is refused, or solved as in SI units.

    Run with warnings as errors (the suite's setting): no overflow, underflow or
    invalid value on the way.
    """
    geometry = Voronoi(64, (0.6, 0.4), 2029)

    def normalised(L, force, E_star, k):
        outline = Circle(L)
        grid = outline.grid(32)
        result = solve(Problem(FacePhases(grid, geometry.labels(grid), 2), [k, 10 * k], force,
                               E_star))
        estimate = estimate_rms_slope(geometry, [k, 10 * k], force, outline, E_star, 32)
        g0 = result.reference_slope
        return np.array([result.normalised_rms_slope, estimate.rms_slope / g0,
                         estimate.error / g0,
                         *(result.phase_pressures / (force / outline.area))])

    base = normalised(4e-3, 10.0, 1.3e6, 1e-13)
    rng = np.random.default_rng(2417)
    low, high = (math.log10(v) for v in SCALE_RANGE)
    solved = 0
    for _ in range(60):
        L, force, E_star, k = 10.0 ** rng.uniform(low, high, 4)
        try:
            values = normalised(L, force, E_star, k)
        except ValueError as err:
            assert RANGE in str(err), f"refused for another reason: {err}"
            continue
        solved += 1
        # The rms slopes and their error bar come from the estimator's single-precision
        # kernel spectra, whose rounding follows the pixel size: measured at most 3.7e-9
        # of the SI values.  The phase pressures keep double precision.
        rtol = np.array([1e-8, 1e-8, 1e-8] + [1e-11] * (len(base) - 3))
        assert np.all(np.abs(values - base) <= rtol * np.abs(base)), \
            f"L = {L:.3g} m, F = {force:.3g} N, E* = {E_star:.3g} Pa, k = {k:.3g}: {values} " \
            f"vs {base}"
    assert solved >= 5, f"only {solved} of 60 random problems in range: test setup"
