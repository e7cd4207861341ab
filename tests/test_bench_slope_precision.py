"""Smoke test of studies/benchmarks/bench_slope_precision.py at a small size."""

import importlib.util
import pathlib

SCRIPT = pathlib.Path(__file__).parents[1] / "studies" / "benchmarks" / "bench_slope_precision.py"


def test_bench_slope_precision_smoke(capsys):
    spec = importlib.util.spec_from_file_location("bench_slope_precision", SCRIPT)
    bench = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bench)
    (row,) = bench.main(["--n", "40", "--repeats", "1"])
    out = capsys.readouterr().out
    assert "| 40 | " in out, out
    assert max(row["errors"].values()) < 1e-6, f"single against double: {row['errors']}"
    assert row["errors"]["total"] < 1e-15, "the exact total involves no transform"
    assert row["relative"] < 1e-6, f"history rms slope moved {row['relative']:.1e}"
    assert row["in_bar"] < 1e-4, f"history's rms slope moved {row['in_bar']:.1e} of its bar"
    assert all(t > 0 for t in row["call"] + row["figures"]), "times"
