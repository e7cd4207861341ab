"""Smoke test of the mixed-precision benchmark (studies/benchmarks) at a small size."""

import importlib.util
import pathlib

BENCHMARKS = pathlib.Path(__file__).parents[1] / "studies" / "benchmarks"


def test_bench_mixed_precision_smoke(monkeypatch):
    monkeypatch.syspath_prepend(str(BENCHMARKS))   # it imports bench_runin, beside it
    spec = importlib.util.spec_from_file_location(
        "bench_mixed_precision", BENCHMARKS / "bench_mixed_precision.py")
    bench = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bench)
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
