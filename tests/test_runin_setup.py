"""What a run-in computes once and shares: the steady face, the map error ladder, the run file.

The run's steady reference needs only the closed-form face and its pressure
(``solve_steady(face_only=True)``), and the closing comparison takes the
ladder of the phase geometry that the run's estimator already computed
(:func:`transient.comparison.steady_of_run`).  Each shared value must be
the one computed afresh, to the last bit.
"""

import dataclasses
import math

import numpy as np
import pytest
from conftest import scene_text, wear_problem

from steady.rms_slope import estimate_rms_slope
from steady.scene import parse_scene
from steady.solution import solve_scene
from transient.comparison import steady_of_run
from transient.history import FaceEstimator
from transient.scene import wear_problem_of


def _same_bits(a, b):
    """Whether two values are equal bit for bit (arrays: dtype, shape and bytes; NaN equal)."""
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        a, b = np.asarray(a), np.asarray(b)
        return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()
    if isinstance(a, float) and isinstance(b, float):
        return np.float64(a).tobytes() == np.float64(b).tobytes()
    return a == b


def _differences(x, y):
    """Names of the dataclass fields of ``x`` and ``y`` that are not the same bits."""
    return [f.name for f in dataclasses.fields(x)
            if not _same_bits(getattr(x, f.name), getattr(y, f.name))]


@pytest.mark.parametrize("geometry", ["voronoi", "rods"])
@pytest.mark.parametrize("n", [32, 33])
def test_face_only_steady_face_is_the_full_solves(geometry, n):
    problem = wear_problem(geometry, n=n)
    full = problem.solve_steady()
    face = problem.solve_steady(face_only=True)
    assert math.isnan(face.rms_slope), "face_only: no rms slope estimate"
    assert math.isfinite(full.rms_slope), "the full solve estimates the rms slope"
    differ = [name for name in _differences(full, face)
              if name not in ("rms_slope", "rms_slope_error")]
    assert not differ, f"face_only changed {differ}"


def _scene(n, extra=""):
    return parse_scene(scene_text("runin", n=n, extra=extra), ".")


@pytest.mark.parametrize("n", [32, 45])
def test_estimator_ladder_is_the_steady_commands(n):
    scene = _scene(n)
    problem = wear_problem_of(scene)
    estimator = FaceEstimator.of(problem, np.zeros(problem.shape))
    own = estimator.geometry_estimate
    fresh = estimate_rms_slope(scene.geometry, problem.problem.wear, problem.problem.normal_force,
                               problem.problem.outline, problem.problem.E_star, problem.n,
                               sliding=problem.problem.sliding)
    assert own is not None, "a scene's geometry: the estimator keeps its ladder"
    assert own.grids == fresh.grids and own.values == fresh.values, \
        f"ladders differ: {own.values} on {own.grids} vs {fresh.values} on {fresh.grids}"
    assert _same_bits(own.error, fresh.error), f"errors differ: {own.error} vs {fresh.error}"
    assert estimator.map_error == own.error / own.rms_slope, "map_error is the shared ladder's"


@pytest.mark.parametrize("extra", ["", '[sliding]\nkind = "pin_on_disk"\ntrack_radius = 0.02\n'])
def test_steady_of_run_is_solve_scene(extra):
    scene = _scene(36, extra)
    problem = wear_problem_of(scene)
    shared = steady_of_run(scene, problem, np.zeros(problem.shape))
    fresh = solve_scene(scene, problem=problem.problem)
    differ = _differences(shared, fresh)
    assert not differ, f"steady_of_run differs from solve_scene in {differ}"
    assert math.isfinite(shared.rms_slope_error), "the error bar of the geometry's ladder"


def test_a_bare_map_keeps_no_ladder():
    problem = wear_problem("voronoi", n=32)  # no scene geometry: a label map
    estimator = FaceEstimator(problem, np.zeros(problem.shape))
    assert estimator.geometry_estimate is None, "a label map has no geometry ladder to share"
