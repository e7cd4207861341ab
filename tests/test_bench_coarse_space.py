"""The coarse-space benchmark (studies/benchmarks): its deflation's algebra, and a smoke run."""

import numpy as np
import pytest
from conftest import benchmark


@pytest.fixture
def bench(monkeypatch):
    return benchmark("bench_coarse_space", monkeypatch)   # it imports bench_runin


def _stage(bench, n=40):
    """A Voronoi face's stage at ``c = 1e-3``, its fixed coarse space and a residual."""
    from transient.preconditioners import ScaledShift
    from transient.scene import load_transient_scene, wear_problem_of

    scene, _, _ = load_transient_scene(bench.SCENE)
    problem = wear_problem_of(scene, n=n)
    face, hs = problem.face_mask, problem.halfspace
    parts = bench.fixed_space(problem)
    Z = np.concatenate([parts[part][0] for part in bench.PARTS[:3]])
    KZ = np.concatenate([parts[part][1] for part in bench.PARTS[:3]])
    shift = 1e-3 * np.where(face, problem.wear_field, 0.0)
    AZ = KZ + shift.reshape(1, -1) * Z
    base = ScaledShift(hs, face, problem.wear_field).preconditioner(1e-3, shift)
    rng = np.random.default_rng(7)
    residual = np.where(face, rng.standard_normal(face.shape), 0.0)
    residual[face] -= residual[face].mean()
    return problem, Z, KZ, AZ, shift, base, residual


def test_deflated_direction_meets_the_coarse_equation(bench):
    # A-DEF2: z = P^T M r + Q r, so (A Z)^T z = Z^T r (P^T's part is A-orthogonal to Z).
    problem, Z, KZ, AZ, shift, base, residual = _stage(bench)
    face = problem.face_mask
    einv = bench.pseudo_inverse(Z, AZ)
    support = np.any(Z != 0, axis=0).reshape(face.shape)
    z = bench.TwoLevel(base, Z, AZ, einv, support, additive=False)(residual, face)
    assert np.all(z[~face] == 0) and abs(z[face].sum()) < 1e-9 * np.abs(z).sum()
    lhs, rhs = AZ @ z.ravel(), Z @ residual.ravel()
    assert np.max(np.abs(lhs - rhs)) < 1e-9 * np.max(np.abs(rhs))
    # The columns are zero-mean on the face and K Z is the half-space's product.
    assert np.max(np.abs(Z.reshape(len(Z), -1)[:, face.ravel()].sum(axis=1))) < 1e-9
    k0 = problem.halfspace.displacement(Z[0].reshape(face.shape)).ravel()
    assert np.array_equal(k0, KZ[0])


def test_corrected_start_is_galerkin_on_the_coarse_space(bench):
    # The corrected first iterate leaves no residual on Z: Z^T r(p1) = 0, load kept.
    problem, Z, KZ, AZ, shift, base, _ = _stage(bench)
    face, hs = problem.face_mask, problem.halfspace
    x0 = np.where(face, 1.0, 0.0)
    ii, jj = np.indices(face.shape)
    recession = np.where(face, 1e-9 * np.cos(ii / 5.0) * np.sin(jj / 7.0), 0.0)
    stage = dict(halfspace=hs, face=face, x0=x0, x0_displacement=None, recession=recession,
                 force=problem.normal_force, shift=shift)
    einv = bench.pseudo_inverse(Z, AZ)
    support = np.any(Z != 0, axis=0).reshape(face.shape)
    p1, v1, products = bench.corrected_start(stage, Z, KZ, einv, support)
    assert products == 1 and p1 is not None
    assert p1[face].sum() * hs.h ** 2 == pytest.approx(problem.normal_force, rel=1e-12)
    assert np.max(np.abs(v1 - hs.displacement(p1))) < 1e-10 * np.max(np.abs(v1))
    g = np.where(face, v1 + shift * p1 + recession, 0.0)
    g[face] -= g[face].mean()
    scale = np.sqrt(np.einsum("mn,mn->m", Z, Z)) * np.linalg.norm(g)
    assert np.max(np.abs(Z @ g.ravel()) / scale) < 1e-8


def test_bench_coarse_space_smoke(bench):
    rows = bench.main(["--sizes", "40", "--cases", "voronoi", "rectangle", "--quick"])
    assert [(r["case"], r["variant"]) for r in rows] == [
        (case, variant) for case in ("voronoi", "rectangle") for variant in bench.VARIANTS]
    for r in rows:
        shipped = next(s for s in rows if s["case"] == r["case"] and s["variant"] == "shipped")
        assert r["solves"] == shipped["solves"] > 0, f"{r}"
        # every variant solves to the stage's own tolerance: the pressures agree to about it
        assert r["change"] < 1e-3, f"pressure moved by {r['change']} pbar: {r}"
        deflating = r["variant"].startswith("coarse-deflate") and not (
            r["case"] == "rectangle" and r["variant"].endswith(":phases"))
        assert (r["coarse_applied"] > 0) == (deflating or r["variant"] in (
            "deflate-history", "coarse-additive")), f"{r}"
    costs = bench.main(["--costs", "--sizes", "40", "--variants", "coarse-deflate:smooth"])
    (row,) = costs
    assert row["m"] == 5 and row["product"] > 0 and row["two_level"] > 0
