"""Sweeps on executors: HDF5 written point by point, resume, interruption, Dask."""

import concurrent.futures
import threading

import h5py
import numpy as np
import pytest

from steady.sweep import SweepFile, open_executor, point_key, run_sweep
from steady.voronoi_sweep import collect_voronoi, voronoi_slopes, voronoi_sweep

SETTINGS = {"grid": 16, "what": "square"}


class Recorder:
    """Task that squares ``x`` and records which points it ran (thread executors only)."""

    def __init__(self, fail_at=None):
        self.calls = []
        self.fail_at = fail_at
        self.lock = threading.Lock()

    def __call__(self, point):
        with self.lock:
            self.calls.append(point["x"])
        if point["x"] == self.fail_at:
            raise RuntimeError(f"task failed at x = {point['x']}")
        return {"square": point["x"] ** 2, "vector": np.full(3, point["x"], dtype=float)}


def values_by_x(path):
    return {p.params["x"]: p.values["square"].item() for p in SweepFile(path).read()}


def test_points_written_and_resumed(tmp_path):
    """A second, larger sweep computes only the new points."""
    path = tmp_path / "sweep.h5"
    task = Recorder()
    with concurrent.futures.ThreadPoolExecutor(2) as ex:
        run_sweep(task, [{"x": x} for x in range(5)], path, settings=SETTINGS,
                  units={"square": "m^2"}, executor=ex)
        assert sorted(task.calls) == list(range(5)), f"first run computed {task.calls}"
        task.calls.clear()
        run_sweep(task, [{"x": x} for x in range(8)], path, settings=SETTINGS, executor=ex)
    assert sorted(task.calls) == [5, 6, 7], f"resume recomputed {sorted(task.calls)}"
    assert values_by_x(path) == {x: x * x for x in range(8)}, "stored values"
    with h5py.File(path, "r") as f:
        group = next(iter(f["points"].values()))
        assert group["square"].attrs["units"] in ("m^2", "1"), "units attribute"
        assert f.attrs["format"] == "runin.sweep", "format attribute"
        assert int(f.attrs["format_version"]) == 1, "version attribute"


def test_interrupted_sweep_is_readable_and_resumes(tmp_path):
    """A failing task stops the sweep; finished points stay; a rerun completes it."""
    path = tmp_path / "sweep.h5"
    with concurrent.futures.ThreadPoolExecutor(1) as ex:
        with pytest.raises(RuntimeError, match="x = 3"):
            run_sweep(Recorder(fail_at=3), [{"x": x} for x in range(6)], path,
                      settings=SETTINGS, executor=ex)
        done = values_by_x(path)
        assert {0, 1, 2} <= set(done) and 3 not in done, f"points after the failure: {done}"
        task = Recorder()
        run_sweep(task, [{"x": x} for x in range(6)], path, settings=SETTINGS, executor=ex)
    assert 3 in task.calls and not set(task.calls) & set(done), \
        f"rerun computed {task.calls}, {sorted(done)} were done"
    assert values_by_x(path) == {x: x * x for x in range(6)}, "completed sweep"


def test_half_written_point_is_dropped(tmp_path):
    """A group left under its temporary name (crash mid-write) is removed on open."""
    path = tmp_path / "sweep.h5"
    sweep = SweepFile(path, SETTINGS)
    sweep.write({"x": 1}, {"square": 1})
    with h5py.File(path, "a") as f:
        f["points"].create_group("tmp-deadbeef").attrs["key"] = point_key({"x": 2})
    assert SweepFile(path, SETTINGS).keys() == {point_key({"x": 1})}, "tmp group kept"


def test_other_settings_refused(tmp_path):
    path = tmp_path / "sweep.h5"
    SweepFile(path, SETTINGS)
    with pytest.raises(ValueError, match="settings"):
        SweepFile(path, {"grid": 32, "what": "square"})
    (tmp_path / "foreign.h5").write_bytes(b"not hdf5")
    with pytest.raises(ValueError, match="cannot open"):
        SweepFile(tmp_path / "foreign.h5", SETTINGS)
    for bad in (-1, 0, 1.5):
        with pytest.raises(ValueError, match=f"workers must be an integer >= 1, got {bad}"):
            with open_executor(workers=bad):
                pass


def test_process_pool_matches_direct_evaluation(tmp_path):
    """The default executor (local processes) gives the task's own values."""
    ratios = [1e-2, 1.0, 10.0]
    sweep = voronoi_sweep(tmp_path / "v.h5", n=48, ratios=ratios, n_seeds=[64],
                          fill_factors=[0.25, 0.5], seeds=[7411, 7412], workers=2)
    data = collect_voronoi(sweep, [64], [0.25, 0.5], [7411, 7412])
    direct = voronoi_slopes({"n_seeds": 64, "fill_factor": 0.5, "seed": 7412}, n=48,
                            ratios=ratios)
    assert np.array_equal(data.rms_slope[0, 1, 1], direct["rms_slope"][-1]), \
        "process pool value differs from the direct evaluation"
    assert np.allclose(data.rms_slope[0, :, :, 1], 1.0, atol=2e-2), \
        "k_2 = k_1 must give the homogeneous value (1 up to the grid error at n = 48)"


def test_dask_local_cluster(tmp_path):
    """A scheduler address runs the sweep on a Dask cluster, with the same values."""
    distributed = pytest.importorskip("distributed")
    ratios = [0.1, 10.0]
    points = dict(n_seeds=[64], fill_factors=[0.3], seeds=[5501, 5502, 5503])
    local = voronoi_sweep(tmp_path / "local.h5", n=32, ratios=ratios, workers=1, **points)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                                  dashboard_address=None) as cluster:
        remote = voronoi_sweep(tmp_path / "dask.h5", n=32, ratios=ratios,
                               scheduler=cluster.scheduler_address, **points)
        with distributed.Client(cluster) as client:  # a connected client works too
            again = voronoi_sweep(tmp_path / "client.h5", n=32, ratios=ratios,
                                  scheduler=client, **points)
    a = collect_voronoi(local, [64], [0.3], points["seeds"]).rms_slope
    b = collect_voronoi(remote, [64], [0.3], points["seeds"]).rms_slope
    c = collect_voronoi(again, [64], [0.3], points["seeds"]).rms_slope
    assert np.array_equal(a, b), "Dask values differ from local ones"
    assert np.array_equal(a, c), "Dask (client) values differ from local ones"


def test_writer_waits_for_a_reader_in_another_process(tmp_path):
    """HDF5 locks an open file: a point finished while a study reads the file is not lost."""
    import subprocess
    import sys
    import time

    path = tmp_path / "sweep.h5"
    SweepFile(path, SETTINGS).write({"x": 1}, {"square": 1})
    hold = ("import h5py, sys, time\n"
            "f = h5py.File(sys.argv[1], 'r'); print('open', flush=True); time.sleep(1.5)\n")
    with subprocess.Popen([sys.executable, "-c", hold, str(path)], stdout=subprocess.PIPE,
                          text=True) as reader:
        assert reader.stdout.readline().strip() == "open", "reader did not start"
        t0 = time.monotonic()
        SweepFile(path, SETTINGS).write({"x": 2}, {"square": 4})
        waited = time.monotonic() - t0
    assert values_by_x(path) == {1: 1, 2: 4}, "point written after the reader let go"
    assert waited > 0.5, f"the write did not wait for the lock ({waited:.2f} s)"
