"""Files of the wear-ratio fit: measured height maps in, HDF5 results and figures out.

Measured worn faces (:class:`steady.measured_face.MeasuredFace`,
:func:`read_measured`):

- ``.npy``: a 2-d float array of heights;
- ``.txt``, ``.csv``, ``.dat``, ``.asc``: a plain text grid read by
  :func:`numpy.loadtxt`, whitespace or comma separated, ``nan`` for a
  missing pixel;
- any other file: a profilometer file read by the package SurfaceTopography
  (``SurfaceTopography.read_topography``, which detects the format from the
  contents: x3p, gwy, sur, opd, datx, ...), the optional extra ``surface``
  (``pip install 'runin[surface]'``).  Such files carry their pixel size
  and height unit, which are converted to metres.

Arrays are indexed ``[i, j]`` with ``i`` along x, like every field of the
project: row ``i`` of a text grid is the line ``x = x_i``.  Heights of
``.npy`` and text grids are in metres unless ``height_scale`` says how many
metres one file unit is (``1e-6`` for micrometres); their pixel size must be
given.  A height is the face's elevation towards the counter-body (larger =
protruding), as a profilometer sees the worn face turned upwards: the sign
of the steady face ``f_inf = K p``.  NaN marks a missing pixel.

Fit result files (layout ``runin.fit``, version 3), written by
:func:`write_fit` through :func:`steady.safe_files.atomic_h5`, with the CF
attributes ``units`` (udunits) and ``long_name`` on every variable::

    root variables, 0-d unless said
        ratios                 k_i / k_ref, one per phase (1 for the reference)
        ratio_lower, ratio_upper   confidence interval of each ratio (inf: unbounded)
        confidence             level of the intervals (0.95)
        reference_phase        index of the phase the ratios refer to
        phase_pressures        fitted steady pressure of each phase, Pa
        phase_pressure_errors  their standard errors, Pa
        pressure_covariance    (phase_name, other_phase_name) covariance of the phase
                               pressures, Pa2
        offset                 fitted height at the face's centre, m
        tilt                   (component) fitted slopes dz/dx, dz/dy of the plane, 1
        shift                  (component) position of the face's centre in the map
                               (from the map's centre), m
        residual_rms           rms of the residual over the fitted pixels, m
        relief                 max - min of the fitted face without the plane, m
        samples                pixels in the fit
        effective_samples      independent samples (residual correlation), 1
        correlation_length     1/e radius of the residual's correlation, m
        degrees_of_freedom     of the t quantile of the intervals
        load_scale, load_scale_lower, load_scale_upper
                               sum_i A_i p_i / F_N and its interval, 1
        implied_normal_force   load implied by the relief at the scene's E*, N
        implied_E_star         modulus implied by the relief at the scene's load, Pa
        exponent, normal_force, E_star, scale, n, scene_ratios
                               the scene (scale: the outline's length L, m; n: the
                               model grid's pixels along the longer side;
                               scene_ratios: the ratios written in the scene, not
                               used by the fit)
        radius                 m, the disk's radius (circular faces only)
        pixel_size             (component) dx, dy of the measured map, m
        x (nx,), y (ny,)       pixel centres from the map's centre: dimension scales, m
        phase_name (P,)        the phase names, phase 0 first: a dimension scale
        other_phase_name (P,)  the same: the second dimension of a matrix
        component (2,)         "x", "y": the dimension of a vector's components
        measured  (ny, nx)     measured heights, NaN where missing        m
        fitted    (ny, nx)     fitted face with its plane, NaN off the face m
        residual  (ny, nx)     measured - fitted on the fitted pixels, NaN  m
        fit_mask  (ny, nx)     1 for the pixels of the fit                1
        phase     (ny, nx)     phase index at each pixel, -1 off the face 1
        scene     string       the scene TOML (attribute source_path)
    root attributes
        format "runin.fit", format_version 3, Conventions
        success, message       all phase pressures positive; notes
        measured_source        the measured file
    group ``outline``: the face's outline (:func:`steady.output.write_outline`)

docs/files.md lists them.  Version 2 files (the quantities as root
attributes, the unit of ``x`` in ``x_units``, the fields stored ``(nx,
ny)``), version 2 files without the coordinates and phase names and version
1 files (disks only: ``radius``, no ``outline`` or ``scale``) are read too.

:func:`plot_fit` draws the measured, fitted and residual faces side by
side from such a file (matplotlib without pyplot, imported on demand).
"""

from __future__ import annotations

import dataclasses
import logging
import os
import pathlib

import h5py
import numpy as np

from .array_files import (
    PNG_SIGNATURE,
    REAL_NUMBERS,
    input_file_size,
    read_npy,
)
from .measured_face import MeasuredFace, check_pixel_size
from .outline import Circle
from .output import (
    CONVENTIONS,
    describe,
    field_from_file,
    read_outline,
    read_phase_names,
    read_values,
    write_field,
    write_grid_coordinates,
    write_outline,
    write_phase_names,
    write_quantity,
    write_record,
)
from .problem import check_phase_names, default_phase_names
from .safe_files import atomic_h5
from .schema import Key

__all__ = [
    "FIT_FORMAT",
    "FIT_FORMAT_VERSION",
    "StoredFit",
    "TEXT_SUFFIXES",
    "fit_figure",
    "plot_fit",
    "read_fit",
    "read_measured",
    "write_fit",
]

logger = logging.getLogger(__name__)

FIT_FORMAT = "runin.fit"
FIT_FORMAT_VERSION = 3
#: Versions :func:`read_fit` reads (1: disks only, without the ``outline`` group; 1 and 2:
#: the quantities as root attributes, the fields stored (nx, ny)).
_READABLE_VERSIONS = (1, 2, 3)

#: Suffixes read as plain text grids (anything else but ``.npy`` goes to
#: SurfaceTopography).
TEXT_SUFFIXES = (".txt", ".csv", ".dat", ".asc")

#: Metres per height unit of a measured map's file.
_HEIGHT_SCALE = Key("height_scale", "number", unit="m per file unit", low=0.0)

_SURFACE_HINT = ("install the optional extra with pip install 'runin[surface]' "
                 "(SurfaceTopography), or give a .npy or text grid")


#: Leading bytes of file formats a measured map is sometimes mistaken for, and their names.
_SIGNATURES = (
    (b"\x93NUMPY", "a .npy array"),
    (b"\x89HDF\r\n\x1a\n", "an HDF5 file"),
    (PNG_SIGNATURE, "a PNG image"),
    (b"PK\x03\x04", "a zip archive (an .npz, an x3p?)"),
    (b"\x1f\x8b", "a gzip-compressed file"),
    (b"%PDF", "a PDF document"),
    (b"II*\x00", "a TIFF image"),
    (b"MM\x00*", "a TIFF image"),
    (b"\xff\xd8\xff", "a JPEG image"),
    *((bytes([0x80, protocol]), "pickled Python data") for protocol in range(2, 6)),
)

#: Kinds of :data:`_SIGNATURES` that hold no heights in any format: refused before
#: SurfaceTopography, which has no reader for them (an image's grey levels are not heights).
_NOT_HEIGHTS = ("a PNG image", "a JPEG image", "a PDF document")


def _file_kind(path):
    """What a file's first bytes say it is (``"an HDF5 file"``), or None if unknown."""
    try:
        with open(path, "rb") as f:
            head = f.read(16)
    except OSError as err:
        raise ValueError(f"cannot read measured map {str(path)!r}: "
                         f"{err.strerror or err}") from None
    for signature, kind in _SIGNATURES:
        if head.startswith(signature):
            return kind
    return None


def _read_npy(path):
    """A 2-d ``.npy`` array of real numbers, checked from its header before the data."""
    kind = _file_kind(path)
    if kind != "a .npy array":
        # Never handed to numpy's loader, which would take a foreign file for pickled
        # data and advise unpickling it.
        found = f"is {kind}" if kind else "has no NumPy header"
        raise ValueError(f"measured map {str(path)!r} {found}, not a .npy array")
    return read_npy(path, what="measured map", holds=REAL_NUMBERS, square=False)


def _text_grid(path):
    """A text grid, whitespace or comma separated (decided by its first data line)."""
    kind = _file_kind(path)
    if kind is not None:
        raise ValueError(f"measured map {str(path)!r} is {kind}, not a text grid")
    try:
        with open(path, encoding="utf-8") as f:
            lines = f.read().splitlines()
    except UnicodeDecodeError as err:
        raise ValueError(f"measured map {str(path)!r} is not a text grid: byte "
                         f"{err.object[err.start]:#04x} at offset {err.start} is not UTF-8 "
                         f"text") from None
    except OSError as err:
        raise ValueError(f"cannot read measured map {str(path)!r}: "
                         f"{err.strerror or err}") from None
    data = [line for line in lines if line.strip() and not line.lstrip().startswith("#")]
    if not data:
        raise ValueError(f"measured map {str(path)!r} holds no numbers (only blank lines or "
                         f"# comments)")
    if any("\x00" in line for line in data[:100]):
        raise ValueError(f"measured map {str(path)!r} is not a text grid: it holds NUL bytes")
    delimiter = "," if "," in data[0] else None
    try:
        # All the lines, so that numpy's row numbers are the file's.
        return np.loadtxt(lines, delimiter=delimiter, ndmin=2, dtype=float, comments="#")
    except ValueError as err:
        # numpy's advice (``usecols``) is for its callers, not for the user.
        reason = str(err).split("; use `usecols`", 1)[0]
        raise ValueError(f"cannot read measured map {str(path)!r} as a text grid: "
                         f"{reason[:200]}") from None


def _surface_topography(path, pixel_size):
    """Heights (m, NaN where undefined) and pixel size (m) through SurfaceTopography."""
    try:
        from SurfaceTopography import open_topography
    except ImportError:
        raise ValueError(f"cannot read {str(path)!r}: a profilometer file needs "
                         f"SurfaceTopography; {_SURFACE_HINT}") from None
    try:
        reader = open_topography(str(path))
        channel = reader.default_channel
        kwargs = {}
        if channel.physical_sizes is None:
            if pixel_size is None:
                raise ValueError(f"{str(path)!r} does not give its pixel size: give it "
                                 f"(--pixel-size, m)")
            dx, dy = check_pixel_size(pixel_size)
            nx, ny = channel.nb_grid_pts
            kwargs["physical_sizes"] = (nx * dx, ny * dy)
        if channel.unit is None:
            kwargs["unit"] = "m"
        topography = reader.topography(**kwargs).to_unit("m")
    except ValueError as err:
        if "pickle" in str(err):
            raise ValueError(f"SurfaceTopography cannot read {str(path)!r}: not a format it "
                             f"knows") from None
        raise
    except Exception as err:  # the readers raise many kinds for a file they cannot parse
        # A reader's advice to unpickle a file is never passed on.
        reason = "not a format it knows" if "pickle" in str(err) else \
            f"{type(err).__name__}: {str(err)[:200]}"
        raise ValueError(f"SurfaceTopography cannot read {str(path)!r}: {reason}") from None
    if topography.dim != 2:
        raise ValueError(f"{str(path)!r} is a line scan ({topography.dim}-d); the fit needs "
                         f"a 2-d height map")
    heights = np.ma.filled(np.ma.asarray(topography.heights(), dtype=float), np.nan)
    file_pixel = tuple(float(s) / int(g) for s, g in zip(topography.physical_sizes,
                                                        topography.nb_grid_pts, strict=True))
    if pixel_size is not None and "physical_sizes" not in kwargs:
        given = check_pixel_size(pixel_size)
        if not np.allclose(given, file_pixel, rtol=1e-6):
            raise ValueError(f"pixel size {given} m given, but {str(path)!r} says "
                             f"{file_pixel} m")
    return heights, file_pixel


def read_measured(path, *, pixel_size=None, height_scale=1.0):
    """Read a measured height map.

    Parameters
    ----------
    path : str or path-like
        ``.npy`` (2-d float array), a text grid (``.txt``, ``.csv``,
        ``.dat``, ``.asc``) or a profilometer file (SurfaceTopography).
    pixel_size : float or (float, float), m, optional
        Pixel side or ``(dx, dy)``; required for ``.npy`` and text grids.
        For a profilometer file it is read from the file; a value given
        here must agree with it.
    height_scale : float, optional
        Metres per height unit of the file (default 1: the file is in m;
        ``1e-6`` for micrometres).  Profilometer files are converted to m
        first, so keep the default for them.

    Returns
    -------
    MeasuredFace

    Raises
    ------
    FileNotFoundError
        The file does not exist.
    ValueError
        A directory, an empty file, a file of another format
        than its suffix says (named when known: an HDF5 file, pickled data
        -- never unpickled), a damaged or truncated ``.npy``, a text grid
        that is not UTF-8 text or holds no numbers, heights that are not
        real numbers (complex, boolean) or overflow when scaled, not a 2-d
        map, missing pixel size, or a profilometer file without
        SurfaceTopography installed (the message says how to install it).
        Each message names the file and what is wrong.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> import numpy as np
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "face.txt"
    >>> np.savetxt(path, [[1.0, 2.0, 3.0], [4.0, np.nan, 6.0]])
    >>> face = read_measured(path, pixel_size=1e-4, height_scale=1e-6)
    >>> face.shape, face.pixel_size, int(np.isnan(face.heights).sum())
    ((2, 3), (0.0001, 0.0001), 1)
    """
    path = pathlib.Path(path)
    if not os.path.lexists(path):  # a loop of links is there, and named as one
        raise FileNotFoundError(f"measured map {str(path)!r} does not exist")
    input_file_size(path, "measured map")  # a regular file, not empty
    scale = _HEIGHT_SCALE.parse(height_scale, "")
    suffix = path.suffix.lower()
    if suffix == ".npy" or suffix in TEXT_SUFFIXES:
        if pixel_size is None:
            raise ValueError(f"the pixel size of {str(path)!r} is unknown: give it "
                             f"(--pixel-size, m)")
        heights = _read_npy(path) if suffix == ".npy" else _text_grid(path)
        pixel = pixel_size
    else:
        kind = _file_kind(path)
        if kind in _NOT_HEIGHTS:
            raise ValueError(f"measured map {str(path)!r} is {kind}, not a height map: give a "
                             f".npy array, a text grid or a profilometer file")
        heights, pixel = _surface_topography(path, pixel_size)
    heights = np.asarray(heights, dtype=float)
    with np.errstate(over="ignore"):
        scaled = heights * scale
    overflow = np.isinf(scaled) & np.isfinite(heights)
    if np.any(overflow):
        raise ValueError(f"measured map {str(path)!r}: heights of up to "
                         f"{np.max(np.abs(heights[overflow])):.3g} file units times the height "
                         f"scale {scale:.3g} m exceed the largest floating-point number")
    return MeasuredFace(scaled, pixel, source=repr(str(path)))


# Datasets on the measured grid: (units, long_name).
_DATASETS = {
    "measured": ("m", "measured face height, NaN where missing"),
    "fitted": ("m", "fitted face with its plane, NaN off the face"),
    "residual": ("m", "measured minus fitted height on the fitted pixels, NaN elsewhere"),
    "fit_mask": ("1", "1 for the pixels of the fit, 0 elsewhere"),
    "phase": ("1", "phase index, -1 off the face"),
}
# Root quantities: (units, long_name); along phase_name, (phase_name, other_phase_name) or
# component (:data:`_DIMENSIONS`), else 0-d.
_ATTRIBUTES = {
    "ratios": ("1", "wear ratio k_i / k_ref of each phase"),
    "ratio_lower": ("1", "lower end of the confidence interval of each ratio"),
    "ratio_upper": ("1", "upper end of the confidence interval of each ratio (inf: unbounded)"),
    "confidence": ("1", "confidence level of the intervals"),
    "reference_phase": ("1", "index of the phase the ratios refer to"),
    "phase_pressures": ("Pa", "fitted steady pressure of each phase"),
    "phase_pressure_errors": ("Pa", "standard error of each fitted phase pressure"),
    "pressure_covariance": ("Pa2", "covariance of the fitted phase pressures"),
    "offset": ("m", "fitted height at the face's centre"),
    "tilt": ("1", "slopes dz/dx, dz/dy of the fitted plane"),
    "shift": ("m", "position of the face's centre from the measured map's centre"),
    "residual_rms": ("m", "rms of the residual over the fitted pixels"),
    "relief": ("m", "max - min of the fitted face without its plane"),
    "samples": ("1", "pixels in the fit"),
    "effective_samples": ("1", "independent samples, from the residual's correlation"),
    "correlation_length": ("m", "1/e radius of the residual's correlation"),
    "degrees_of_freedom": ("1", "degrees of freedom of the t quantile of the intervals"),
    "load_scale": ("1", "sum_i A_i p_i / F_N: 1 when the fitted pressures carry the load"),
    "load_scale_lower": ("1", "lower end of the confidence interval of load_scale"),
    "load_scale_upper": ("1", "upper end of the confidence interval of load_scale"),
    "implied_normal_force": ("N", "normal force implied by the relief at the scene's E*"),
    "implied_E_star": ("Pa", "effective modulus implied by the relief at the scene's load"),
    "exponent": ("1", "the scene's exponent m of dw/ds = k_i p^m"),
    "normal_force": ("N", "the scene's normal force F_N"),
    "E_star": ("Pa", "the scene's effective modulus E*"),
    "scale": ("m", "length scale L of the outline (a disk's radius)"),
    "n": ("1", "pixels of the model grid along the face's longer side"),
    "scene_ratios": ("1", "wear ratios written in the scene (not used by the fit; NaN: none)"),
    "pixel_size": ("m", "pixel sides dx, dy of the measured map"),
}
# Quantities along dimensions other than phase_name (one value per phase, by its length).
_DIMENSIONS = {"pressure_covariance": ("phase_name", "other_phase_name"),
               "tilt": ("component",), "shift": ("component",), "pixel_size": ("component",)}


@dataclasses.dataclass(frozen=True)
class StoredFit:
    """A fit read back from HDF5 (:func:`read_fit`).

    Attributes
    ----------
    attrs : dict
        The attributes of the layout (see the module notes), plus
        ``success`` (bool), ``message`` and ``measured_source`` (str);
        ``radius`` (m) is None for a face other than a disk, and ``scale``
        is the radius for a version 1 file.
    arrays : dict of str to ndarray
        ``measured``, ``fitted``, ``residual`` (m), ``fit_mask`` (bool),
        ``phase`` (int), each of shape ``(nx, ny)``.
    scene_text : str
    path : pathlib.Path
    outline : outline object
        The face's outline (:mod:`steady.outline`; a disk for a version 1
        file).
    version : int
        The file's layout version.
    phase_names : tuple of str
        One per phase, phase 0 first (``"phase 0", ...`` for a file
        written without names).
    """

    attrs: dict
    arrays: dict
    scene_text: str
    path: pathlib.Path
    outline: object
    version: int = FIT_FORMAT_VERSION
    phase_names: tuple = ()


def write_fit(path, result, scene=None, *, phase_names=None, force=False, checked=False):
    """Write a fit to an HDF5 file (layout ``runin.fit``), atomically.

    Parameters
    ----------
    path : str or path-like
        Missing parent directories are created.
    result : steady.fit.FitResult
    scene : Scene, optional
        Its TOML text and source path are stored.
    phase_names : sequence of str, optional
        One per phase; default the scene's (``[phases] names``), else
        ``"phase 0", "phase 1", ...``.
    force : bool, optional
        Overwrite an existing file (default False).
    checked : bool, optional
        The caller checked ``path`` before the fit: a file found now was
        written meanwhile (see :func:`steady.safe_files.atomic_h5`).

    Returns
    -------
    pathlib.Path

    Raises
    ------
    ValueError
        ``path`` exists and ``force`` is False (an
        :class:`steady.safe_files.OutputAppearedError` if another writer wrote
        it meanwhile: nothing is written), or is a directory.
    """
    path = pathlib.Path(path)
    if phase_names is None:
        phase_names = getattr(scene, "phase_names", None)
    phase_names = (default_phase_names(result.n_phases) if phase_names is None
                   else check_phase_names(phase_names, result.n_phases))
    values = {
        "ratios": result.ratios,
        "ratio_lower": result.ratio_intervals[:, 0],
        "ratio_upper": result.ratio_intervals[:, 1],
        "confidence": result.confidence,
        "reference_phase": result.reference_phase,
        "phase_pressures": result.phase_pressures,
        "phase_pressure_errors": result.phase_pressure_errors,
        "pressure_covariance": result.pressure_covariance,
        "offset": result.offset,
        "tilt": np.asarray(result.tilt),
        "shift": np.asarray(result.shift),
        "residual_rms": result.residual_rms,
        "relief": result.relief,
        "samples": result.samples,
        "effective_samples": result.effective_samples,
        "correlation_length": result.correlation_length,
        "degrees_of_freedom": result.degrees_of_freedom,
        "load_scale": result.load_scale,
        "load_scale_lower": result.load_scale_interval[0],
        "load_scale_upper": result.load_scale_interval[1],
        "implied_normal_force": result.implied_normal_force,
        "implied_E_star": result.implied_E_star,
        "exponent": result.exponent,
        "normal_force": result.normal_force,
        "E_star": result.E_star,
        "scale": result.outline.scale,
        "n": result.n,
        "scene_ratios": (np.full(result.n_phases, np.nan) if result.scene_ratios is None
                         else np.asarray(result.scene_ratios)),
        "pixel_size": np.asarray(result.measured.pixel_size),
    }
    arrays = {
        "measured": result.measured.heights,
        "fitted": result.fitted,
        "residual": result.residual,
        "fit_mask": result.fit_mask.astype(np.int8),
        "phase": result.phase.astype(np.int8 if result.n_phases < 127 else np.int16),
    }
    with atomic_h5(path, format=FIT_FORMAT, version=FIT_FORMAT_VERSION, force=force,
                   checked=checked) as f:
        f.attrs["Conventions"] = CONVENTIONS
        f.attrs["success"] = bool(result.success)
        f.attrs["message"] = result.message
        f.attrs["measured_source"] = result.measured.source
        scales = write_grid_coordinates(f, *result.measured.coordinates())
        dims = _write_dimensions(f, phase_names)
        for name, (unit, long_name) in _ATTRIBUTES.items():
            write_quantity(f, name, values[name], unit, long_name,
                           [dims[d] for d in _DIMENSIONS.get(name, ("phase_name",))]
                           if np.ndim(values[name]) else ())
        write_record(f, result.outline.root_attributes())
        for name, (unit, long_name) in _DATASETS.items():
            write_field(f, name, arrays[name], unit, long_name, scales)
        write_outline(f.create_group("outline"), result.outline)
        ds = f.create_dataset("scene", data="" if scene is None else scene.text,
                              dtype=h5py.string_dtype())
        describe(ds, None, "scene file (TOML), verbatim")
        ds.attrs["source_path"] = ("" if scene is None or scene.source_path is None
                                   else str(scene.source_path))
    return path


def _write_dimensions(f, phase_names):
    """The dimension scales of the fit's quantities: ``{name: scale}``.

    ``phase_name`` and ``other_phase_name`` (the phase names again: the
    columns of the covariance matrix), and ``component`` (``"x"``,
    ``"y"``: the components of the tilt, the shift and the pixel size).
    """
    phase = write_phase_names(f, phase_names)
    other = f.create_dataset("other_phase_name", data=phase[()], dtype=h5py.string_dtype())
    describe(other, None, "name of the phase, phase 0 first (the second index of a matrix)")
    other.make_scale("other_phase_name")
    component = f.create_dataset("component", data=np.array(["x", "y"], dtype=object),
                                 dtype=h5py.string_dtype())
    describe(component, None, "axis of a vector's component")
    component.make_scale("component")
    return {"phase_name": phase, "other_phase_name": other, "component": component}


def _text(value):
    return value.decode() if isinstance(value, bytes) else str(value)


def read_fit(path):
    """Read and check a file written by :func:`write_fit` (this version or version 1).

    Parameters
    ----------
    path : str or path-like

    Returns
    -------
    StoredFit

    Raises
    ------
    FileNotFoundError
        The file does not exist.
    ValueError
        Not a regular file, not HDF5, another layout or version, incomplete
        or a bad outline (the message names the path and the problem).
    """
    path = pathlib.Path(path)
    if not os.path.lexists(path):  # a loop of links is there, and named as one
        raise FileNotFoundError(f"fit file {str(path)!r} does not exist")
    if not path.is_file():
        raise ValueError(f"fit file {str(path)!r} is not a regular file")
    if not h5py.is_hdf5(path):
        raise ValueError(f"fit file {str(path)!r} is not an HDF5 file")
    with h5py.File(path, "r") as f:
        fmt = _text(f.attrs.get("format", ""))
        version = f.attrs.get("format_version")
        version = None if version is None else int(version)
        if fmt != FIT_FORMAT or version not in _READABLE_VERSIONS:
            readable = " or ".join(map(str, _READABLE_VERSIONS))
            raise ValueError(f"{str(path)!r} is not a {FIT_FORMAT} file of version {readable} "
                             f"(format {fmt!r}, version {version!r})")
        # Version 3 stores the quantities as variables and the fields (y, x); 1 and 2 as
        # root attributes and (nx, ny).  Version 1 (disks only) has the radius, not the
        # scale or the outline.
        stored_yx = version >= 3
        values = read_values(f, skip=(*_DATASETS, "scene")) if stored_yx else dict(f.attrs)
        names = [name if version >= 2 or name != "scale" else "radius" for name in _ATTRIBUTES]
        missing = [name for name in (*_DATASETS, "scene") if name not in f]
        missing += [name for name in (*names, "success", "message") if name not in values]
        if version >= 2 and "outline" not in f:
            missing.append("outline")
        if missing:
            raise ValueError(f"fit file {str(path)!r} lacks {missing[0]!r}")
        attrs = {name: values[name] for name in names}
        if version >= 2:
            try:
                outline = read_outline(f["outline"], stored_yx=stored_yx)
            except (ValueError, KeyError, TypeError) as err:
                raise ValueError(f"fit file {str(path)!r}: bad outline: {err}") from None
        else:
            outline = Circle(float(attrs["radius"]))
        attrs["scale"] = outline.scale
        # Disks record their radius at the root (Circle.root_attributes), other faces do not.
        attrs["radius"] = float(values["radius"]) if "radius" in values else None
        attrs["success"] = bool(values["success"])
        attrs["message"] = _text(values["message"])
        attrs["measured_source"] = _text(values.get("measured_source", ""))
        arrays = {name: f[name][()] for name in _DATASETS}
        if stored_yx:
            arrays = {name: field_from_file(value) for name, value in arrays.items()}
        scene_text = _text(f["scene"][()])
        try:
            names = read_phase_names(f, len(np.atleast_1d(attrs["ratios"])))
        except ValueError as err:
            raise ValueError(f"fit file {str(path)!r}: {err}") from None
    arrays["fit_mask"] = arrays["fit_mask"].astype(bool)
    arrays["phase"] = arrays["phase"].astype(np.int64)
    return StoredFit(attrs=attrs, arrays=arrays, scene_text=scene_text, path=path,
                     outline=outline, version=version, phase_names=names)


def _plane(stored):
    """The fitted plane (offset and tilt) on the measured grid, m."""
    a, shape = stored.attrs, stored.arrays["measured"].shape
    dx, dy = a["pixel_size"]
    x = (np.arange(shape[0]) - 0.5 * (shape[0] - 1)) * dx - a["shift"][0]
    y = (np.arange(shape[1]) - 0.5 * (shape[1] - 1)) * dy - a["shift"][1]
    return a["offset"] + a["tilt"][0] * x[:, None] + a["tilt"][1] * y[None, :]


def _interval(lo, hi):
    upper = "inf" if not np.isfinite(hi) else f"{hi:.4g}"
    return f"[{lo:.4g}, {upper}]"


def _layout(half_extent):
    """Panels side by side, or stacked for a face more than twice as wide as tall.

    Returns ``(rows, columns, figsize)``; each panel's box keeps the
    face's aspect (``set_aspect("equal")``) at a legible size.
    """
    from .plotting import PAGE_WIDTH

    lx, ly = half_extent
    aspect = ly / lx
    if aspect >= 0.5:  # a page wide, each map 1.5 in wide beside its colour bar
        height = min(max(1.5 * aspect, 1.5), 5.0)
        return 1, 3, (PAGE_WIDTH, height + 1.4)
    height = min(max(4.8 * aspect, 1.0), 3.0)  # maps about 4.8 in wide, stacked
    return 3, 1, (0.85 * PAGE_WIDTH, 3 * (height + 0.55) + 0.9)


def fit_figure(stored):
    """Measured, fitted and residual faces, on the face's bounding box.

    Parameters
    ----------
    stored : StoredFit
        From :func:`read_fit`.

    Returns
    -------
    matplotlib.figure.Figure
        First: the measured face less the fitted plane (offset and tilt);
        second: the fitted face ``sum_i p_i K chi_i`` on the same colour
        scale, both as relief about the fitted face's least-squares plane
        (:func:`steady.plotting.relief`); third: the residual with the
        phase boundaries.  Each panel shows the outline's bounding box
        about the fitted centre with equal aspect (side by side, or stacked
        for a face more than twice as wide as tall), the face's rim in
        grey.  Heights in micrometres, axes in mm from the map's centre.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from .plotting import FONT_SIZES, relief, set_fonts

    a, arr, outline = stored.attrs, stored.arrays, stored.outline
    plane = _plane(stored)
    measured = (arr["measured"] - plane) * 1e6
    fitted = (arr["fitted"] - plane) * 1e6
    residual = arr["residual"] * 1e6
    on_face = arr["phase"] >= 0
    measured = np.where(on_face, measured, np.nan)
    # Relief, not the dome f = K p: both about the fitted face's plane (pixel units suffice).
    known = on_face & np.isfinite(fitted)
    if known.any():
        level = fitted - relief(fitted, known, 1.0)
        measured, fitted = measured - level, fitted - level
    nx, ny = measured.shape
    dx, dy = a["pixel_size"]
    extent = (-0.5e3 * nx * dx, 0.5e3 * nx * dx, -0.5e3 * ny * dy, 0.5e3 * ny * dy)
    lx, ly = outline.half_extent
    sx, sy = a["shift"]
    view = ((sx - lx) * 1e3, (sx + lx) * 1e3, (sy - ly) * 1e3, (sy + ly) * 1e3)
    values = np.concatenate([measured[np.isfinite(measured)], fitted[np.isfinite(fitted)]])
    vmin, vmax = np.percentile(values, [0.5, 99.5]) if values.size else (0.0, 1.0)
    finite = residual[np.isfinite(residual)]
    rmax = float(np.percentile(np.abs(finite), 99.5)) if finite.size else 1.0

    rows, columns, figsize = _layout(outline.half_extent)
    fig = Figure(figsize=figsize, layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(rows, columns, sharex=True, sharey=True).ravel()
    panels = [(measured, "measured", "viridis", (vmin, vmax)),
              (fitted, r"fitted $\sum_i p_i K\chi_i$", "viridis", (vmin, vmax)),
              (residual, f"residual, rms {a['residual_rms'] * 1e6:.3g} µm", "RdBu_r",
               (-rmax, rmax))]
    x = np.linspace(extent[0], extent[1], nx, endpoint=False) + 0.5e3 * dx
    y = np.linspace(extent[2], extent[3], ny, endpoint=False) + 0.5e3 * dy
    rim = on_face.T.astype(float)
    images = []
    for ax, (field, title, cmap, (lo, hi)) in zip(axes, panels, strict=True):
        # Arrays are indexed [x, y]; imshow wants [row = y, column = x].
        images.append(ax.imshow(field.T, origin="lower", extent=extent, cmap=cmap, vmin=lo,
                                vmax=hi, interpolation="nearest"))
        if 0 < rim.sum() < rim.size:
            ax.contour(x, y, rim, levels=[0.5], colors="0.5", linewidths=0.6)
        ax.set_title(title)
        ax.set_aspect("equal")
        ax.set_xlim(view[0], view[1])
        ax.set_ylim(view[2], view[3])
    # Measured and fitted share one colour scale and one bar.
    bars = [fig.colorbar(images[0], ax=list(axes[:2]), shrink=0.85, aspect=30),
            fig.colorbar(images[2], ax=axes[2], shrink=0.85, aspect=30)]
    bars[0].set_label("height about plane (µm)")
    bars[1].set_label("residual (µm)")
    for ax in axes[-columns:]:
        ax.set_xlabel("x (mm)")
    for ax in axes[::columns]:
        ax.set_ylabel("y (mm)")
    set_fonts(*axes, *(bar.ax for bar in bars))
    n_phases = len(a["ratios"])
    if n_phases > 1:
        axes[2].contour(x, y, arr["phase"].T.astype(float), levels=np.arange(n_phases) + 0.5,
                        colors="k", linewidths=0.4)
    ref = int(a["reference_phase"])
    ratios = ", ".join(
        f"k{i}/k{ref} = {r:.4g} {_interval(lo, hi)}"
        for i, (r, lo, hi) in enumerate(zip(a["ratios"], a["ratio_lower"], a["ratio_upper"],
                                            strict=True)) if i != ref)
    level = f"{100 * a['confidence']:.0f} %"
    shift = a["shift"] * 1e3
    title = (f"{ratios or 'one phase'} ({level} intervals); load scale {a['load_scale']:.4g} "
             f"{_interval(a['load_scale_lower'], a['load_scale_upper'])}\n"
             f"{outline.describe()}, centre at ({shift[0]:.3g}, {shift[1]:.3g}) mm")
    if not a["success"]:
        title += f"\nfit failed: {a['message']}"
    fig.suptitle(title, fontsize=FONT_SIZES["title"])
    return fig


def plot_fit(fit_path, png_path, *, force=False, dpi=200):
    """Draw the figure of an HDF5 fit file into a PNG file.

    Parameters
    ----------
    fit_path : str or path-like
        File written by :func:`write_fit`.
    png_path : str or path-like
        Output image; missing parent directories are created.
    force : bool, optional
        Overwrite an existing image (default False).
    dpi : int, optional

    Returns
    -------
    pathlib.Path

    Raises
    ------
    ValueError
        Unreadable fit file, or ``png_path`` exists and ``force`` is False.
    """
    from .plotting import save_new  # deferred: matplotlib is slow to import

    return save_new(fit_figure(read_fit(fit_path)), png_path, force=force, dpi=dpi)
