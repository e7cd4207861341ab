"""Smoke test of the mixed-precision benchmark (studies/benchmarks) at a small size."""

from conftest import benchmark


def test_bench_mixed_precision_smoke(monkeypatch):
    bench = benchmark("bench_mixed_precision", monkeypatch)   # it imports bench_runin
    tables = bench.main(["--products", "--runs", "--sizes", "40", "--repeats", "1",
                         "--count", "2"])
    (product,) = tables["products"]
    # float32 round-off of a padded product: a few eps_32 of its largest value
    assert 1e-8 < product["error"] < 1e-5, f"single product error {product['error']}"
    rows = tables["runs"]
    assert [(r["case"], r["variant"]) for r in rows] == [
        (case, variant) for case in ("voronoi", "rectangle") for variant in bench.VARIANTS]
    for r in rows:
        double = next(d for d in rows if d["case"] == r["case"] and d["variant"] == "double")
        assert r["status"] == "steady" and r["steps"] == double["steps"], f"{r}"
        assert (r["single"] > 0) == (r["variant"] != "double"), f"single products: {r}"
        assert r["change"] < 1e-5, f"history moved by {r['change']} grad_f0: {r}"
