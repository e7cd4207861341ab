"""The fixed costs of one run-in: set-up, checkpoints, run file, closing comparison.

What it reproduces
    docs/benchmarks.md, "Fixed costs of a run-in": the command line
    (``python -m transient``) on the shipped scene
    ``steady/examples/voronoi_transient.toml`` with only ``[grid] n``
    changed, run in this process with explicit timers around the parts of
    a run that do not grow with its number of steps:

    - the history's estimator (:meth:`transient.history.FaceEstimator.of`:
      its slope energy, the ladder of the phase geometry behind its error);
    - the first contact solve (``transient.runin._Run._first_state``);
    - the steady reference the history measures against
      (``transient.recording.RunRecord.__init__``: the closed-form face and
      its figures);
    - the rest of the run's set-up (``transient.runin._Run.__init__``);
    - checkpoints (:func:`transient.output.write_run` of a running result)
      and the final run file (of a finished one), and the final file's
      read-back check (:func:`transient.output.verify_run`);
    - the closing steady solve (:func:`steady.solution.solve_scene`, with
      its error bar) and the comparison itself
      (:func:`transient.comparison.compare_with_steady`);
    - the main thread's waits for the history's figures
      (``transient.recording.RunRecord.collect``), which checkpoints include;
    - everything else: the step loop and its contact solves.

    Each timer counts its own time only (the profile's timers,
    ``profile_runin.Timers``).  A part whose function does not exist in the
    installed code is reported as absent, so that the script also runs on
    earlier and later versions of the run.

How to run
    python studies/benchmarks/profile_fixed_costs.py --n 1024     # ~80 s on 2 cores
    python studies/benchmarks/profile_fixed_costs.py --n 40 --quick  # smoke test

Prints the parts as a Markdown table and writes them to ``--out`` (HDF5).
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import importlib.util
import io
import pathlib
import platform
import sys
import tempfile
import time

import numpy as np

from steady.safe_files import atomic_h5

N = 1024

#: The timed parts: label and the functions (module, dotted attribute) behind it.  The
#: run file's writes are told apart by the status of the result written.
PARTS = {
    "estimator (FaceEstimator.of)": [("transient.history", "FaceEstimator.of")],
    "first contact solve": [("transient.runin", "_Run._first_state")],
    "steady reference": [("transient.recording", "RunRecord.__init__"),
                         ("transient.problem", "WearProblem.solve_steady")],
    "rest of the set-up": [("transient.runin", "_Run.__init__")],
    "checkpoints": [],
    "final run file": [],
    "final file's read-back check": [("transient.output", "verify_run")],
    "closing steady solve (solve_scene)": [("steady.solution", "solve_scene"),
                                           ("transient.comparison", "solve_scene")],
    "comparison (compare_with_steady)": [("transient.comparison", "compare_with_steady")],
    "waits for the history's figures": [("transient.recording", "RunRecord.collect")],
}


def _profile_module():
    """``profile_runin`` beside this script: its timers and its scene copy."""
    path = pathlib.Path(__file__).resolve().parent / "profile_runin.py"
    spec = importlib.util.spec_from_file_location("profile_runin", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _attribute(module_name, attribute):
    """``(owner, name)`` of a dotted attribute of a module; owner None when absent."""
    owner = importlib.import_module(module_name)
    *path, name = attribute.split(".")
    for part in path:
        owner = getattr(owner, part, None)
    if owner is None or not hasattr(owner, name):
        return None, name
    return owner, name


def install(timers):
    """Wrap every function of :data:`PARTS` that exists; return the names missing."""
    missing, wrapped = [], set()
    for label, targets in PARTS.items():
        for module_name, attribute in targets:
            owner, name = _attribute(module_name, attribute)
            if owner is None:
                missing.append(f"{module_name}.{attribute}")
                continue
            function = getattr(owner, name)
            if id(function) not in wrapped:  # a name imported from a module wrapped already
                function = timers.wrap(label, function)
                wrapped.add(id(function))
                setattr(owner, name, function)
    output = importlib.import_module("transient.output")
    write_run = output.write_run
    checkpoint = timers.wrap("checkpoints", write_run)
    final = timers.wrap("final run file", write_run)

    def dispatch(path, result, **kwargs):
        return (checkpoint if result.status == "running" else final)(path, result, **kwargs)

    output.write_run = dispatch
    return missing


def profile(n, *, tol=None):
    """Run the command line once under the timers; return the rows of the table."""
    runin_profile = _profile_module()
    timers = runin_profile.Timers()
    missing = install(timers)
    cli = importlib.import_module("transient.__main__")
    with tempfile.TemporaryDirectory() as tmp:
        argv = [str(runin_profile.scene_copy(n, tmp)), "-o", str(pathlib.Path(tmp) / "run.h5"),
                "--force"]
        if tol is not None:
            argv += ["--tol", repr(tol)]
        t = time.perf_counter()
        with contextlib.redirect_stdout(io.StringIO()):  # the command line's summary
            status = cli.main(argv)
        wall = time.perf_counter() - t
    if status != 0:
        raise RuntimeError(f"the run ended with exit status {status}")
    rows = [dict(part=label, seconds=timers.total.get(label, 0.0),
                 calls=timers.calls.get(label, 0)) for label in PARTS]
    other = wall - sum(r["seconds"] for r in rows)
    rows.append(dict(part="everything else (step loop, contact solves)", seconds=other, calls=1))
    rows.append(dict(part="whole run", seconds=wall, calls=1,
                     missing=", ".join(missing)))
    return rows


def markdown(rows):
    """The parts in Markdown."""
    lines = ["| part | wall (s) | calls |", "|---|---|---|"]
    lines += [f"| {r['part']} | {r['seconds']:.2f} | {r['calls']} |" for r in rows]
    return "\n".join(lines)


def main(argv=None):
    """Command line of the profile (see the module docstring).

    Parameters
    ----------
    argv : list of str, optional
        Arguments (default: ``sys.argv[1:]``).

    Returns
    -------
    list of dict
        The rows of the table.
    """
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=N)
    parser.add_argument("--quick", action="store_true", help="smoke test (loose tol)")
    parser.add_argument("--out", type=pathlib.Path,
                        default=pathlib.Path("profile_fixed_costs.h5"))
    args = parser.parse_args(argv)
    rows = profile(args.n, tol=1e-2 if args.quick else None)
    print(markdown(rows))
    if rows[-1]["missing"]:
        print(f"absent in this version: {rows[-1]['missing']}")
    with atomic_h5(args.out, format="runin.profile_fixed_costs", version=1, force=True) as f:
        f.attrs.update(n=args.n, machine=platform.processor() or platform.machine(),
                       python=platform.python_version(), numpy=np.__version__,
                       command=" ".join(sys.argv), seconds_units="s")
        for i, row in enumerate(rows):
            g = f.create_group(f"{i:02d}")
            for k, v in row.items():
                g.attrs[k] = v
    return rows


if __name__ == "__main__":
    main()
