"""Rasterised phase maps: label checks, fill factors, and fields extended off the face.

A phase map on a grid is an integer array: the phase index ``0..P-1`` of
every face pixel, ``-1`` off the face.  :func:`validate_labels` checks one
against its declared number of phases ``P`` (every phase on the face);
:func:`realised_fill_factors` gives the phases' area fractions (eq. 13).
"""

from __future__ import annotations

import math

import numpy as np
from scipy import ndimage

from .schema import Key

__all__ = ["apportion", "check_fill_factors", "extend_off_face", "realised_fill_factors",
           "validate_labels"]

#: Tolerance on the sum of the fill factors.
_FILL_SUM_TOL = 1e-9

#: Phases a phase map is checked against.
_N_PHASES = Key("n_phases", "integer", low=1, low_open=False)


def validate_labels(labels, n_phases, *, face_mask=None):
    """Check a rasterised phase map and count the pixels of each phase.

    Parameters
    ----------
    labels : ndarray, shape (nx, ny), int
        Phase index on the face, ``-1`` off the face.
    n_phases : int
        Number of phases ``P``.
    face_mask : ndarray of bool, shape (nx, ny), optional
        The face's pixels (e.g. :attr:`steady.outline.FaceGrid.mask`), to
        check the labels against; default: the pixels with ``labels >= 0``.

    Returns
    -------
    ndarray, shape (P,), int
        Face pixels of each phase.

    Raises
    ------
    ValueError
        If the array is not 2-d, the face pixels do not carry labels
        ``0..P-1``, a pixel off the face is not ``-1``, there is no face
        pixel, or a phase has no pixel.
    """
    labels = np.asarray(labels)
    if labels.ndim != 2:
        raise ValueError(f"phase labels must be a 2-d array, got shape {labels.shape}")
    if not np.issubdtype(labels.dtype, np.integer):
        raise ValueError(f"phase labels must be integers, got dtype {labels.dtype}")
    n_phases = _N_PHASES.parse(n_phases, "")
    mask = labels >= 0 if face_mask is None else np.asarray(face_mask)
    if mask.shape != labels.shape:
        raise ValueError(f"face mask of shape {mask.shape} for labels of shape {labels.shape}")
    if not mask.any():
        raise ValueError("the phase map has no face pixel")
    face_labels = labels[mask]
    low, high = int(face_labels.min()), int(face_labels.max())
    if low < 0:
        raise ValueError(f"phase label {low} found on the face; face pixels need labels "
                         f"0..{n_phases - 1}")
    if high >= n_phases:
        raise ValueError(f"unknown phase label {high} on the face: there are {n_phases} phases "
                         f"(labels 0..{n_phases - 1})")
    if np.any(labels[~mask] != -1):
        raise ValueError("pixels off the face must carry the label -1")
    if n_phases > face_labels.size:
        # Counting would allocate one entry per label: refuse before.
        raise ValueError(f"{n_phases} phases (labels 0..{n_phases - 1}) cannot all have a pixel "
                         f"on a face of {face_labels.size} pixels")
    counts = np.bincount(face_labels, minlength=n_phases)
    empty = np.flatnonzero(counts == 0)
    if empty.size:
        shown = (f"pixel counts per phase: {counts.tolist()}" if n_phases <= 16
                 else f"{empty.size} of the {n_phases} phases have none")
        raise ValueError(f"phase {int(empty[0])} has no pixel on the face ({shown})")
    return counts


def realised_fill_factors(labels, n_phases):
    """Fraction of the face pixels held by each phase (eq. 13).

    Parameters
    ----------
    labels : ndarray, shape (nx, ny), int
        Phase index on the face, ``-1`` off the face.
    n_phases : int

    Returns
    -------
    ndarray, shape (P,)
        Pixel-count fractions; they sum to 1.

    Raises
    ------
    ValueError
        As :func:`validate_labels`.
    """
    counts = validate_labels(labels, n_phases)
    return counts / counts.sum()


def extend_off_face(values, face_mask):
    """Copy of a face field with every pixel off the face set to its nearest face pixel.

    Parameters
    ----------
    values : ndarray, shape (nx, ny)
        Field on the pixel grid; values off the face are not used.
    face_mask : ndarray of bool, shape (nx, ny)
        The face's pixels.

    Returns
    -------
    ndarray, shape (nx, ny)
        Same dtype; equal to ``values`` on the face.
    """
    values = np.asarray(values)
    _, (ii, jj) = ndimage.distance_transform_edt(~np.asarray(face_mask), return_indices=True)
    return values[ii, jj]


def check_fill_factors(fill_factors):
    """Fill factors as a tuple of floats: at least two, each in (0, 1), summing to 1.

    Raises
    ------
    ValueError
        Naming the fill factors.
    """
    try:
        values = tuple(float(v) for v in fill_factors)
    except (TypeError, ValueError):
        raise ValueError(f"fill factors must be a sequence of numbers, got "
                         f"{fill_factors!r}") from None
    if len(values) < 2:
        raise ValueError(f"fill factors need at least two phases, got {list(values)}")
    bad = [v for v in values if not (np.isfinite(v) and 0.0 < v < 1.0)]
    if bad:
        raise ValueError(f"fill factors must each lie in (0, 1), got {list(values)}")
    if abs(math.fsum(values) - 1.0) > _FILL_SUM_TOL:
        raise ValueError(f"fill factors must sum to 1, got {list(values)} "
                         f"(sum {math.fsum(values)!r})")
    return values


def apportion(fractions, total):
    """Integers proportional to ``fractions`` summing to ``total``.

    Largest-remainder rounding: each count is ``floor`` or ``ceil`` of
    ``fraction * total``, which is as close to the fill factors as whole
    seeds allow.
    """
    exact = np.asarray(fractions) * total
    counts = np.floor(exact).astype(int)
    remainder = total - counts.sum()
    # Stable sort: ties go to the lower phase index, reproducibly.
    order = np.argsort(-(exact - counts), kind="stable")
    counts[order[:remainder]] += 1
    return counts
