"""Convergence of a run-in through spherical particles, in the grid and in the depth resolution.

The scene is steady/examples/spheres_transient.toml with spheres of radius
0.125 a (two pixels at n = 32, the coarsest grid they allow), 30 % by
volume, ten times harder than the matrix, worn from flat; ``f*`` is about
0.3 mm, 0.6 of the radius.  The history figures are read at three
distances where the steps land exactly (snapshots at 0.15, 0.3 and 0.45
s*, mean worn depths 0.5, 0.9 and 1.4 f*):

- in the grid: the same spheres rasterised at n = 32, 64, 128;
- in the depth resolution: the same spheres as a voxel stack (a ``.npy``
  file of the spheres' own columns sampled at the voxel centres) of voxel
  depth dz = 0.1 mm, dz/2 and dz/4, against the exact columns at n = 32.

The step tolerance is 1e-3: at 1e-4 the figures of the exact columns at
n = 32 move by at most 1.1e-5 f* (mean worn depth) and 0.0018 grad_f0 (rms
slope), measured, below the differences measured here.
"""

import dataclasses
import pathlib
import warnings

import numpy as np
import pytest

from steady.depth_maps import Spheres, Voxels, load_voxels
from steady.scene import load_scene
from steady.validity import ValidityWarning
from transient.options import RunOptions
from transient.runin import run_in
from transient.scene import wear_problem_of

SCENE = pathlib.Path(__file__).resolve().parent.parent / "steady" / "examples" / \
    "spheres_transient.toml"
SNAPSHOTS = (0.15, 0.3, 0.45)   # s*
DEPTH = 2.0e-3                  # m, bottom of the particle field
VOXEL_DEPTH = 1.0e-4            # m, the coarsest voxel stack


def base_scene():
    """The example scene with its spheres enlarged to radius 0.125 a (the same seed)."""
    scene = load_scene(SCENE, extra_sections=("transient", "initial_face"))
    spheres = Spheres(0.125 * scene.outline.scale, 0.3, 2031, DEPTH)
    return dataclasses.replace(scene, geometry=spheres)


def run(scene, n):
    """Wear the scene's punch from flat at ``n`` to the last snapshot; the history figures there.

    Returns a dict of arrays over the snapshots: ``depth`` (mean worn depth
    / f*), ``slope`` and ``quasi`` (the rms slope of the face and of the
    section's steady face / grad_f0), ``error`` (the run's estimate of the
    rms slope's discretisation error / grad_f0), and ``worn`` (worn depth
    fields / f*, shape (3, n, n), NaN off the face).
    """
    problem = wear_problem_of(dataclasses.replace(scene, n=n))
    options = RunOptions(tol=1e-3, snapshots_s_star=SNAPSHOTS,
                         distance_limit=SNAPSHOTS[-1] * problem.distance_scale)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ValidityWarning)
        result = run_in(problem, np.zeros(problem.shape), options)
    h = result.history
    distance = np.asarray(h["distance"])
    at = [int(np.flatnonzero(distance == s)[0]) for s in result.snapshot_distance]
    assert len(at) == len(SNAPSHOTS), f"snapshots at {result.snapshot_distance}"
    f_star, grad = problem.depth_scale, result.reference_slope
    return {"depth": np.asarray(h["worn_depth_mean"])[at] / f_star,
            "slope": np.asarray(h["rms_slope"])[at] / grad,
            "quasi": np.asarray(h["quasi_steady_rms_slope"])[at] / grad,
            "error": np.asarray(h["rms_slope_error"])[at] / grad,
            "worn": (result.snapshot_recession - result.initial_recession[None]) / f_star}


def voxel_scene(scene, n, dz, directory):
    """The scene's spheres as a voxel stack of voxel depth ``dz`` (m), written to a ``.npy`` file.

    Slice ``k`` is the spheres' own columns at the voxel centre ``(k + 1/2) dz``
    on the grid ``n`` (the matrix off the face), down to the field's bottom.
    """
    columns = scene.geometry.columns(scene.grid(n))
    slices = [columns.phase_at((k + 0.5) * dz) for k in range(round(DEPTH / dz))]
    stack = np.maximum(np.stack(slices, axis=-1), 0).astype(np.int8)
    path = pathlib.Path(directory) / f"spheres_dz{dz:.3g}.npy"
    np.save(path, stack)
    voxels = Voxels(load_voxels(path, max_side=n), dz, str(path), scene.outline)
    return dataclasses.replace(scene, geometry=voxels)


@pytest.fixture(scope="module")
def exact32():
    """The run on the exact sphere columns at n = 32."""
    return run(base_scene(), 32)


def face_difference(a, b):
    """Rms over the face of the difference of two worn depth fields (f*), one per snapshot."""
    diff = a["worn"] - b["worn"]
    return np.sqrt(np.nanmean(diff * diff, axis=(1, 2)))


def test_a_fine_voxel_stack_is_the_spheres(exact32, tmp_path):
    """Voxels of dz/4 = 25 um (0.08 f*) give the spheres' history within the voxel error.

    Measured: mean worn depth within 0.0025 f*, rms slope within 0.014
    grad_f0 (the run's own estimate of its discretisation error is 0.049),
    worn face within 0.0089 f* rms; the bounds are 1.4 to 1.6 times these.
    """
    scene = base_scene()
    voxels = run(voxel_scene(scene, 32, VOXEL_DEPTH / 4, tmp_path), 32)
    depth = np.max(np.abs(voxels["depth"] - exact32["depth"]))
    assert depth < 0.004, f"mean worn depth differs by {depth:.3g} f*"
    slope = np.max(np.abs(voxels["slope"] - exact32["slope"]))
    assert slope < 0.02, f"rms slope differs by {slope:.3g} grad_f0"
    assert slope < np.min(exact32["error"]), "rms slope differs by more than its error bar"
    face = np.max(face_difference(voxels, exact32))
    assert face < 0.012, f"worn face differs by {face:.3g} f* rms"


@pytest.mark.slow
def test_voxel_stacks_converge_to_the_spheres_in_depth(exact32, tmp_path):
    """dz, dz/2, dz/4: the worn face and its mean depth converge at about first order.

    Measured (rms over the three snapshots): the worn face differs by
    0.0234, 0.0123, 0.0081 f* rms (order 0.76 from dz to dz/4), the mean
    worn depth by 0.0087, 0.0050, 0.0020 f* (order 1.06; the bounds on the
    orders, 0.5 and 0.7, are two thirds of the measured ones).  The rms slope
    does not converge monotonically (largest differences 0.032, 0.006,
    0.014 grad_f0: a voxel stack moves every interface by up to dz/2, a
    random perturbation of the sections) but stays within the run's
    estimate of its discretisation error (0.049 at the first snapshot).
    """
    scene = base_scene()
    runs = [run(voxel_scene(scene, 32, VOXEL_DEPTH / 2 ** j, tmp_path), 32) for j in range(3)]
    face = np.array([np.sqrt(np.mean(face_difference(r, exact32) ** 2)) for r in runs])
    mean = np.array([np.sqrt(np.mean((r["depth"] - exact32["depth"]) ** 2)) for r in runs])
    slope = np.array([np.max(np.abs(r["slope"] - exact32["slope"])) for r in runs])
    for name, errors, low in (("worn face", face, 0.5), ("mean worn depth", mean, 0.7)):
        order = np.log2(errors[0] / errors[2]) / 2
        assert np.all(np.diff(errors) < 0), f"{name}: errors {errors} do not shrink"
        assert order > low, f"{name}: order {order:.2f} from errors {errors}"
    assert np.all(slope < np.min(exact32["error"])), f"rms slope differs by {slope}"


@pytest.mark.slow
def test_grid_convergence_of_the_history():
    """The same spheres at n = 32, 64, 128: the history figures converge.

    Measured, differences 32 -> 64 and 64 -> 128 at the three snapshots:
    mean worn depth 0.0033, 0.0008, 0.0026 then 0.0003, 0.0003, 0.0009 f*
    (order 2.07 on their rms); rms slope 0.018, 0.018, 0.025 then 0.013,
    0.012, 0.021 grad_f0 (order 0.37: the rasterised spheres change the
    sections with n, beyond the discretisation of the slope on one map that
    the run's error bar estimates, 0.0064 grad_f0 at n = 128).  The bounds
    on the orders, 1.5 and 0.2, are about 0.7 and 0.5 of the measured ones.
    """
    scene = base_scene()
    runs = [run(scene, n) for n in (32, 64, 128)]
    for key, low in (("depth", 1.5), ("slope", 0.2)):
        d1 = np.abs(runs[1][key] - runs[0][key])
        d2 = np.abs(runs[2][key] - runs[1][key])
        assert np.all(d2 < d1), f"{key}: differences {d1} then {d2}"
        order = np.log2(np.sqrt(np.mean(d1 ** 2) / np.mean(d2 ** 2)))
        assert order > low, f"{key}: order {order:.2f} from differences {d1} then {d2}"
    # The coarse grid's error bar covers its distance from the finest grid (measured 0.031,
    # 0.030, 0.046 against 0.049, 0.050, 0.052).
    far = np.abs(runs[0]["slope"] - runs[2]["slope"])
    assert np.all(far < runs[0]["error"]), f"n = 32 is {far} from n = 128"
