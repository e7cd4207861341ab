"""Load programmes: a normal force that changes in steps along the sliding distance.

A scene's ``[load] programme = [[s_1, F_1], [s_2, F_2], ...]`` holds the
force ``F_i`` (N) from the sliding distance ``s_i`` (m, from the start of
the run-in) on, up to the next breakpoint; before ``s_1`` the scene's
``normal_force`` holds (a breakpoint at ``s_1 = 0`` replaces it from the
start).  The steady state of such a scene is the one under the last force
(docs/model.md, "Load programmes").

Examples
--------
>>> programme = LoadProgramme(10.0, ((0.5, 20.0), (2.0, 5.0)))
>>> programme.force_at(0.1), programme.force_at(0.5), programme.force_at(3.0)
(10.0, 20.0, 5.0)
>>> programme.next_breakpoint(0.5), programme.next_breakpoint(2.0)
(2.0, None)
>>> programme.final_force
5.0
"""

from __future__ import annotations

import bisect
import dataclasses

from .schema import Key
from .text import shorten

__all__ = ["BREAKPOINT_SLACK", "LoadProgramme", "check_programme"]

#: A pair of a programme: the distance from which its force acts, and the force.
_DISTANCE = Key("distance", "number", unit="m", low=0.0, low_open=False)
_FORCE = Key("force", "number", unit="N", low=0.0)

#: Relative slack with which a distance counts as reached (round-off of summed steps).
BREAKPOINT_SLACK = 1e-12


def check_programme(pairs, where="[load] programme"):
    """The pairs ``(s_i, F_i)`` of a programme, checked; ``ValueError`` naming the bad value.

    Parameters
    ----------
    pairs : sequence of (float, float)
        Distances (m, finite, ``>= 0``, strictly increasing) and forces (N,
        finite, ``> 0``), as a scene key of type ``"pairs"`` reads them.
    where : str, optional
        The key, for messages.

    Returns
    -------
    tuple of (float, float)
    """
    # The forces' scale range is checked with the problem's (steady.scene).
    pairs = tuple((_DISTANCE.parse(s, f"{where} pair {i}", scale=False),
                   _FORCE.parse(f, f"{where} pair {i}", scale=False))
                  for i, (s, f) in enumerate(pairs))
    if not pairs:
        raise ValueError(f"{where} must hold at least one [distance, force] pair, got []")
    for i, (s, _) in enumerate(pairs):
        if i and s <= pairs[i - 1][0]:
            raise ValueError(f"{where}: distances must increase, got {s!r} m after "
                             f"{pairs[i - 1][0]!r} m (pairs {shorten([list(p) for p in pairs])})")
    return pairs


@dataclasses.dataclass(frozen=True)
class LoadProgramme:
    """A piecewise-constant normal force along the sliding distance.

    Parameters
    ----------
    initial_force : float, N
        The force before the first breakpoint (the scene's ``normal_force``).
    pairs : sequence of (float, float)
        ``(s_i, F_i)``: the force ``F_i`` (N) from the distance ``s_i`` (m)
        on; checked by :func:`check_programme`.

    Attributes
    ----------
    breakpoints : tuple of float, m
        The distances ``s_i``.
    forces : tuple of float, N
        The forces ``F_i``.
    """

    initial_force: float
    pairs: tuple

    def __post_init__(self):
        """Check the pairs."""
        object.__setattr__(self, "pairs", check_programme(self.pairs))
        object.__setattr__(self, "initial_force", float(self.initial_force))

    @property
    def breakpoints(self):
        """The distances ``s_i`` at which the force changes, m."""
        return tuple(s for s, _ in self.pairs)

    @property
    def forces(self):
        """The forces ``F_i``, N."""
        return tuple(f for _, f in self.pairs)

    @property
    def final_force(self):
        """The force after the last breakpoint, N: the one of the steady state."""
        return self.pairs[-1][1]

    def _reached(self, s):
        """Breakpoints reached at ``s`` (m), within :data:`BREAKPOINT_SLACK`."""
        return bisect.bisect_right(self.breakpoints, s * (1 + BREAKPOINT_SLACK))

    def force_at(self, s):
        """The force at the sliding distance ``s`` (m), N (a breakpoint's own force on it)."""
        i = self._reached(s)
        return self.initial_force if i == 0 else self.pairs[i - 1][1]

    def next_breakpoint(self, s):
        """The first breakpoint beyond ``s`` (m), m; None after the last."""
        i = self._reached(s)
        return self.breakpoints[i] if i < len(self.pairs) else None

    def rises(self, s, *, before=False):
        """The rises of the force reached at ``s`` (m): ``(s_j, dF_j)`` pairs, m and N.

        The first is the load applied at the start, ``(0, F(0))``; then each
        breakpoint where the force rose, with its increase.  With
        ``before`` a breakpoint at ``s`` itself is not yet reached.

        Examples
        --------
        >>> p = LoadProgramme(10.0, ((1.0, 20.0), (2.0, 5.0), (3.0, 8.0)))
        >>> p.rises(2.5)
        ((0.0, 10.0), (1.0, 10.0))
        >>> p.rises(3.0), p.rises(3.0, before=True)
        (((0.0, 10.0), (1.0, 10.0), (3.0, 3.0)), ((0.0, 10.0), (1.0, 10.0)))
        """
        reached = self._reached(s)
        if before and reached and self.breakpoints[reached - 1] >= s * (1 - BREAKPOINT_SLACK):
            reached -= 1
        force = self.force_at(0.0)
        out = [(0.0, force)]
        for s_i, f_i in self.pairs[:reached]:
            if s_i > 0.0 and f_i > force:
                out.append((s_i, f_i - force))
            force = f_i
        return tuple(out)

    def rim_layers(self, s, *, before=False):
        """The rim layers the rises of the force reached at ``s`` (m) have worn so far.

        Each rise adds the flat punch's pressure under the increase,
        singular at the rim, whose worn layer grows from the rise on: one
        ``(s - s_j (m), (dF_j / F_final)^2)`` per rise (:meth:`rises`, with
        ``before``), ``F_final`` the programme's last force, the run's
        normal force.

        Examples
        --------
        >>> LoadProgramme(10.0, ((1.0, 20.0),)).rim_layers(3.0)
        ((3.0, 0.25), (2.0, 0.25))
        """
        return tuple((s - s_j, (rise / self.final_force) ** 2)
                     for s_j, rise in self.rises(s, before=before))

    def snap(self, s):
        """``s`` (m) replaced by the breakpoint it reached within the slack, if any."""
        i = self._reached(s)
        if i and abs(s - self.breakpoints[i - 1]) <= BREAKPOINT_SLACK * abs(s):
            return self.breakpoints[i - 1]
        return s
