"""Phase maps that change with depth below the initial surface: columns of segments.

The paper's punch is columnar: the phase of a face pixel does not depend on
how deep the face has worn.  A coating, a multilayer, a tomography stack or
a particle composite is not.  Every depth-varying geometry is rasterised
here into *columns*: along the line below each face pixel, the depths at
which the phase changes (the *interfaces*) and the phase of each *segment*
between two of them.

- ``interfaces`` has shape ``(S, nx, ny)``, m: ascending along the first
  axis at every pixel, finite for the pixel's own interfaces and ``+inf``
  beyond them (the padding of pixels with fewer than ``S`` interfaces);
- ``phases`` has shape ``(S + 1, nx, ny)``: the phase of segment ``j``,
  which lies between ``interfaces[j - 1]`` (0 for ``j = 0``, the initial
  surface) and ``interfaces[j]``; the last finite segment of a pixel goes
  on for ever (the material below the geometry is columnar).  Off the face
  every entry is ``-1``.

A depth exactly at an interface belongs to the segment below it.  The
depth is the worn depth ``w(x, y)`` below the initial surface, m, never
negative.  A columnar map is the special case ``S = 0``
(:meth:`DepthColumns.from_labels`).
"""

from __future__ import annotations

import dataclasses
import functools

import numpy as np

__all__ = ["DepthColumns"]


@dataclasses.dataclass(frozen=True, eq=False)
class DepthColumns:
    """The phase below every face pixel as a function of depth, checked.

    Parameters
    ----------
    interfaces : array_like of float, shape (S, nx, ny), m
        Depths of the phase changes below each pixel, ascending, ``> 0`` and
        finite, then ``+inf`` padding (module docstring).
    phases : array_like of int, shape (S + 1, nx, ny)
        Phase of each segment, ``0..P-1`` on the face, ``-1`` off it (the
        face is the set of pixels whose first segment has a phase); a padded
        segment repeats the pixel's last phase.
    n_phases : int
        ``P``.  Every phase must occur somewhere in the columns (not
        necessarily at the surface).

    Raises
    ------
    ValueError
        Shapes that do not match, no face pixel, interfaces that are not
        positive, not ascending or NaN, phases outside ``0..P-1`` on the face, a face that
        changes with depth, or a phase that occurs nowhere; the message
        names the value and, for a pixel, its index.

    Examples
    --------
    A coating 1 um thick of phase 1 over a substrate of phase 0 on a 2 x 2
    face:

    >>> import numpy as np
    >>> columns = DepthColumns(np.full((1, 2, 2), 1e-6), np.stack(
    ...     [np.ones((2, 2), int), np.zeros((2, 2), int)]), 2)
    >>> columns.phase_at(np.array([[0.0, 5e-7], [1e-6, 2e-6]])).tolist()
    [[1, 1], [0, 0]]
    """

    interfaces: np.ndarray
    phases: np.ndarray
    n_phases: int

    def __post_init__(self):
        """Check the columns and store them read-only."""
        z = np.array(self.interfaces, dtype=float, copy=True)
        phases = np.array(self.phases, copy=True)
        if z.ndim != 3:
            raise ValueError(f"interfaces must have shape (S, nx, ny), got {z.shape}")
        if phases.shape != (z.shape[0] + 1,) + z.shape[1:]:
            raise ValueError(f"phases must have shape (S + 1, nx, ny) = "
                             f"{(z.shape[0] + 1,) + z.shape[1:]} to match interfaces "
                             f"{z.shape}, got {phases.shape}")
        if not np.issubdtype(phases.dtype, np.integer):
            raise ValueError(f"phases must be integers, got dtype {phases.dtype}")
        n_phases = int(self.n_phases)
        face = phases[0] >= 0
        with np.errstate(invalid="ignore"):  # inf - inf in the padding
            descending = np.diff(z, axis=0) < 0.0
        for what, bad in (("NaN", np.isnan(z)), ("not positive", z <= 0.0),
                          ("not ascending", descending)):
            where = np.argwhere(bad & face)
            if where.size:
                raise ValueError(f"interfaces: depth {what} below pixel "
                                 f"{tuple(int(i) for i in where[0][1:])}")
        if not face.any():
            raise ValueError("phases: no face pixel (every first segment is -1)")
        off = np.argwhere((phases >= 0) != face)
        if off.size:
            raise ValueError(f"phases: the face changes with depth at pixel "
                             f"{tuple(int(i) for i in off[0][1:])} (segment {int(off[0][0])})")
        bad = np.argwhere(face & ((phases >= n_phases) | (phases < 0)))
        if bad.size:
            raise ValueError(f"phases: phase {int(phases[tuple(bad[0])])} at pixel "
                             f"{tuple(int(i) for i in bad[0][1:])} is outside 0..{n_phases - 1}")
        present = np.bincount(phases[:, face].ravel(), minlength=n_phases)
        absent = np.flatnonzero(present == 0)
        if absent.size:
            raise ValueError(f"phase {int(absent[0])} occurs nowhere in the columns")
        for a in (z, phases):
            a.flags.writeable = False
        object.__setattr__(self, "interfaces", z)
        object.__setattr__(self, "phases", phases)
        object.__setattr__(self, "n_phases", n_phases)

    @classmethod
    def from_labels(cls, labels, n_phases):
        """The columnar map of a 2-d phase map (``S = 0``): the paper's punch."""
        labels = np.asarray(labels)
        return cls(np.zeros((0,) + labels.shape), labels[None], n_phases)

    @property
    def shape(self):
        """``(nx, ny)``."""
        return self.phases.shape[1:]

    @property
    def face_mask(self):
        """Face pixels, shape (nx, ny)."""
        return self.phases[0] >= 0

    @property
    def n_interfaces(self):
        """``S``, the most interfaces below one pixel."""
        return self.interfaces.shape[0]

    @property
    def columnar(self):
        """Whether no pixel has an interface: the phase map does not change with depth."""
        return not np.isfinite(self.interfaces).any()

    @property
    def bottom(self):
        """Depth of each pixel's last interface, m, shape (nx, ny); 0 where it has none.

        Below it the pixel's phase no longer changes.
        """
        finite = np.where(np.isfinite(self.interfaces), self.interfaces, 0.0)
        return finite.max(axis=0, initial=0.0)

    def describe(self):
        """The columns in words: their interfaces, how deep and below how many face pixels.

        Examples
        --------
        >>> columns = DepthColumns(np.full((1, 2, 2), 1e-6), np.stack(
        ...     [np.ones((2, 2), int), np.zeros((2, 2), int)]), 2)
        >>> columns.describe()
        '4 interfaces at depth 1e-06 m below 4 of 4 face pixels'
        """
        face = self.face_mask
        finite = np.isfinite(self.interfaces[:, face])
        if not finite.any():
            return "no interface below the face"
        z = self.interfaces[:, face][finite]
        lo, hi = float(z.min()), float(z.max())
        at = f"at depth {lo:.4g} m" if lo == hi else f"at depths {lo:.4g} to {hi:.4g} m"
        below = int(finite.any(axis=0).sum())
        return f"{z.size} interfaces {at} below {below} of {int(face.sum())} face pixels"

    @functools.cached_property
    def digest(self):
        """SHA-256 (hex) of the columns: equal for equal interfaces, phases and ``n_phases``.

        What a checkpoint records of them (the columns themselves are
        larger than the rest of a run file), to compare a resumed run's;
        computed once.
        """
        import hashlib

        h = hashlib.sha256()
        h.update(np.asarray(self.interfaces.shape + (self.n_phases,), dtype="<i8").tobytes())
        h.update(np.ascontiguousarray(self.interfaces, dtype="<f8").tobytes())
        h.update(np.ascontiguousarray(self.phases, dtype="<i8").tobytes())
        return h.hexdigest()

    def segment_at(self, depth):
        """Index of the segment at ``depth`` (m, shape (nx, ny)) below each pixel.

        A depth exactly at an interface is in the segment below it.
        """
        depth = np.asarray(depth, dtype=float)
        return np.sum(self.interfaces <= depth, axis=0)

    def phase_at(self, depth):
        """Phase at ``depth`` (m, shape (nx, ny)) below each pixel, -1 off the face.

        Parameters
        ----------
        depth : array_like, shape (nx, ny) or scalar, m
            Depth below the initial surface; a scalar is the same at every
            pixel (a plane section).
        """
        depth = np.broadcast_to(np.asarray(depth, dtype=float), self.shape)
        index = self.segment_at(depth)
        return np.take_along_axis(self.phases, index[None], axis=0)[0]

    def next_interface(self, depth):
        """Depth of the first interface strictly below ``depth``, m, shape (nx, ny); inf if none."""
        depth = np.broadcast_to(np.asarray(depth, dtype=float), self.shape)
        index = np.minimum(self.segment_at(depth), self.n_interfaces)
        padded = np.concatenate([self.interfaces, np.full((1,) + self.shape, np.inf)])
        return np.take_along_axis(padded, index[None], axis=0)[0]

    def columnar_below(self, depth):
        """Whether every face pixel is at or below its last interface at ``depth`` (m)."""
        depth = np.broadcast_to(np.asarray(depth, dtype=float), self.shape)
        face = self.face_mask
        return bool(np.all(depth[face] >= self.bottom[face]))

    def fractions(self, depth):
        """Area fraction of each phase in the section at ``depth`` (m), shape (P,)."""
        labels = self.phase_at(depth)
        counts = np.bincount(labels[labels >= 0], minlength=self.n_phases)
        return counts / counts.sum()
