"""The square pixel grid that covers the punch face.

``n x n`` pixel centres cover ``[-a, a]^2`` with pixel size ``h = 2a/n``
(indexing ``ij``: axis 0 is x, axis 1 is y).  A pixel belongs to the face
when its centre lies inside the disk of radius ``a``.
"""

from __future__ import annotations

import numpy as np

__all__ = ["face_mask", "pixel_centres", "pixel_size", "polar"]


def pixel_size(n, radius):
    """Pixel side ``h = 2a / n``, m."""
    return 2.0 * radius / n


def pixel_centres(n, radius):
    """Coordinates of the pixel centres along one axis.

    Parameters
    ----------
    n : int
        Pixels across the diameter.
    radius : float, m
        Punch radius ``a``.

    Returns
    -------
    ndarray, shape (n,), m
        ``-a + (i + 1/2) h`` for ``i = 0..n-1``.
    """
    h = pixel_size(n, radius)
    return -radius + (np.arange(n) + 0.5) * h


def polar(n, radius):
    """Radius and azimuth of every pixel centre.

    Returns
    -------
    r : ndarray, shape (n, n), m
    theta : ndarray, shape (n, n), rad
    """
    x = pixel_centres(n, radius)
    X, Y = np.meshgrid(x, x, indexing="ij")
    return np.hypot(X, Y), np.arctan2(Y, X)


def face_mask(n):
    """Pixels whose centre lies strictly inside the unit disk.

    The mask does not depend on the radius: it is the same for every ``a``.

    Returns
    -------
    ndarray of bool, shape (n, n)
    """
    # Integer arithmetic: (2i + 1 - n)^2 + (2j + 1 - n)^2 < n^2 is exact.
    c = 2 * np.arange(n) + 1 - n
    return c[:, None] ** 2 + c[None, :] ** 2 < n * n
