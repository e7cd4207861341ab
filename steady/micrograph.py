"""Micrographs as phase maps: segmentation of a grey-level image and its placement on the face.

A micrograph has hundreds of grey levels and noise, so it cannot be read
like a pixel-exact phase map (one phase per grey level, see
:func:`steady.phases.load_phase_map`).  Here it becomes a phase map in two
steps:

1. :func:`segment` splits the grey levels into a requested number of
   phases: an optional crop (to leave out a data bar or a scale bar),
   optional Gaussian smoothing, thresholds -- multi-level Otsu
   (:func:`skimage.filters.threshold_multiotsu`; Liao, Chen & Chung,
   J. Inf. Sci. Eng. 17, 2001) or given grey levels --, optional hole
   filling (a particle seen as a bright rim around a dark core becomes a
   filled particle) and removal of specks, connected patches smaller than
   a given number of pixels, which take the phase that surrounds them.
   Phase 0 is the darkest.  The thresholds, the holes filled and the
   realised fill factors are reported in a :class:`Segmentation`.
2. :class:`Micrograph` places the segmented image on the face with its
   own pixel size in metres: centred (or shifted by an offset) and either
   cropped to the face's bounding square, which it must then cover, or
   tiled periodically.  Each grid pixel takes the phase of the image pixel
   under its centre (nearest neighbour: phases are labels, not values), so
   the geometry can be rasterised at any grid size.

The image is placed as it is viewed: its columns run along ``x`` (to the
right), its rows along ``-y`` (the top row lies at the largest ``y``), so
the phase map drawn by :mod:`steady.plotting` looks like the micrograph.
:func:`steady.plotting.segmentation_figure` draws the segmentation over
the image, with the face and the grey-level histogram, to check a phase
map before trusting a result.

Otsu thresholds need scikit-image, an optional extra:
``pip install 'runin[micrograph]'``; given thresholds do not.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import pathlib

import numpy as np
from scipy import ndimage

from .array_files import input_file_size, npy_header, read_png
from .outline import MIN_SIDE_PIXELS, FaceGrid, as_outline
from .phases import PHASE_MAPS, PhaseMap, check_resolution
from .schema import Key
from .text import shorten

__all__ = [
    "COVERS",
    "MAX_PIXELS",
    "OTSU_MAX_SETS",
    "Micrograph",
    "Segmentation",
    "load_micrograph",
    "read_grey",
    "segment",
]

logger = logging.getLogger(__name__)

#: Ways to fill the face from a micrograph of another size: ``"crop"`` (the
#: image must cover the face's bounding square) or ``"tile"`` (periodic copies).
COVERS = ("crop", "tile")

#: Largest micrograph read, pixels (4096 x 4096); checked before its data
#: are read.  Speck removal holds a few integer arrays of this size.
MAX_PIXELS = 4096 * 4096

#: Histogram bins of the Otsu thresholds: a threshold is known to within one
#: bin, ``(max - min) / 256`` of the grey range.
_OTSU_BINS = 256

#: Most sets of thresholds a multi-level Otsu may search.  It tries every set
#: of ``P - 1`` of the histogram's bins, ``C(256, P - 1)``: 1.7e8 for 5 phases,
#: 8.8e9 for 6, at a time per set measured in docs/benchmarks.md ("Micrograph
#: segmentation").  Beyond it the thresholds must be given.
OTSU_MAX_SETS = 2e8

#: Luminance weights of ITU-R BT.709, for colour images (as scikit-image's rgb2gray).
_LUMINANCE = (0.2125, 0.7154, 0.0721)

#: Relative slack on the cover test, so that an image exactly as wide as the
#: face passes despite rounding.
_COVER_SLACK = 1e-9


def _threshold_multiotsu():
    """:func:`skimage.filters.threshold_multiotsu`, or ``ValueError`` naming the extra."""
    try:
        from skimage.filters import threshold_multiotsu  # optional dependency
    except ImportError:
        raise ValueError("segmenting a micrograph needs scikit-image: install the optional "
                         "extra with pip install 'runin[micrograph]'") from None
    return threshold_multiotsu


def _is_integer(value):
    return not isinstance(value, bool) and isinstance(value, (int, np.integer))


def _is_number(value):
    return not isinstance(value, bool) and isinstance(value, (int, float, np.integer,
                                                              np.floating))


# Keys of a scene's micrograph map, also the checks of the same arguments given in Python.
_N_PHASES = Key("n_phases", "integer", low=2, low_open=False, required=True,
                doc="phases, by multi-level Otsu thresholds (phase 0 darkest)")
_SMOOTHING = Key("smoothing", "number", unit="pixels", low=0.0, low_open=False,
                 doc="Gaussian sigma before thresholding (default 0)")
_MIN_SPECK = Key("min_speck", "integer", unit="pixels", low=0, low_open=False,
                 doc="patches below this are relabelled to the surrounding phase (default 0)")
_PIXEL_SIZE = Key("pixel_size", "number", unit="m", low=0.0,
                  doc="side of an image pixel (default: a square image spans the face's box)")


def _check_thresholds(thresholds, n_phases):
    """Given thresholds as a tuple of floats (None: Otsu); count and order checked.

    Without thresholds, Otsu's search must be one that finishes: every set of
    ``n_phases - 1`` of the histogram's bins, at most :data:`OTSU_MAX_SETS`.
    """
    if thresholds is None:
        sets = math.comb(_OTSU_BINS, n_phases - 1)
        if sets > OTSU_MAX_SETS:
            most = max(p for p in range(2, n_phases)
                       if math.comb(_OTSU_BINS, p - 1) <= OTSU_MAX_SETS)
            raise ValueError(f"n_phases = {n_phases} by Otsu's thresholds would search "
                             f"C({_OTSU_BINS}, {n_phases - 1}) = {sets:.2g} sets of thresholds "
                             f"in the {_OTSU_BINS}-bin grey-level histogram, more than the "
                             f"{OTSU_MAX_SETS:.0e} it may (at most {most} phases): give "
                             f"thresholds = [...], {n_phases - 1} increasing grey levels (PNG: "
                             f"0 black to 1 white)")
        return None
    shown = shorten(list(thresholds) if isinstance(thresholds, (tuple, np.ndarray))
                    else thresholds)
    try:
        if isinstance(thresholds, (str, bytes)):
            raise TypeError
        values = tuple(thresholds)
        if not all(_is_number(v) and math.isfinite(v) for v in values):
            raise TypeError
    except TypeError:
        raise ValueError(f"thresholds = {shown} must be a list of finite grey levels") from None
    if len(values) != n_phases - 1:
        raise ValueError(f"thresholds = {shown} must hold n_phases - 1 = {n_phases - 1} grey "
                         f"level{'s' if n_phases > 2 else ''}, got {len(values)}")
    if any(b <= a for a, b in zip(values[:-1], values[1:], strict=True)):
        raise ValueError(f"thresholds = {shown} must increase (phase 0 is the darkest)")
    return tuple(float(v) for v in values)


def _check_crop(crop):
    """``crop`` as ``((row0, row1), (col0, col1))`` of ints (None: no crop); order checked."""
    if crop is None:
        return None
    shown = shorten([list(pair) if isinstance(pair, tuple) else pair for pair in crop]
                    if isinstance(crop, (tuple, list)) else crop)
    bad = (f"crop = {shown} must be [[row0, row1], [col0, col1]], whole pixel indices with "
           f"0 <= row0 < row1 and 0 <= col0 < col1")
    try:
        if isinstance(crop, (str, bytes)) or len(crop) != 2:
            raise TypeError
        pairs = tuple(tuple(pair) for pair in crop)
        if any(len(pair) != 2 for pair in pairs):
            raise TypeError
        if not all(_is_number(v) and math.isfinite(v) and v == int(v) and v >= 0
                   for pair in pairs for v in pair):
            raise TypeError
    except TypeError:
        raise ValueError(bad) from None
    (r0, r1), (c0, c1) = ((int(a), int(b)) for a, b in pairs)
    if r1 - r0 < 2 or c1 - c0 < 2:
        raise ValueError(f"{bad}, at least 2 pixels each way")
    return (r0, r1), (c0, c1)


def _crop_window(crop, shape):
    """The slices of a checked ``crop`` in an image of ``shape``; ``ValueError`` if outside it."""
    if crop is None:
        return slice(None), slice(None)
    (r0, r1), (c0, c1) = crop
    rows, cols = shape
    if r1 > rows or c1 > cols:
        raise ValueError(f"crop = [[{r0}, {r1}], [{c0}, {c1}]] reaches beyond the image of "
                         f"{rows} rows x {cols} columns (row1 <= {rows}, col1 <= {cols})")
    return slice(r0, r1), slice(c0, c1)


def _check_fill(fill_holes, fill_phases, n_phases):
    """The phases whose holes are filled, a sorted tuple (empty: none)."""
    if not isinstance(fill_holes, (bool, np.bool_)):
        raise ValueError(f"fill_holes must be true or false, got {shorten(fill_holes)}")
    if fill_phases is None:
        return tuple(range(1, n_phases)) if fill_holes else ()
    shown = shorten(list(fill_phases) if isinstance(fill_phases, tuple) else fill_phases)
    if not fill_holes:
        raise ValueError(f"fill_phases = {shown} needs fill_holes = true")
    try:
        phases = tuple(fill_phases)
    except TypeError:
        phases = (None,)
    if (not phases or not all(_is_integer(p) and 1 <= p < n_phases for p in phases)
            or len(set(phases)) != len(phases)):
        raise ValueError(f"fill_phases = {shown} must list distinct phases 1 to {n_phases - 1} "
                         f"(phase 0, the darkest, has no darker phase to enclose)")
    return tuple(sorted(int(p) for p in phases))


def _mm(value):
    """A length in m, written in mm."""
    return f"{value * 1e3:.6g} mm"


@dataclasses.dataclass(frozen=True, eq=False)
class Segmentation:
    """A grey-level image split into phases, with what the split found.

    Attributes
    ----------
    labels : ndarray, shape (rows, cols), int
        Phase index of every pixel of the (cropped) image, ``0..P-1`` by
        increasing grey level (read-only).
    thresholds : tuple of float, shape (P-1,)
        Increasing grey levels between the phases, in the units of the
        image (a PNG is read as a fraction of full scale, 0 black to 1
        white); a pixel at or above ``thresholds[i]`` belongs to phase
        ``i + 1`` or above (before holes are filled).
    fill_factors : tuple of float, shape (P,)
        Fraction of the (cropped) image's pixels in each phase after hole
        filling and speck removal; they sum to 1.  (The fill factors on
        the face depend on the placement and the grid:
        :meth:`Micrograph.face_fill_factors`.)
    smoothing : float, pixels
        Standard deviation of the Gaussian smoothing (0: none).
    min_speck : int, pixels
        Connected patches smaller than this were relabelled (0 or 1: none).
    specks : int
        Number of patches relabelled.
    speck_pixels : int
        Number of pixels relabelled.
    method : {"otsu", "manual"}
        Where the thresholds come from: multi-level Otsu, or given (manual).
    fill_phases : tuple of int
        Phases whose holes were filled (empty: none).
    holes : int
        Number of holes filled.
    hole_pixels : int
        Number of pixels that changed phase by hole filling.
    crop : ((int, int), (int, int)) or None
        ``((row0, row1), (col0, col1))``: the rows ``row0 <= r < row1`` (0
        the top row) and columns ``col0 <= c < col1`` (0 the left column)
        of the image that were kept; None: the whole image.
    image : ndarray, shape (rows, cols), float, or None
        The grey levels of the (cropped) image before smoothing
        (read-only), for :func:`steady.plotting.segmentation_figure`; None
        if not kept.
    """

    labels: np.ndarray
    thresholds: tuple
    fill_factors: tuple
    smoothing: float
    min_speck: int
    specks: int
    speck_pixels: int
    method: str = "otsu"
    fill_phases: tuple = ()
    holes: int = 0
    hole_pixels: int = 0
    crop: tuple | None = None
    image: np.ndarray | None = None

    @property
    def n_phases(self):
        """Number of phases ``P``."""
        return len(self.fill_factors)

    @property
    def shape(self):
        """``(rows, cols)`` of the (cropped) image."""
        return self.labels.shape

    def summary(self):
        """One line: phases, thresholds, crop, holes, fill factors and specks."""
        thresholds = ", ".join(f"{t:.4g}" for t in self.thresholds)
        fill = ", ".join(f"{f:.4f}" for f in self.fill_factors)
        words = [f"{self.n_phases} phases, thresholds {thresholds} ({self.method})"]
        if self.crop is not None:
            (r0, r1), (c0, c1) = self.crop
            words.append(f"crop rows {r0}:{r1}, columns {c0}:{c1}")
        if self.fill_phases:
            phases = ", ".join(str(p) for p in self.fill_phases)
            words.append(f"{self.holes} holes ({self.hole_pixels} pixels) filled in phase"
                         f"{'s' if len(self.fill_phases) > 1 else ''} {phases}")
        words.append(f"image fill factors {fill}")
        words.append(f"{self.specks} specks ({self.speck_pixels} pixels) relabelled")
        return ", ".join(words)

    def histogram(self):
        """Histogram of the grey levels that were thresholded (after the smoothing).

        Returns
        -------
        counts : ndarray, shape (256,), int
            Pixels in each bin: the bins of the Otsu thresholds, a 256th of
            the grey range each.
        edges : ndarray, shape (257,), units of the image

        Raises
        ------
        ValueError
            The segmentation keeps no image.
        """
        if self.image is None:
            raise ValueError("the segmentation keeps no image (made by segment() or "
                             "load_micrograph(), it does)")
        grey = self.image
        if self.smoothing:
            grey = ndimage.gaussian_filter(grey, self.smoothing, mode="nearest")
        return np.histogram(grey, bins=_OTSU_BINS)


def _remove_specks(labels, n_phases, min_speck):
    """Labels with every patch under ``min_speck`` pixels given the surrounding phase.

    Patches are 4-connected (pixels sharing a side).  A removed pixel takes
    the phase of the nearest kept pixel (Euclidean distance transform), so a
    speck inside a grain takes the grain's phase and one on a boundary is
    shared among its neighbours.
    """
    keep = np.ones(labels.shape, dtype=bool)
    specks = 0
    for phase in range(n_phases):
        patches, _ = ndimage.label(labels == phase)
        sizes = np.bincount(patches.ravel())
        small = sizes < min_speck
        small[0] = False  # background of this phase's labelling
        specks += int(np.count_nonzero(small))
        keep &= ~small[patches]
    removed = int(labels.size - np.count_nonzero(keep))
    if removed == 0:
        return labels, 0, 0
    if not keep.any():
        raise ValueError(f"min_speck = {min_speck} removes every patch of the image: no phase "
                         f"has a connected patch of {min_speck} pixels")
    _, (ii, jj) = ndimage.distance_transform_edt(~keep, return_indices=True)
    return labels[ii, jj], specks, removed


def _fill_holes(labels, phases):
    """Labels with the holes of each phase in ``phases`` that hold only darker phases filled.

    A hole of phase ``j`` is a patch of other pixels that phase ``j`` encloses
    (not connected to the image's edge through pixels sharing a side:
    :func:`scipy.ndimage.binary_fill_holes`).  It takes phase ``j`` if all
    its pixels are of phases below ``j``; one holding a brighter phase (a
    bright particle inside a darker matrix) is left alone.  Phases are
    treated from the brightest down.  Returns ``(labels, holes, pixels)``.
    """
    labels = labels.copy()
    holes = pixels = 0
    for phase in sorted(phases, reverse=True):
        inside = labels == phase
        enclosed = ndimage.binary_fill_holes(inside) & ~inside
        patches, count = ndimage.label(enclosed)
        if count == 0:
            continue
        brightest = ndimage.maximum(labels, patches, index=np.arange(1, count + 1))
        darker = np.concatenate([[False], np.asarray(brightest) < phase])
        fill = darker[patches]
        labels[fill] = phase
        holes += int(np.count_nonzero(darker))
        pixels += int(np.count_nonzero(fill))
    return labels, holes, pixels


def _check_image(image):
    """A 2-d finite image of numbers as float64; ``ValueError`` saying what is wrong."""
    image = np.asarray(image)
    if image.ndim != 2:
        raise ValueError(f"a micrograph must be a 2-d grey-level image, got shape {image.shape}")
    if not (np.issubdtype(image.dtype, np.integer) or np.issubdtype(image.dtype, np.floating)
            or np.issubdtype(image.dtype, np.bool_)):
        raise ValueError(f"a micrograph must hold numbers, got dtype {image.dtype}")
    image = image.astype(np.float64)
    if not np.all(np.isfinite(image)):
        raise ValueError(f"the micrograph has {np.count_nonzero(~np.isfinite(image))} "
                         f"non-finite pixels (NaN or inf)")
    if min(image.shape) < 2:
        raise ValueError(f"a micrograph needs at least 2 x 2 pixels, got {image.shape}")
    return image


def _thresholds(grey, n_phases, given, cropped):
    """Otsu's thresholds of ``grey``, or the ``given`` ones checked against its grey range."""
    if given is None:
        threshold_multiotsu = _threshold_multiotsu()
        try:
            return np.asarray(threshold_multiotsu(grey, classes=n_phases, nbins=_OTSU_BINS),
                              dtype=np.float64)
        except ValueError as err:
            raise ValueError(f"cannot split the micrograph into {n_phases} phases: "
                             f"{str(err)[:200]}") from None
    low, high = float(grey.min()), float(grey.max())
    outside = [t for t in given if not low < t <= high]
    if outside:
        where = "the cropped image" if cropped else "the image"
        raise ValueError(f"thresholds = {shorten(list(given))}: {outside[0]:.6g} lies outside "
                         f"the grey range ({low:.6g}, {high:.6g}] of {where} (the same units: "
                         f"a PNG reads 0 black to 1 white), so a phase would be empty")
    return np.asarray(given, dtype=np.float64)


def segment(image, n_phases, *, smoothing=0.0, min_speck=0, thresholds=None, fill_holes=False,
            fill_phases=None, crop=None):
    """Split a grey-level image into phases by thresholds: Otsu's or given ones.

    Parameters
    ----------
    image : ndarray, shape (rows, cols), float
        Grey levels (any units; brighter is larger).
    n_phases : int
        Number of phases ``P >= 2``.
    smoothing : float, optional
        Standard deviation of a Gaussian smoothing applied first, in
        pixels (default 0: none).  Noise of a few grey levels scatters
        pixels across the thresholds; a sigma of about one pixel removes
        most of that speckle at the cost of rounding grain corners.
    min_speck : int, optional
        Last, connected patches (sharing a side) of fewer than
        ``min_speck`` pixels take the phase of the pixels around them
        (default 0: none).
    thresholds : sequence of float, shape (P-1,), optional
        Increasing grey levels between the phases, in the units of the
        image, each inside its grey range ``(min, max]`` (after the crop
        and the smoothing).  Default: multi-level Otsu thresholds (Notes).
    fill_holes : bool, optional
        Fill holes (default False): a patch of darker phases enclosed by
        phase ``j``, such as the dark core of a particle seen as a bright
        rim, takes phase ``j``.  See Notes.
    fill_phases : sequence of int, optional
        The phases ``j`` whose holes are filled, among ``1..P-1`` (needs
        ``fill_holes``; default: all of them).
    crop : ((int, int), (int, int)), optional
        ``((row0, row1), (col0, col1))``: keep only the rows
        ``row0 <= r < row1`` (row 0 at the top, as viewed) and the columns
        ``col0 <= c < col1`` (column 0 at the left), e.g. to leave out a
        data bar.  Applied first: everything else, the thresholds
        included, sees the cropped image only.

    Returns
    -------
    Segmentation
        Of the cropped image; phase 0 is the darkest.

    Raises
    ------
    ValueError
        scikit-image is not installed for Otsu thresholds (the message
        names the extra), the image is not a finite 2-d array, it has
        fewer distinct grey levels than phases, a parameter is out of
        range (the message names it and its value; beyond 5 phases Otsu's,
        asking for thresholds), or a phase ends up with no pixel.

    Notes
    -----
    Steps: crop, smoothing, thresholds, holes, specks.  Otsu's thresholds
    maximise the between-class variance of the grey-level histogram (256
    bins between the smallest and the largest value, so a threshold is
    resolved to one bin, 1/256 of the grey range); their search of
    ``C(256, P - 1)`` sets is refused beyond :data:`OTSU_MAX_SETS` (more
    than 5 phases).  Pixels are classed by :func:`numpy.digitize`: a pixel
    equal to a threshold goes to the brighter phase.  Holes are filled
    from the brightest phase down: a hole of phase ``j`` (a patch not
    connected to the image's edge through pixels sharing a side) takes
    phase ``j`` if it holds only phases below ``j``; one holding a
    brighter phase stays.  With two phases, every dark patch enclosed by
    phase 1 becomes phase 1; a particle cut by the image's edge keeps its
    open core.

    Examples
    --------
    >>> import numpy as np
    >>> image = np.zeros((40, 40))
    >>> image[:, 10:] = 1.0             # three quarters bright
    >>> image[5, 5] = 1.0               # a one-pixel speck in the dark part
    >>> seg = segment(image, 2, min_speck=4)
    >>> seg.fill_factors, seg.specks
    ((0.25, 0.75), 1)
    >>> ring = np.full((20, 20), 0.5)   # a bright ring with a dark core on grey
    >>> ring[5:15, 5:15], ring[8:12, 8:12] = 1.0, 0.0
    >>> segment(ring, 2, thresholds=[0.75], fill_holes=True).fill_factors
    (0.75, 0.25)
    """
    n_phases = _N_PHASES.parse(n_phases, "")
    smoothing = _SMOOTHING.parse(smoothing, "")
    min_speck = _MIN_SPECK.parse(min_speck, "")
    given = _check_thresholds(thresholds, n_phases)
    fill_phases = _check_fill(fill_holes, fill_phases, n_phases)
    crop = _check_crop(crop)
    if given is None:
        _threshold_multiotsu()  # name the missing extra first
    image = _check_image(image)[_crop_window(crop, np.shape(image))]
    if smoothing >= min(image.shape):
        raise ValueError(f"smoothing = {smoothing:g} pixels is not smaller than the image "
                         f"({image.shape[0]} x {image.shape[1]} pixels)")
    if min_speck > image.size:
        raise ValueError(f"min_speck = {min_speck} pixels exceeds the image's {image.size} "
                         f"pixels")
    grey = ndimage.gaussian_filter(image, smoothing, mode="nearest") if smoothing else image
    levels = np.unique(grey)
    if len(levels) < n_phases:
        raise ValueError(f"the micrograph has {len(levels)} distinct grey levels, fewer than "
                         f"the {n_phases} phases asked for")
    cuts = _thresholds(grey, n_phases, given, crop is not None)
    labels = np.digitize(grey, cuts).astype(np.int64)
    labels, holes, hole_pixels = _fill_holes(labels, fill_phases)
    labels, specks, speck_pixels = _remove_specks(labels, n_phases, min_speck)
    counts = np.bincount(labels.ravel(), minlength=n_phases)
    empty = np.flatnonzero(counts == 0)
    if empty.size:
        raise ValueError(f"phase {int(empty[0])} has no pixel after segmentation into "
                         f"{n_phases} phases (thresholds {cuts.tolist()}, pixel counts "
                         f"{counts.tolist()}); ask for fewer phases or a smaller min_speck")
    labels, image = np.ascontiguousarray(labels), np.array(image)
    labels.flags.writeable = image.flags.writeable = False
    return Segmentation(labels=labels, thresholds=tuple(float(t) for t in cuts),
                        fill_factors=tuple(float(c) for c in counts / labels.size),
                        smoothing=smoothing, min_speck=min_speck, specks=specks,
                        speck_pixels=speck_pixels,
                        method="otsu" if given is None else "manual", fill_phases=fill_phases,
                        holes=holes, hole_pixels=hole_pixels, crop=crop, image=image)


def read_grey(path):
    """Read a micrograph as grey levels.

    Parameters
    ----------
    path : str or path-like
        ``.png`` (grey, grey with alpha, RGB or RGBA, 8 or 16 bits): read
        as a fraction of full scale, 0 black to 1 white; colours become
        their luminance (ITU-R BT.709 weights), alpha is ignored.
        ``.npy``: a 2-d array of numbers, used as they are.

    Returns
    -------
    ndarray, shape (rows, cols), float64

    Raises
    ------
    ValueError
        Missing, empty or unreadable file, an unsupported suffix, more than
        :data:`MAX_PIXELS` pixels (refused before the data are read), not
        2-d, not numbers.
    """
    path = pathlib.Path(path)
    what = "micrograph"
    suffix = path.suffix.lower()
    input_file_size(path, what)
    if suffix == ".npy":
        shape, dtype = npy_header(path, what=what)
        if len(shape) != 2:
            raise ValueError(f"{what} {str(path)!r} must be a 2-d array, got shape {shape}")
        if math.prod(shape) > MAX_PIXELS:
            raise ValueError(f"{what} {str(path)!r} has {shape[0]} x {shape[1]} pixels, more "
                             f"than the {MAX_PIXELS} read")
        if not (np.issubdtype(dtype, np.integer) or np.issubdtype(dtype, np.floating)
                or np.issubdtype(dtype, np.bool_)):
            raise ValueError(f"{what} {str(path)!r} must hold real numbers, got dtype {dtype}")
        try:
            return np.load(path, allow_pickle=False).astype(np.float64)
        except (OSError, ValueError, EOFError) as err:
            raise ValueError(f"cannot read {what} {str(path)!r}: {str(err)[:200]}") from None
    if suffix != ".png":
        raise ValueError(f"{what} {str(path)!r} must be a .png or .npy file")

    def check_size(size):
        if size[0] * size[1] > MAX_PIXELS:
            raise ValueError(f"{what} {str(path)!r} has {size[0]} x {size[1]} pixels, more "
                             f"than the {MAX_PIXELS} read")

    img = np.asarray(read_png(path, what, check_size), dtype=np.float64)
    if img.ndim == 3:
        if img.shape[2] >= 3:
            img = img[..., :3] @ np.asarray(_LUMINANCE)
        else:  # grey and alpha
            img = img[..., 0]
    return img


def _placement(shape, outline, pixel_size, cover, offset, source):
    """Checked ``(pixel_size, cover, offset)`` of an image of ``shape`` on a face."""
    rows, cols = shape
    outline = as_outline(outline)
    half_x, half_y = outline.half_extent
    if cover not in COVERS:
        raise ValueError(f"cover must be one of {list(COVERS)}, got {shorten(cover)}")
    try:
        if isinstance(offset, (str, bytes)) or len(offset) != 2:
            raise TypeError
        offset = tuple(offset)
        if not all(_is_number(v) and math.isfinite(v) for v in offset):
            raise TypeError
    except TypeError:
        raise ValueError(f"offset must be a pair [x, y] of finite numbers (m), got "
                         f"{shorten(offset)}") from None
    offset = (float(offset[0]), float(offset[1]))
    if pixel_size is None:
        if rows != cols or half_x != half_y:
            raise ValueError(f"micrograph {source!r} is {cols} x {rows} pixels: without a "
                             f"pixel_size it must be square and so must the face's bounding "
                             f"box (the image then spans it)")
        pixel_size = 2.0 * half_x / cols
    else:  # its scale range is a problem's to check
        pixel_size = _PIXEL_SIZE.parse(pixel_size, "", scale=False)
    if cover == "crop":
        width, height = cols * pixel_size, rows * pixel_size
        slack = 1.0 + _COVER_SLACK
        if (abs(offset[0]) + half_x > 0.5 * width * slack
                or abs(offset[1]) + half_y > 0.5 * height * slack):
            box = "(the face's bounding box)"
            raise ValueError(
                f"micrograph {source!r} covers {_mm(width)} x {_mm(height)} ({cols} x {rows} "
                f"pixels of {pixel_size:.6g} m) but the face needs {_mm(2 * half_x)} x "
                f"{_mm(2 * half_y)} {box} around offset ({_mm(offset[0])}, "
                f"{_mm(offset[1])}): use cover = \"tile\", a larger image or a smaller offset")
    return pixel_size, cover, offset


@PHASE_MAPS.register("micrograph", (
    Key("path", "path", required=True, doc="grey-level image, .png or .npy"),
    _N_PHASES,
    Key("thresholds", "numbers", unit="grey level",
        doc="n_phases - 1 increasing grey levels instead of Otsu's (PNG: 0 black to 1 white)"),
    Key("crop", "pairs", unit="pixels", low=0.0, low_open=False,
        doc="[[row0, row1], [col0, col1]]: the part of the image used (row 0 at the top)"),
    _SMOOTHING,
    Key("fill_holes", "boolean",
        doc="darker patches enclosed by a phase take that phase (default false)"),
    Key("fill_phases", "integers", low=1, low_open=False,
        doc="the phases whose holes are filled (default: all but phase 0)"),
    _MIN_SPECK,
    _PIXEL_SIZE,
    Key("cover", "string", choices=COVERS, doc="crop (default) or tile"),
    Key("offset", "pair", unit="m", doc="face centre relative to the image centre")),
    doc="a grey-level micrograph segmented into phases and placed on the face")
@dataclasses.dataclass(frozen=True, eq=False)
class Micrograph(PhaseMap):
    """A segmented micrograph placed on the face: a phase geometry.

    Parameters
    ----------
    segmentation : Segmentation
        The image's phases (see :func:`segment`).
    outline : outline object or float
        The face (:mod:`steady.outline`); a number is the radius ``a`` of a
        circular face, m.
    pixel_size : float, m, optional
        Side of one image pixel.  Default: the image and the face's
        bounding box must be square, and the image spans it (for a disk
        the diameter: ``2a / cols``).
    cover : {"crop", "tile"}, optional
        ``"crop"`` (default): the image, centred on the face (shifted by
        ``offset``), must cover the face's bounding box (``[-a, a]^2`` for
        a disk); ``"tile"``: the image is repeated periodically, so any
        pixel size covers the face.
    offset : (float, float), m, optional
        Position ``(x, y)`` of the face centre relative to the image
        centre, ``x`` to the right, ``y`` up (default ``(0, 0)``).
    source : str, optional
        Where the image came from, e.g. its path (for messages and records).

    Raises
    ------
    ValueError
        A bad ``pixel_size``, ``cover`` or ``offset``, a non-square image
        without ``pixel_size``, or a crop that does not cover the face (the
        message gives both sizes).

    Notes
    -----
    The grid pixel at ``(x, y)`` takes the phase of image pixel
    ``(row, col) = (floor((H/2 - y - y0) / p), floor((x + x0 + W/2) / p))``
    (taken modulo the image size when tiling), ``p`` the pixel size,
    ``W x H`` the image's size and ``(x0, y0)`` the offset.  When
    ``pixel_size = 2a / n0`` and ``n = k n0``, each image pixel becomes
    exactly ``k x k`` grid pixels.  A grid coarser than the image keeps
    one image pixel in every few: features smaller than the grid pixel
    (``2a / n`` on a disk) are lost or kept at random, like any
    nearest-neighbour resampling.

    Examples
    --------
    >>> import numpy as np
    >>> labels = np.zeros((4, 6), dtype=int)
    >>> labels[:, 3:] = 1                    # right half of the image is phase 1
    >>> seg = Segmentation(labels, (0.5,), (0.5, 0.5), 0.0, 0, 0, 0)
    >>> geometry = Micrograph(seg, 1e-3, pixel_size=0.5e-3)   # 3 mm x 2 mm, disk a = 1 mm
    >>> geometry.labels(8)[[0, 7], 4]        # left and right edge of the face, y ~ 0
    array([0, 1])
    """

    segmentation: Segmentation
    outline: object
    pixel_size: float | None = None
    cover: str = "crop"
    offset: tuple = (0.0, 0.0)
    source: str = "image"

    def __post_init__(self):
        """Check the placement; store the resolved pixel size and the offset as floats."""
        if not isinstance(self.segmentation, Segmentation):
            raise ValueError(f"segmentation must be a Segmentation, got "
                             f"{shorten(self.segmentation)}")
        outline = as_outline(self.outline)
        pixel_size, cover, offset = _placement(self.segmentation.shape, outline,
                                               self.pixel_size, self.cover, self.offset,
                                               self.source)
        object.__setattr__(self, "outline", outline)
        object.__setattr__(self, "pixel_size", pixel_size)
        object.__setattr__(self, "offset", offset)

    @property
    def n_phases(self):
        """Number of phases of the segmentation."""
        return self.segmentation.n_phases

    @classmethod
    def from_values(cls, values, context):
        """From the checked ``[phases] map`` keys: :func:`load_micrograph` on the outline."""
        options = {key: value for key, value in values.items() if key != "path"}
        return load_micrograph(values["path"], context.outline, **options)

    @classmethod
    def declared_phases(cls, values):
        """``n_phases``, before the image is read and segmented."""
        return values["n_phases"]

    @property
    def extent(self):
        """``(width, height)`` of the image, m."""
        rows, cols = self.segmentation.shape
        return cols * self.pixel_size, rows * self.pixel_size

    def min_grid(self, outline=None):
        """Smallest accepted grid, :data:`steady.outline.MIN_SIDE_PIXELS`."""
        return MIN_SIDE_PIXELS

    def check_grid(self, grid):
        """``n`` as an int; ``ValueError`` if the grid is too coarse."""
        return check_resolution(grid, self.min_grid(), f"micrograph {self.source!r}")

    def segmented_image(self):
        """The segmentation of the micrograph (:class:`Segmentation`)."""
        return self.segmentation

    def file_record(self):
        """The group ``micrograph`` of a result file: the segmentation and the placement.

        Returns
        -------
        dict
            ``{"micrograph": attributes}``: the source, the thresholds, the
            crop (pixels), the fill and speck counts, the image's fill
            factors and shape, the pixel size (m), the cover and the offset
            (m); docs/files.md lists them.
        """
        seg = self.segmentation
        attributes = {
            "source": self.source,
            "n_phases": seg.n_phases,
            "thresholds": np.asarray(seg.thresholds, dtype=float),
            "image_fill_factors": np.asarray(seg.fill_factors),
            "smoothing": seg.smoothing,
            "min_speck": seg.min_speck,
            "specks": seg.specks,
            "speck_pixels": seg.speck_pixels,
            "threshold_method": seg.method,
            "crop": np.asarray(seg.crop or ((0, seg.shape[0]), (0, seg.shape[1]))),
            "crop_units": "pixels",
            "fill_phases": np.asarray(seg.fill_phases, dtype=np.int64),
            "holes": seg.holes,
            "hole_pixels": seg.hole_pixels,
            "image_shape": np.asarray(seg.shape),
            "pixel_size": self.pixel_size,
            "pixel_size_units": "m",
            "cover": self.cover,
            "offset": np.asarray(self.offset),
            "offset_units": "m",
            # Counts of pixels: dimensionless for udunits (docs/files.md says pixels).
            "smoothing_units": "1",
            "min_speck_units": "1",
        }
        return {"micrograph": attributes}

    def _grid(self, grid):
        """The face grid of ``grid`` (``n``: this micrograph's own outline)."""
        return grid if isinstance(grid, FaceGrid) else FaceGrid(self.outline, int(grid))

    def image_indices(self, grid):
        """Image row and column under each grid pixel centre.

        Parameters
        ----------
        grid : FaceGrid or int
            A grid of the face, or ``n`` (pixels along the longer side of
            this micrograph's face).

        Returns
        -------
        rows : ndarray, shape (ny,), int
            Image row under grid column ``j`` (coordinate ``y_j``).
        cols : ndarray, shape (nx,), int
            Image column under grid row ``i`` (coordinate ``x_i``).
        """
        self.check_grid(grid)
        grid = self._grid(grid)
        n_rows, n_cols = self.segmentation.shape
        width, height = self.extent
        cols = np.floor((grid.x + self.offset[0] + 0.5 * width)
                        / self.pixel_size).astype(np.int64)
        rows = np.floor((0.5 * height - grid.y - self.offset[1])
                        / self.pixel_size).astype(np.int64)
        if self.cover == "tile":
            return rows % n_rows, cols % n_cols
        # A crop covers the face: only rounding at an exact edge can step outside.
        return np.clip(rows, 0, n_rows - 1), np.clip(cols, 0, n_cols - 1)

    def labels(self, grid):
        """Phase of the image pixel under each face pixel centre, -1 off the face."""
        rows, cols = self.image_indices(grid)
        picked = self.segmentation.labels[rows[None, :], cols[:, None]]
        return np.where(self._grid(grid).mask, picked, -1)

    def face_fill_factors(self, grid):
        """Fraction of the face pixels of each phase on a grid, shape (P,).

        Unlike :attr:`Segmentation.fill_factors` (the whole image), these
        are what the model sees.  A phase absent from the face counts 0.
        """
        labels = self.labels(grid)
        counts = np.bincount(labels[labels >= 0], minlength=self.n_phases)
        return counts / counts.sum()


def load_micrograph(path, outline, n_phases, *, thresholds=None, crop=None, smoothing=0.0,
                    fill_holes=False, fill_phases=None, min_speck=0, pixel_size=None,
                    cover="crop", offset=(0.0, 0.0)):
    """Read, segment and place a micrograph: the map kind ``micrograph`` of scene files.

    Parameters
    ----------
    path : str or path-like
        ``.png`` or ``.npy`` image (see :func:`read_grey`).
    outline : outline object or float
        The face (:mod:`steady.outline`); a number is the radius ``a`` of a
        circular face, m.
    n_phases : int
        Number of phases ``P >= 2``.
    thresholds : sequence of float, shape (P-1,), optional
        Increasing grey levels between the phases, in the image's units (a
        PNG: 0 black to 1 white); default: multi-level Otsu.
    crop : ((int, int), (int, int)), optional
        ``((row0, row1), (col0, col1))``, the part of the image kept (row 0
        at the top); the pixel size and the cover refer to it.
    smoothing : float, pixels, optional
        Gaussian sigma before thresholding (default 0).
    fill_holes : bool, optional
        Fill the holes of phases ``fill_phases`` (default False).
    fill_phases : sequence of int, optional
        Default: every phase but 0.  See :func:`segment`.
    min_speck : int, pixels, optional
        Patches smaller than this take the surrounding phase (default 0).
    pixel_size : float, m, optional
        Side of one image pixel (default: a square (cropped) image spanning
        the face's square bounding box, ``2a`` for a disk).
    cover : {"crop", "tile"}, optional
        Default ``"crop"``; see :class:`Micrograph`.
    offset : (float, float), m, optional
        Face centre relative to the centre of the (cropped) image (default
        ``(0, 0)``).

    Returns
    -------
    Micrograph
        Its ``segmentation`` holds the thresholds, the holes filled and the
        image's fill factors, also logged (``INFO``).

    Raises
    ------
    ValueError
        Any error of :func:`read_grey`, :func:`segment` or
        :class:`Micrograph`; the parameters, the crop and the cover are
        checked before the image is segmented.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> import numpy as np
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "grey.npy"
    >>> image = np.zeros((50, 60))
    >>> image[:, 30:] = 1.0                  # dark left half, bright right half
    >>> np.save(path, image)
    >>> geometry = load_micrograph(path, 1e-3, 2, pixel_size=5e-5)  # 3 x 2.5 mm, face 2 mm
    >>> geometry.segmentation.fill_factors, geometry.face_fill_factors(40)
    ((0.5, 0.5), array([0.5, 0.5]))
    """
    path = pathlib.Path(path)
    source = str(path)
    n_phases = _N_PHASES.parse(n_phases, "")
    options = dict(smoothing=_SMOOTHING.parse(smoothing, ""),
                   min_speck=_MIN_SPECK.parse(min_speck, ""),
                   thresholds=_check_thresholds(thresholds, n_phases), crop=_check_crop(crop),
                   fill_holes=fill_holes, fill_phases=fill_phases)
    _check_fill(fill_holes, fill_phases, n_phases)
    if options["thresholds"] is None:
        _threshold_multiotsu()  # name the missing extra before reading anything
    image = read_grey(path)
    try:
        rows, cols = _crop_window(options["crop"], image.shape)
    except ValueError as err:
        raise ValueError(f"micrograph {source!r}: {err}") from None
    _placement(image[rows, cols].shape, outline, pixel_size, cover, offset, source)
    try:
        seg = segment(image, n_phases, **options)
    except ValueError as err:
        raise ValueError(f"micrograph {source!r}: {err}") from None
    logger.info("micrograph %s: %s", path, seg.summary())
    return Micrograph(seg, outline, pixel_size, cover, offset, source)
