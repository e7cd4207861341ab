"""A measured height map of a worn face: heights in metres on a grid of pixels.

:class:`MeasuredFace` is what the wear-ratio fit (:mod:`steady.fit`) takes;
the readers of measured files (:func:`steady.fit_files.read_measured`)
return one.  Arrays are indexed ``[i, j]`` with ``i`` along x, like every
field of the project; a height is the face's elevation towards the
counter-body (larger = protruding), the sign of the steady face
``f_inf = K p``; NaN marks a missing pixel.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from .array_files import REAL_NUMBERS
from .schema import Key
from .text import shorten

__all__ = ["MeasuredFace", "check_pixel_size"]


#: The side of a measured map's pixels, along x or y.
_PIXEL_SIZE = Key("pixel_size", "number", unit="m", low=0.0)


def check_pixel_size(pixel_size, where=""):
    """``(dx, dy)`` from a number or a pair, each a length > 0; ``ValueError`` otherwise.

    Parameters
    ----------
    pixel_size : float or (float, float), m
        A square pixel's side, or ``(dx, dy)``.
    where : str, optional
        What the pixel size is of, for the message (``"measured map 'face.npy'"``).

    Returns
    -------
    (float, float), m
    """
    values = pixel_size.tolist() if isinstance(pixel_size, np.ndarray) else pixel_size
    if not isinstance(values, (list, tuple)):
        values = [values]
    if len(values) not in (1, 2):
        name = f"{where} pixel_size" if where else "pixel_size"
        raise ValueError(f"{name} must be one or two lengths (m), got {shorten(pixel_size)}")
    # Any length a measurement gives is taken: the scale range is a problem's to check.
    return tuple(_PIXEL_SIZE.parse(v, where, scale=False) for v in (values[0], values[-1]))


@dataclasses.dataclass(frozen=True, eq=False)
class MeasuredFace:
    """A measured height map of a worn face.

    Parameters
    ----------
    heights : array_like, shape (nx, ny), m
        Face elevation (larger = protruding) at the pixel centres, indexed
        ``[i, j]`` with ``i`` along x; NaN where the measurement has no
        value.  Stored as a read-only float array.
    pixel_size : float or (float, float), m
        Pixel side, or ``(dx, dy)``.
    source : str, optional
        Where the map came from (for messages and the result file).

    Notes
    -----
    The map's centre, the middle of its pixel array, is taken as the face's
    centre (the origin of its outline, the axis of a disk) unless the fit is
    given or searches a shift.
    """

    heights: np.ndarray
    pixel_size: tuple
    source: str = "array"

    def __post_init__(self):
        """Check the array and the pixel size; store them read-only."""
        raw = np.asarray(self.heights)
        if raw.dtype.kind != "O":  # as from a file; Python objects are tried as numbers below
            REAL_NUMBERS.check(raw.dtype, f"measured map {self.source}")
        try:
            h = np.array(raw, dtype=float)
        except (TypeError, ValueError) as err:
            raise ValueError(f"measured map {self.source} must hold real numbers: "
                             f"{str(err)[:200]}") from None
        if h.ndim != 2 or min(h.shape) < 2:
            raise ValueError(f"measured map {self.source} must be a 2-d array of at least 2 x 2 "
                             f"pixels, got shape {h.shape}")
        if np.any(np.isinf(h)):
            raise ValueError(f"measured map {self.source} holds infinite heights")
        if not np.any(np.isfinite(h)):
            raise ValueError(f"measured map {self.source} holds no finite height")
        h.flags.writeable = False
        object.__setattr__(self, "heights", h)
        object.__setattr__(self, "pixel_size",
                           check_pixel_size(self.pixel_size, f"measured map {self.source}"))

    @property
    def shape(self):
        """``(nx, ny)``, pixels."""
        return self.heights.shape

    @property
    def extent(self):
        """Size of the map ``(nx dx, ny dy)``, m."""
        return (self.shape[0] * self.pixel_size[0], self.shape[1] * self.pixel_size[1])

    def coordinates(self):
        """Pixel-centre coordinates from the map's centre.

        Returns
        -------
        x : ndarray, shape (nx,), m
        y : ndarray, shape (ny,), m
        """
        (nx, ny), (dx, dy) = self.shape, self.pixel_size
        return (np.arange(nx) - 0.5 * (nx - 1)) * dx, (np.arange(ny) - 0.5 * (ny - 1)) * dy
