"""The progress display of ``runin-transient``: a bar at a terminal, log lines elsewhere.

At a terminal (stderr a tty) a tqdm bar shows how far the run is from its
end: the wear-rate spread falls from 1 (or its start) to the tolerance at
which the run ends (``jump_spread``, where the jump to the steady state
ends it, or ``spread_tol`` without jumps), roughly exponentially in the
sliding distance, so the bar's fraction is ``log(spread) / log(target)``,
with the step, the distance and the spread beside it.  Elsewhere (a pipe, a
log file) nothing is shown by default; with ``-v`` one line per step, at
most one every :data:`LOG_INTERVAL` seconds (the first and every jump
always), goes to the log (stderr): the step, the distance in m and in
``s*``, the spread of the phase wear rates and the latest rms slope the
history has computed (its figures are computed beside the run, so it may
lag a step or two behind; the line says at which step it was).
"""

from __future__ import annotations

import logging
import math
import shutil
import sys
import time

import numpy as np

__all__ = ["LOG_INTERVAL", "Progress", "end_fraction"]

logger = logging.getLogger(__name__)

#: Least time between two progress lines of ``-v`` outside a terminal, s.
LOG_INTERVAL = 1.0

# Resolution of the bar: its fraction in thousandths.
_TOTAL = 1000


def end_fraction(spread, options):
    """How far a run is from its end, in [0, 1], from its wear-rate spread.

    Parameters
    ----------
    spread : float
        The current wear-rate spread (``(max - min) / mean``; 1 with pixels
        out of contact).
    options : transient.options.RunOptions
        The run's options: the run ends once the spread is below
        ``jump_spread`` (if it jumps) or ``spread_tol``.

    Returns
    -------
    float
        ``log(spread) / log(target)`` clipped to [0, 1]; 0 when the target
        is 1 or above (nothing to measure).

    Examples
    --------
    >>> from transient.options import RunOptions
    >>> print(f"{end_fraction(0.03, RunOptions(jump_spread=1e-3)):.3f}")
    0.508
    """
    target = max(options.spread_tol, options.jump_spread) if options.jump_spread > 0 \
        else options.spread_tol
    if not (0 < target < 1) or not spread > 0:
        return 0.0 if not spread <= target else 1.0
    return float(np.clip(math.log(min(spread, 1.0)) / math.log(target), 0.0, 1.0))


class Progress:
    """The ``on_step`` callback of :func:`transient.runin.run_in`: a bar, or log lines.

    Parameters
    ----------
    start : int
        Steps already taken (a resumed run).
    log : bool, optional
        Log one line per step (rate-limited) when stderr is not a terminal
        (``-v``; default False).
    label : str, optional
        What runs: the bar's name and, but for the main run (default
        ``"run-in"``), the log lines' first words.
    """

    def __init__(self, start, log=False, label="run-in"):
        from tqdm import tqdm

        self.terminal = sys.stderr.isatty()
        self.log = bool(log) and not self.terminal
        self.last_line = -math.inf
        self.last_jumps = None
        # Some terminals report no size (tqdm then draws nothing): fall back to 100 x 40.
        cols, rows = shutil.get_terminal_size((100, 40))
        self.start = start
        self.prefix = "" if label == "run-in" else f"{label}: "
        self.bar = tqdm(desc=label, total=_TOTAL, unit="", file=sys.stderr,
                        disable=not self.terminal, ncols=cols if cols > 0 else 100,
                        nrows=rows if rows > 0 else 40,
                        bar_format="{desc}: {percentage:3.0f}%|{bar}| {elapsed}{postfix}")

    def __call__(self, run):
        """Show the run's progress after an accepted step (a jump too)."""
        spread = run.latest[0]
        s = run.s
        if not self.bar.disable:
            self.bar.n = max(self.bar.n, round(_TOTAL * end_fraction(spread, run.options)))
            self.bar.set_postfix_str(f"step {run.steps}, s={s / run.s_star:.4g} s*, "
                                     f"spread={spread:.2e}", refresh=False)
            self.bar.refresh()
        if self.log:
            now = time.monotonic()
            jumped = run.jumps != self.last_jumps and self.last_jumps is not None
            if jumped or now - self.last_line >= LOG_INTERVAL:
                self.last_line = now
                logger.info("%s%s", self.prefix, self.line(run))
            self.last_jumps = run.jumps

    @staticmethod
    def line(run):
        """The progress line of a run's current point."""
        spread = run.latest[0]
        slope = np.asarray(run.history["rms_slope"], dtype=float)
        known = np.flatnonzero(np.isfinite(slope))
        if known.size:
            i = int(known[-1])
            slope_text = (f"rms slope {slope[i]:.6g} (at s = "
                          f"{run.history['distance'][i] / run.s_star:.4g} s*)")
        else:
            slope_text = "rms slope not yet computed"
        return (f"step {run.steps}: s = {run.s:.6g} m = {run.s / run.s_star:.6g} s*, "
                f"wear-rate spread {spread:.3g}, {slope_text}")

    def close(self):
        """Remove the bar."""
        self.bar.close()
