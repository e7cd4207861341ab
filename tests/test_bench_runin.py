"""Smoke tests of the run-in benchmark scripts (studies/benchmarks) at a small size."""

import h5py
import pytest
from conftest import benchmark


def test_bench_runin_smoke(tmp_path):
    out = tmp_path / "bench.h5"
    groups = benchmark("bench_runin").main(["--table", "--schemes", "--sizes", "40", "--n",
                                            "40", "--quick", "--out", str(out)])
    (row,) = groups["grids"]
    assert row["status"] == "steady" and row["solves"] > 2 * row["steps"] - 2, \
        f"grid table row {row}"
    schemes = {r["scheme"] for r in groups["schemes"]}
    assert {"sdirk2", "esdirk3", "bdf2", "implicit_euler"} <= schemes, f"schemes run: {schemes}"
    for r in groups["schemes"]:
        assert 0 <= r["history_error"] < 0.1, f"{r['scheme']} {r['tol']}: {r}"
    with h5py.File(out) as f:
        assert f.attrs["format"] == "runin.bench_runin", "layout attribute"
        assert len(f["schemes"]) == len(groups["schemes"]), "one group per row"


def test_bench_runin_levers_smoke(tmp_path):
    out = tmp_path / "bench.h5"
    bench = benchmark("bench_runin")
    rows = bench.main(["--levers", "--sizes", "40", "--quick", "--out", str(out)])["levers"]
    assert [(r["case"], r["rule"]) for r in rows] == [
        (case, rule) for case in ("voronoi", "rectangle") for rule in list(bench.LEVERS)[:2]], \
        "each case under the first two rules"
    for r in rows:
        assert r["status"] == "steady" and 0 <= r["history_error"] < 0.1, f"row {r}"
    # The looser share takes fewer iterations; the first rule is its own reference.
    assert rows[1]["iterations"] < rows[0]["iterations"] and rows[0]["change"] == 0, rows[:2]
    with h5py.File(out) as f:
        assert len(f["levers"]) == len(rows), "one group per row"


def test_bench_runin_periodic_smoke(tmp_path):
    out = tmp_path / "bench.h5"
    tables = benchmark("bench_runin").main(["--periodic", "--sizes", "40", "--out", str(out)])
    rows = tables["periodic"]
    assert [r["face"] for r in rows] == ["punch", "periodic cell"], f"rows {rows}"
    for r in rows:
        assert r["status"] == "steady" and r["products"] > r["iterations"] > 0, f"row {r}"
        assert 0 < r["product"] < 1.0, f"one product takes {r['product']} s"


def test_bench_runin_memory_smoke(tmp_path):
    out = tmp_path / "bench.h5"
    bench = benchmark("bench_runin")
    (row,) = bench.main(["--memory", "--sizes", "40", "--out", str(out)])["memory"]
    assert row["steps"] > 10 and row["snapshots"] == 3, f"memory table row {row}"
    # The interpreter with NumPy, SciPy and h5py alone takes about 95 MiB.
    assert 50 * 2 ** 20 < row["peak_rss"] < 400 * 2 ** 20, f"peak {row['peak_rss']} bytes"
    with h5py.File(out) as f:
        assert f["memory/000"].attrs["n"] == 40, "one group per row"
    text = "[grid]\nn = 64               # pixels\n\n[wear]\nn = 3\n"
    assert bench.scene_at(text, 1024) == text.replace("n = 64", "n = 1024", 1), \
        "only [grid] n changes"
    with pytest.raises(ValueError, match=r"no '\[grid\] n = <int>' line"):
        bench.scene_at("[wear]\nn = 3\n", 1024)


def test_profile_runin_smoke(tmp_path):
    out = tmp_path / "profile.h5"
    rows = benchmark("profile_runin").main(["--n", "40", "--quick", "--out", str(out)])
    whole = rows[-1]
    assert whole["part"] == "whole run" and "missing" not in whole, f"parts absent: {whole}"
    total = sum(r["seconds"] for r in rows[:-1])
    assert abs(total - whole["seconds"]) < 1e-6 * whole["seconds"] + 1e-9, \
        f"parts sum to {total} s, the run took {whole['seconds']} s"
    contact = rows[0]
    assert contact["part"] == "contact solves" and contact["calls"] > 0, f"{contact}"
    assert out.exists(), "the profile writes its HDF5 file"


def test_bench_runin_interfaces_smoke(tmp_path):
    out = tmp_path / "bench.h5"
    bench = benchmark("bench_runin")
    scene = bench.EXAMPLES / "coating_transient.toml"
    (row,) = bench.main(["--interfaces", "--interfaces-scene", str(scene), "--sizes", "16",
                         "--tol", "1e-3", "--reference-tol", "1e-4",
                         "--out", str(out)])["interfaces"]
    assert row["status"] == "depth" and row["crossings"] > 0, f"interfaces row {row}"
    assert 0 <= row["extra_newton"] < row["solves"], f"second Newton solves: {row}"
    assert 0 < row["face_error"] < 1e-2, f"final face against tol 1e-4: {row}"
