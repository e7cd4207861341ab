"""The range of validity: the warning fires past the slope limit and not inside it.

The suite runs with warnings as errors, so every solve and design query of
the other tests lies inside the range; here the limit is crossed on purpose.
"""

import dataclasses
import math
import pathlib
import warnings

import pytest
from conftest import run_cli, scene_text

import steady.cli.design as design_cli
import steady.cli.solve as steady_cli
from steady.design import DesignTable
from steady.scene import load_scene, parse_scene
from steady.solution import solve_scene
from steady.validity import (
    SLOPE_LIMIT,
    ValidityWarning,
    check_rms_slope,
    max_pbar_over_estar,
)

SCENES = pathlib.Path(__file__).resolve().parent.parent / "steady" / "examples"


def test_the_limit_is_where_the_dropped_terms_reach_five_per_cent():
    assert 1 - math.cos(SLOPE_LIMIT) == pytest.approx(0.05, rel=0.01), \
        f"1 - cos({SLOPE_LIMIT}) is not about theta^2 / 2 = 5 %"
    assert check_rms_slope(SLOPE_LIMIT, "a face"), "the limit itself is inside"
    assert check_rms_slope(math.nan, "a face"), "an unknown slope is no warning"
    with pytest.warns(ValidityWarning, match=r"^a face has an rms slope of 0\.317 rad, beyond "
                                             r"the 0\.316 rad of small slopes"):
        assert not check_rms_slope(1.001 * SLOPE_LIMIT, "a face")


@pytest.mark.parametrize("factor, warns", [(0.98, False), (1.02, True)])
def test_homogeneous_disk_leaves_the_range_at_the_derived_load(factor, warns):
    """At ``pbar / E* = max_pbar_over_estar()`` the eq. 10 face reaches the limit.

    The corrected rms slope of the homogeneous disk is ``grad_f0`` to 0.3 %
    at n = 128 (measured 0.99812 +- 0.0031), well inside the 2 % margins.
    """
    scene = load_scene(SCENES / "epoxy_cylinder.toml")
    pbar = scene.normal_force / (math.pi * 0.004 ** 2)
    scene = dataclasses.replace(scene, E_star=pbar / (factor * max_pbar_over_estar()))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", ValidityWarning)
        result = solve_scene(scene, n=128)
    assert abs(result.normalised_rms_slope - 1) < 0.005, result.normalised_rms_slope
    assert len(caught) == warns, [str(w.message) for w in caught]
    if warns:
        assert str(caught[0].message).startswith(
            f"the steady face of {SCENES / 'epoxy_cylinder.toml'} has an rms slope of 0.32"), \
            str(caught[0].message)


def test_steady_command_prints_one_warning_line_and_succeeds(tmp_path, capsys):
    inside, outside = tmp_path / "in.toml", tmp_path / "out.toml"
    inside.write_text(scene_text("steady"))                       # 0.305 rad
    outside.write_text(scene_text("steady", normal_force=20.0))   # twice the slope
    status, out, err = run_cli(steady_cli, [inside, "-o", tmp_path / "in.h5"], capsys)
    assert (status, err) == (0, ""), f"inside: exit {status}, stderr {err!r}"
    status, out, err = run_cli(steady_cli, [outside, "-o", tmp_path / "out.h5"], capsys)
    assert status == 0 and (tmp_path / "out.h5").exists(), f"exit {status}: {err}"
    lines = err.splitlines()
    assert len(lines) == 1 and lines[0].startswith(
        f"warning: the steady face of {outside} has an rms slope of 0.61"), err
    assert "rms slope        0.61" in out, out


def test_design_query_past_the_limit_warns(capsys):
    table = DesignTable.read()
    value, _ = table.rms_slope(0.08, 1e-3, 0.3)   # inside: 0.263 rad, no warning
    assert value < SLOPE_LIMIT, value
    with pytest.warns(ValidityWarning, match=r"^the design pbar/E\* = 0\.5, k_1/k_0 = 0\.01, "
                                             r"rho_1 = 0\.1 has an rms slope of 2\.78 rad"):
        table.rms_slope(0.5, 1e-2, 0.1)
    with pytest.warns(ValidityWarning, match=r"^the design target at pbar/E\* = 0\.08, "
                                             r"k_1/k_0 = 0\.001 has an rms slope of 1 rad"):
        table.fill_factor_for(0.08, 1e-3, 1.0)   # the paper's tyre rule
    status, out, err = run_cli(design_cli, ["--pbar-over-estar", "0.5", "--wear-ratio", "1e-2",
                                            "--fill-factor", "0.1"], capsys)
    assert status == 0 and out.startswith("rms slope = 2.777"), (status, out)
    assert err.count("\n") == 1 and err.startswith("warning: the design pbar/E* = 0.5"), err
    status, out, err = run_cli(design_cli, ["--pbar-over-estar", "0.08", "--wear-ratio", "1e-3",
                                            "--target-slope", "0.3"], capsys)
    assert (status, err) == (0, ""), f"inside: exit {status}, stderr {err!r}"


def test_solve_scene_warns_once_per_scene(tmp_path):
    scene = parse_scene(scene_text("steady", normal_force=20.0), tmp_path)
    with pytest.warns(ValidityWarning) as caught:
        solve_scene(scene)
    assert len(caught) == 1, [str(w.message) for w in caught]
    assert str(caught[0].message).startswith("the steady face of the scene has an rms slope"), \
        str(caught[0].message)


def test_runin_command_warns_after_the_run(tmp_path, capsys):
    """The run-in's scene is checked on its steady face, at the end of the run."""
    import transient.cli.runin as runin_cli

    scene = tmp_path / "s.toml"
    scene.write_text(scene_text("runin", normal_force=25.0))      # 2.5 x 0.254 rad
    status, out, err = run_cli(runin_cli, [scene, "-o", tmp_path / "r.h5"], capsys)
    assert status == 0 and (tmp_path / "r.h5").exists(), f"exit {status}: {err}"
    lines = err.splitlines()
    assert len(lines) == 1 and lines[0].startswith(
        f"warning: the steady face of {scene} has an rms slope of 0.63"), err
