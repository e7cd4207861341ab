"""Smoke test of studies/benchmarks/bench_slope_precision.py at a small size."""

from conftest import benchmark


def test_bench_slope_precision_smoke(capsys):
    bench = benchmark("bench_slope_precision")
    (row,) = bench.main(["--n", "40", "--repeats", "1"])
    out = capsys.readouterr().out
    assert "| 40 | " in out, out
    assert max(row["errors"].values()) < 1e-6, f"single against double: {row['errors']}"
    assert row["errors"]["total"] < 1e-15, "the exact total involves no transform"
    assert row["relative"] < 1e-6, f"history rms slope moved {row['relative']:.1e}"
    assert row["in_bar"] < 1e-4, f"history's rms slope moved {row['in_bar']:.1e} of its bar"
    assert all(t > 0 for t in row["call"] + row["figures"]), "times"
