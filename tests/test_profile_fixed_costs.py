"""Smoke test of studies/benchmarks/profile_fixed_costs.py at a small size."""

import h5py
from conftest import benchmark


def test_profile_fixed_costs_smoke(tmp_path):
    module = benchmark("profile_fixed_costs")
    out = tmp_path / "fixed.h5"
    rows = module.main(["--n", "40", "--quick", "--out", str(out)])
    by_part = {r["part"]: r for r in rows}
    whole = by_part["whole run"]
    assert not whole["missing"], f"parts absent in this version: {whole['missing']}"
    total = sum(r["seconds"] for r in rows[:-1])
    assert abs(total - whole["seconds"]) < 1e-6 * whole["seconds"] + 1e-9, \
        f"parts sum to {total} s, the run took {whole['seconds']} s"
    for part, calls in (("first contact solve", 1), ("final run file", 1),
                        ("final file's read-back check", 1),
                        ("closing steady solve (solve_scene)", 1)):
        assert by_part[part]["calls"] == calls, f"{part}: {by_part[part]}"
    assert by_part["checkpoints"]["calls"] >= 1, "the first checkpoint follows the first step"
    with h5py.File(out) as f:
        assert f.attrs["format"] == "runin.profile_fixed_costs", "layout attribute"
        assert len(f) == len(rows), "one group per row"
