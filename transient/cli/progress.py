"""The progress bar of ``runin-transient`` (a terminal's stderr only)."""

from __future__ import annotations

import shutil
import sys

__all__ = ["Progress"]


class Progress:
    """tqdm bar: steps, distance in s*, wear-rate spread (quiet unless stderr is a tty)."""

    def __init__(self, start):
        from tqdm import tqdm

        # Some terminals report no size (tqdm then draws nothing): fall back to 100 x 40.
        cols, rows = shutil.get_terminal_size((100, 40))
        self.bar = tqdm(desc="run-in", unit="step", initial=start, file=sys.stderr,
                        disable=not sys.stderr.isatty(), ncols=cols if cols > 0 else 100,
                        nrows=rows if rows > 0 else 40)

    def __call__(self, run):
        """Show the run's steps, distance and spread after an accepted step."""
        self.bar.update(run.steps - self.bar.n)
        self.bar.set_postfix_str(f"s={run.s / run.s_star:.4g} s*, "
                                 f"spread={run.history['spread'][-1]:.2e}", refresh=False)

    def close(self):
        """Remove the bar."""
        self.bar.close()
