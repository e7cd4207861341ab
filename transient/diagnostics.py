"""Pixel figures of the run-in's face: shape, differences, plain rms slope, wear-rate spread.

The run loop (:mod:`transient.runin`) and its step control use the shape
and the spread; the history's rms slope and rms height
(:mod:`transient.history`) use the differences and keep the plain pixel rms
slope beside the continuum estimate; the comparison with the steady face
(:mod:`transient.comparison`) uses the same definitions, so that the last
recorded point and the comparison agree.
"""

from __future__ import annotations

import numpy as np

__all__ = ["face_rms_slope", "masked_gradient", "shape_rms", "wear_rate_spread"]


def shape_rms(field, face_mask):
    """Rms over the face of ``field`` with its face mean removed (the shape, not the offset)."""
    v = field[face_mask]
    v = v - v.mean()
    return float(np.sqrt(np.mean(v * v)))


def masked_gradient(field, face_mask, h, *, periodic=False, stride=1):
    """Finite-difference gradient using only pixels of the face (central where possible).

    Parameters
    ----------
    field : ndarray, shape (nx, ny)
    face_mask : ndarray of bool, shape (nx, ny)
    h : float, m
        Pixel size.
    periodic : bool, optional
        Whether the grid is a periodic cell (the outline's ``periodic``):
        the neighbours of an edge pixel are then those across the opposite
        edge, so that differences are central there too and the gradient
        of a face that repeats with the cell does not depend on where the
        cell's origin lies.  Default False: off the grid is off the face.
    stride : int, optional
        Pixels between a pixel and its neighbours (default 1): differences
        over ``stride h``, those of a grid ``stride`` times coarser taken at
        every pixel.

    Returns
    -------
    gx, gy : ndarray, shape (nx, ny)
        Central differences where both neighbours are on the face, one-sided
        where one is, zero where none is and off the face.

    Examples
    --------
    A cosine over a cell of eight pixels, at the pixels of both edges: central
    differences across the edge on the cell, one-sided ones on a finite face
    (the exact derivative is 0 and 4.44 there):

    >>> x = np.arange(8) / 8
    >>> field = np.broadcast_to(np.cos(2 * np.pi * x)[:, None], (8, 3))
    >>> face = np.ones((8, 3), bool)
    >>> cell, _ = masked_gradient(field, face, 1 / 8, periodic=True)
    >>> finite, _ = masked_gradient(field, face, 1 / 8)
    >>> print(np.round(cell[[0, 7], 0], 3), np.round(finite[[0, 7], 0], 3))
    [0. 4.] [-2.343  5.657]
    """
    f = np.where(face_mask, field, 0.0)
    step = stride * h
    out = []
    for fp, fm, on_p, on_m in _neighbours(f, face_mask, periodic, stride):
        mp, mm = on_p & face_mask, on_m & face_mask
        g = np.zeros(f.shape)
        both = mp & mm
        for where, a, b, width in ((both, fp, fm, 2 * step), (mp & ~mm, fp, f, step),
                                   (mm & ~mp, f, fm, step)):
            np.subtract(a, b, out=g, where=where)
            np.divide(g, width, out=g, where=where)
        out.append(g)
    return out


def _neighbours(f, face_mask, periodic, stride):
    """Along each axis in turn, the field and the face mask ``stride`` pixels ahead and behind.

    On a periodic cell by wrap-around (copies, one axis at a time);
    otherwise through a border of zeros, off the face (views of one padded
    array, no copies).
    """
    if periodic:
        for axis in (0, 1):
            yield (np.roll(f, -stride, axis), np.roll(f, stride, axis),
                   np.roll(face_mask, -stride, axis), np.roll(face_mask, stride, axis))
        return
    f_pad, on_pad = np.pad(f, stride), np.pad(face_mask, stride)
    for axis in (0, 1):
        ahead, behind = [slice(stride, -stride)] * 2, [slice(stride, -stride)] * 2
        ahead[axis], behind[axis] = slice(2 * stride, None), slice(None, -2 * stride)
        yield (f_pad[tuple(ahead)], f_pad[tuple(behind)],
               on_pad[tuple(ahead)], on_pad[tuple(behind)])


def face_rms_slope(halfspace, face_mask, recession, pressure, approach, *, gradient=None,
                   periodic=False):
    """Plain pixel rms slope of the worn face over the face pixels, dimensionless.

    On the contact the face is ``d - w = K p``, whose gradient is the exact
    kernel derivative convolved with the pressure (the definition of
    :func:`steady.solution.solve`, so that the final value compares with
    it); the gap ``w - (d - K p)`` off the contact adds its finite-difference
    gradient.  The history records it as ``rms_slope_plain``, beside the
    continuum estimate of :mod:`transient.history`.

    This is the slope of the half-space surface under the pixel pressure,
    at the pixel centres: a first-order quadrature of a log-singular
    integrand.  For the flat punch at ``s = 0`` it is not zero but a
    finite share of ``grad_f0`` that does not vanish under refinement
    (docs/model.md, "The run-in history", gives the measured values): the
    pixel pressure of the edge singularity, ``~ (a/h)^(1/2)``, makes
    ``K p`` ripple between the pixel centres of the rim, whose share of the
    face falls like ``h/a``.

    Parameters
    ----------
    halfspace : steady.halfspace.HalfSpace
    face_mask : ndarray of bool, shape (nx, ny)
    recession : ndarray, shape (nx, ny), m
    pressure : ndarray, shape (nx, ny), Pa
        Contact pressure of ``recession``.
    approach : float, m
    gradient : tuple of ndarray, optional
        ``halfspace.gradient(pressure)``, when the caller has it already.
    periodic : bool, optional
        Whether the grid is a periodic cell (the outline's ``periodic``):
        the gap's differences wrap around its edges (:func:`masked_gradient`).
        Default False.

    Returns
    -------
    float
    """
    pressure_q = halfspace.forward(pressure)
    if gradient is None:
        gradient = halfspace.gradient(pressure, pressure_q=pressure_q)
    gx, gy = gradient
    contact = pressure > 0
    if np.any(face_mask & ~contact):
        kp = halfspace.displacement_q(pressure_q)
        gap = np.where(face_mask, recession - (approach - kp), 0.0)
        gap = np.where(contact, 0.0, np.maximum(gap, 0.0))
        dx, dy = masked_gradient(gap, face_mask, halfspace.h, periodic=periodic)
        gx = gx - dx
        gy = gy - dy
    s2 = gx * gx + gy * gy
    return float(np.sqrt(np.mean(s2[face_mask])))


def wear_rate_spread(rate, pressure, face_mask):
    """Spread of the wear rate, the steady-state test (eq. 3).

    Parameters
    ----------
    rate : callable
        The wear rate of a pressure field, m/m (the run's
        :meth:`transient.solver.StageSolver.rate`: the law at the current
        section).
    pressure : ndarray, shape (nx, ny), Pa
    face_mask : ndarray of bool, shape (nx, ny)

    Returns
    -------
    float
        ``(max - min) / mean`` of ``g(p)`` over the face; 1 when some face
        pixel is out of contact (its rate is 0).
    """
    if np.any(pressure[face_mask] <= 0):
        return 1.0
    r = rate(pressure)[face_mask]
    return float((r.max() - r.min()) / r.mean())
