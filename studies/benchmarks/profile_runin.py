"""Where the time of one run-in goes: contact solves, per-step diagnostics, checkpoints, run file.

What it reproduces
    docs/benchmarks.md, "Where the time goes": the command line
    (``python -m transient``) on the shipped scene
    ``steady/examples/voronoi_transient.toml`` with only ``[grid] n`` changed,
    run in this process with explicit timers around the parts of a run:

    - contact solves (:meth:`transient.problem.WearProblem.contact`: the
      solver, its preconditioner and its FFT products);
    - the rest of the implicit stages: the warm start
      (:meth:`transient.warm_start.WarmStart.predict`) and the face
      rebuilt from the pressure (``WearProblem._rebuild``, one FFT product);
    - the figures recorded after every step (``transient.runin._Run.record``:
      rms slope and the other diagnostics of the history);
    - checkpoints and the final run file (:func:`transient.output.write_run`,
      HDF5 with the history, written atomically), and reading a run file;
    - the final comparison with the steady face
      (:func:`transient.comparison.compare_with_steady` and
      :meth:`~transient.problem.WearProblem.solve_steady`);
    - everything else (the step loop, rates, error norms, the scene, set-up).

    Each timer counts its own time only (a timed part inside another is
    taken out of the outer one).  A part whose function does not exist in
    the installed code is reported as absent, so that the script runs on
    later versions of the run loop unchanged.

How to run
    python studies/benchmarks/profile_runin.py --n 512            # ~1 min on 2 cores
    python studies/benchmarks/profile_runin.py --n 512 --checkpoint-interval 0
    python studies/benchmarks/profile_runin.py --n 40 --quick     # smoke test

``--cprofile FILE`` also writes :mod:`cProfile` statistics of the run.
Prints the shares as a Markdown table and writes them to ``--out`` (HDF5).
"""

from __future__ import annotations

import argparse
import contextlib
import cProfile
import functools
import importlib
import io
import pathlib
import platform
import re
import sys
import tempfile
import time

import numpy as np

from steady.safe_files import atomic_h5

SCENE = (pathlib.Path(__file__).resolve().parents[2] / "steady" / "examples"
         / "voronoi_transient.toml")
N = 512

#: The timed parts: label and the functions (module, dotted attribute) behind it.
PARTS = {
    "contact solves": [("transient.solver", "StageSolver.contact")],
    "stages outside the solver (warm start, face rebuild)": [
        ("transient.warm_start", "WarmStart.predict"),
        ("transient.solver", "StageSolver._rebuild")],
    "per-step diagnostics (history figures)": [("transient.recording", "RunRecord.record")],
    "checkpoints and run file (HDF5)": [("transient.output", "write_run"),
                                        ("transient.output", "read_run")],
    "comparison with the steady face": [
        ("transient.comparison", "compare_with_steady"),
        ("transient.problem", "WearProblem.solve_steady")],
}


class Timers:
    """Exclusive wall time per label, for nested calls of wrapped functions."""

    def __init__(self):
        self.total = {}
        self.calls = {}
        self._stack = []

    def wrap(self, label, function):
        """``function`` timed under ``label``."""
        @functools.wraps(function)
        def timed(*args, **kwargs):
            self._stack.append([label, 0.0])
            t = time.perf_counter()
            try:
                return function(*args, **kwargs)
            finally:
                elapsed = time.perf_counter() - t
                _, inner = self._stack.pop()
                self.total[label] = self.total.get(label, 0.0) + elapsed - inner
                self.calls[label] = self.calls.get(label, 0) + 1
                if self._stack:
                    self._stack[-1][1] += elapsed
        return timed


def install(timers):
    """Wrap every function of :data:`PARTS` that exists; return the labels found and missing."""
    found, missing = {}, {}
    for label, targets in PARTS.items():
        for module_name, attribute in targets:
            module = importlib.import_module(module_name)
            owner, name = module, attribute
            *path, name = attribute.split(".")
            for part in path:
                owner = getattr(owner, part, None)
            if owner is None or not hasattr(owner, name):
                missing.setdefault(label, []).append(f"{module_name}.{attribute}")
                continue
            setattr(owner, name, timers.wrap(label, getattr(owner, name)))
            found.setdefault(label, []).append(f"{module_name}.{attribute}")
    return found, missing


def scene_copy(n, directory):
    """The shipped scene with ``[grid] n`` set to ``n``, written into ``directory``."""
    text = SCENE.read_text()
    text, count = re.subn(r"(?m)^(\[grid\][^\[]*?^n\s*=\s*)\d+", rf"\g<1>{n}", text)
    if count != 1:
        raise ValueError(f"no [grid] n in {SCENE}")
    path = pathlib.Path(directory) / f"scene_n{n}.toml"
    path.write_text(text)
    return path


def profile(n, *, tol=None, checkpoint_interval=None, cprofile=None):
    """Run the command line once under the timers; return the rows of the shares table."""
    timers = Timers()
    found, missing = install(timers)
    # Imported after the wrapping, so that names it imports are the timed ones.
    cli = importlib.import_module("transient.__main__")
    with tempfile.TemporaryDirectory() as tmp:
        argv = [str(scene_copy(n, tmp)), "-o", str(pathlib.Path(tmp) / "run.h5"), "--force"]
        if tol is not None:
            argv += ["--tol", repr(tol)]
        if checkpoint_interval is not None:
            argv += ["--checkpoint-interval", repr(checkpoint_interval)]
        profiler = cProfile.Profile() if cprofile else None
        t = time.perf_counter()
        if profiler:
            profiler.enable()
        with contextlib.redirect_stdout(io.StringIO()):  # the command line's summary
            status = cli.main(argv)
        if profiler:
            profiler.disable()
            profiler.dump_stats(cprofile)
        wall = time.perf_counter() - t
    if status != 0:
        raise RuntimeError(f"the run ended with exit status {status}")
    rows = []
    for label in PARTS:
        seconds = timers.total.get(label, 0.0)
        rows.append(dict(part=label, seconds=seconds, share=seconds / wall,
                         calls=timers.calls.get(label, 0),
                         functions=", ".join(found.get(label, [])) or "absent"))
    other = wall - sum(r["seconds"] for r in rows)
    rows.append(dict(part="everything else", seconds=other, share=other / wall, calls=1,
                     functions="set-up, step loop, rates, error norms"))
    rows.append(dict(part="whole run", seconds=wall, share=1.0, calls=1, functions="main()"))
    if missing:
        rows[-1]["missing"] = "; ".join(f"{k}: {', '.join(v)}" for k, v in missing.items())
    return rows


def markdown(rows):
    """The shares in Markdown."""
    lines = ["| part | wall (s) | share | calls |", "|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['part']} | {r['seconds']:.2f} | {100 * r['share']:.1f} % | "
                     f"{r['calls']} |")
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
        The rows of the shares table.
    """
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=N)
    parser.add_argument("--tol", type=float, help="override the scene's tol")
    parser.add_argument("--checkpoint-interval", type=float,
                        help="seconds between checkpoints (default: the scene's)")
    parser.add_argument("--quick", action="store_true", help="smoke test (loose tol)")
    parser.add_argument("--cprofile", type=pathlib.Path, help="also write cProfile stats")
    parser.add_argument("--out", type=pathlib.Path, default=pathlib.Path("profile_runin.h5"))
    args = parser.parse_args(argv)
    tol = 1e-2 if args.quick and args.tol is None else args.tol
    rows = profile(args.n, tol=tol, checkpoint_interval=args.checkpoint_interval,
                   cprofile=args.cprofile)
    print(markdown(rows))
    if "missing" in rows[-1]:
        print(f"absent in this version: {rows[-1]['missing']}")
    with atomic_h5(args.out, format="runin.profile_runin", version=1, force=True) as f:
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
