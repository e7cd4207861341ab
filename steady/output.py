"""Steady result files, and the HDF5 helpers every file layout of the project shares.

The helpers give a dataset its CF attributes (:func:`describe`), write the
pixel centres and the phase names as dimension scales
(:func:`write_grid_coordinates`, :func:`write_phase_names`,
:func:`attach_scales`) and the face's outline (:func:`write_outline`,
:func:`read_outline`); the fit files (:mod:`steady.fit_files`) and the run
files use them too.  Every file is written whole and atomically by
:func:`steady.safe_files.atomic_h5`.

Steady result files (layout ``runin.steady``, version 2): see docs/files.md
for every dataset and attribute with its unit and meaning.  In short::

    root datasets (CF attributes ``units``, udunits, and ``long_name``)
        x (nx,), y (ny,)  m      pixel centres from the outline's centre: the
                                 dimension scales of every (nx, ny) dataset
        phase_name (P,) string   the phase names, phase 0 first: the dimension
                                 scale ``phase_name``
        phase     (nx, ny) int   phase index, -1 off the face          units "1"
        pressure  (nx, ny) float steady pressure                       units "Pa"
        face      (nx, ny) float limiting face f_inf, NaN off the face units "m"
        slope     (nx, ny) float |grad f_inf|, NaN off the face        units "1"
        scene     scalar string  the scene TOML (attribute ``source_path``)
    root attributes: a quantity ``x`` with its udunits unit in ``x_units``
        format "runin.steady", format_version 2, rms_slope, rms_slope_error,
        rms_slope_plain, rms_slope_ref (grad_f0), rms_slope_ref_error,
        rms_slope_ref_source (text), mean_pressure (Pa), rms_height (m),
        fill_factors, phase_pressures (Pa), the wear law (wear_law_kind, its
        ``[wear] law``; wear_law, in words; and its own attributes, for the
        power law wear_coefficients (Pa-m) and exponent), normal_force (N),
        E_star (Pa),
        pixel_size (m), radius (m, disks only), scale (m), n (pixels along
        the longer side)
    group ``outline``: the face's outline (:func:`write_outline`)
    groups the phase map records (:meth:`steady.phases.PhaseMap.file_record`):
        ``micrograph``, a segmented micrograph's segmentation and placement

An attribute cannot carry attributes, so the unit of attribute ``x`` is the
string attribute ``x_units``, a udunits string like a dataset's ``units``.
Files written before the coordinates and phase names (version 2 without
them, and version 1, disks only, without ``outline``, ``scale``,
``mean_pressure`` and the reference's error and source) are read too.
"""

from __future__ import annotations

import dataclasses
import pathlib

import h5py
import numpy as np

from .outline import OUTLINES, Circle
from .problem import check_phase_names, default_phase_names
from .safe_files import atomic_h5
from .solution import SteadyResult
from .wear import wear_file_attributes, wear_law_from_file

__all__ = ["FORMAT", "FORMAT_VERSION", "StoredResult", "attach_scales", "describe",
           "read_outline", "read_phase_names", "read_result", "write_grid_coordinates",
           "write_outline", "write_phase_names", "write_result"]

FORMAT = "runin.steady"
FORMAT_VERSION = 2
#: Versions :func:`read_result` reads.
_READABLE_VERSIONS = (1, 2)

# Datasets: (units, long_name).
_DATASETS = {
    "phase": ("1", "phase index, -1 off the face"),
    "pressure": ("Pa", "steady contact pressure, zero off the face"),
    "face": ("m", "limiting worn face f_inf = K p, NaN off the face"),
    "slope": ("1", "magnitude of the gradient of the limiting face, NaN off the face"),
}
# Root attributes and their units (udunits); the wear law's come from the law
# (steady.wear.wear_file_attributes).
_ATTRIBUTES = {
    "rms_slope": "1",
    "rms_slope_error": "1",
    "rms_slope_plain": "1",
    "rms_slope_ref": "1",
    "fill_factors": "1",
    "phase_pressures": "Pa",
    "normal_force": "N",
    "E_star": "Pa",
    "pixel_size": "m",
    "n": "1",
}
# Attributes written by this version and read when present (files written
# before they existed still read, with NaN).
_OPTIONAL_ATTRIBUTES = {"rms_height": "m", "rms_slope_ref_error": "1", "mean_pressure": "Pa",
                        "scale": "m"}


def describe(obj, units, long_name):
    """Give a dataset its CF attributes ``units`` (udunits; None: none) and ``long_name``.

    Parameters
    ----------
    obj : h5py.Dataset
    units : str or None
        ``"Pa"``, ``"m"``, ``"1"`` (dimensionless), ...; None for text or
        a code.
    long_name : str
        What the values are, in words.
    """
    if units is not None:
        obj.attrs["units"] = units
    obj.attrs["long_name"] = long_name


def _create(group, name, values, units, long_name, put, **options):
    """A dataset with its CF attributes, made by ``put`` if given."""
    if put is not None:
        return put(group, name, values, units, long_name, **options)
    ds = group.create_dataset(name, data=values, **options)
    describe(ds, units, long_name)
    return ds


def write_grid_coordinates(group, x, y, put=None):
    """The datasets ``x`` and ``y`` (m) of ``group``, made dimension scales ``x`` and ``y``.

    Parameters
    ----------
    group : h5py.Group
    x : ndarray, shape (nx,), m
    y : ndarray, shape (ny,), m
        Pixel centres from the face's centre.
    put : callable, optional
        ``put(group, name, values, units, long_name, **options)`` creating
        a dataset with its CF attributes (a writer that adds its own, such
        as checksums); default :meth:`h5py.Group.create_dataset` and
        :func:`describe`.

    Returns
    -------
    (h5py.Dataset, h5py.Dataset)
        The scales, for :func:`attach_scales`.
    """
    scales = []
    for name, values in (("x", x), ("y", y)):
        ds = _create(group, name, np.asarray(values, dtype=float), "m",
                     f"{name} of the pixel centre, from the centre of the face", put)
        ds.make_scale(name)
        scales.append(ds)
    return tuple(scales)


def write_phase_names(group, names, put=None):
    """The dataset ``phase_name`` of ``group``: the phase names, made a dimension scale.

    Parameters
    ----------
    group : h5py.Group
    names : sequence of str
        One per phase, phase 0 first.
    put : callable, optional
        As for :func:`write_grid_coordinates`.

    Returns
    -------
    h5py.Dataset
    """
    values = np.array([str(name) for name in names], dtype=object)
    ds = _create(group, "phase_name", values, None, "name of the phase, phase 0 first", put,
                 dtype=h5py.string_dtype())
    ds.make_scale("phase_name")
    return ds


def read_phase_names(group, n_phases):
    """The phase names :func:`write_phase_names` wrote, or the defaults if there are none.

    Parameters
    ----------
    group : h5py.Group
    n_phases : int

    Returns
    -------
    tuple of str
        ``("phase 0", "phase 1", ...)`` for a file written without names.

    Raises
    ------
    ValueError
        Another number of names than ``n_phases``.
    """
    if "phase_name" not in group:
        return default_phase_names(n_phases)
    names = tuple(_text(name) for name in np.atleast_1d(group["phase_name"][()]))
    if len(names) != n_phases:
        raise ValueError(f"{len(names)} phase names for {n_phases} phases")
    return names


def attach_scales(ds, *scales):
    """Attach dimension scales to the axes of ``ds``, in order; None leaves an axis bare.

    Parameters
    ----------
    ds : h5py.Dataset
    *scales : h5py.Dataset or None
        One per leading axis of ``ds``; a scale whose length is not that
        of its axis is not attached.
    """
    for axis, scale in enumerate(scales):
        if scale is not None and scale.shape[0] == ds.shape[axis]:
            ds.dims[axis].attach_scale(scale)


@dataclasses.dataclass(frozen=True)
class StoredResult:
    """A steady result read back from HDF5.

    Attributes
    ----------
    result : SteadyResult
    scene_text : str
        The scene TOML stored with the result ("" if none was stored).
    path : pathlib.Path
    phase_names : tuple of str
        One per phase, phase 0 first (``"phase 0", ...`` for a file
        written without names).
    """

    result: SteadyResult
    scene_text: str
    path: pathlib.Path
    phase_names: tuple = ()


def write_result(path, result, scene=None, *, phase_names=None, force=False, checked=False):
    """Write a steady result (and its scene) to an HDF5 file, atomically.

    See :func:`steady.safe_files.atomic_h5`: a reader never sees half a file; missing parent
    directories are created.  The file holds the result's inputs (load,
    modulus, wear law, phase map, outline, phase names) whether or not a
    scene is given.

    Parameters
    ----------
    path : str or path-like
    result : SteadyResult
    scene : Scene, optional
        Its TOML text and source path are stored.
    phase_names : sequence of str, optional
        One per phase; default the scene's (``[phases] names``), else
        ``"phase 0", "phase 1", ...``.
    force : bool, optional
        Overwrite an existing file (default False).
    checked : bool, optional
        The caller checked ``path`` before the solve: a file found now was
        written meanwhile (see :func:`steady.safe_files.atomic_h5`).

    Returns
    -------
    pathlib.Path

    Raises
    ------
    ValueError
        ``path`` is a directory, or ``phase_names`` are not one distinct
        name per phase.
    steady.safe_files.OutputExistsError
        (a ``ValueError``) ``path`` exists and ``force`` is False; an
        :class:`~steady.safe_files.OutputAppearedError` if another writer
        wrote it while this result was written (nothing is written then).

    Examples
    --------
    >>> import pathlib, tempfile
    >>> import xarray as xr
    >>> from steady import Circle, FacePhases, Problem, Voronoi, solve
    >>> grid = Circle(4e-3).grid(32)
    >>> phases = FacePhases(grid, Voronoi(64, (0.7, 0.3), seed=2029).labels(grid), 2)
    >>> result = solve(Problem(phases, [1e-13, 1e-12], 10.0, 1.3e6))
    >>> path = write_result(pathlib.Path(tempfile.mkdtemp()) / "r.h5", result)
    >>> with xr.open_dataset(path, engine="h5netcdf") as ds:
    ...     print(ds["pressure"].dims, ds["x"].attrs["units"], ds["phase_name"].values.tolist())
    ('x', 'y') m ['phase 0', 'phase 1']
    """
    path = pathlib.Path(path)
    if phase_names is None:
        phase_names = getattr(result, "phase_names", None) or getattr(scene, "phase_names", None)
    phase_names = check_phase_names(phase_names, result.n_phases) if phase_names is not None \
        else default_phase_names(result.n_phases)
    with atomic_h5(path, format=FORMAT, version=FORMAT_VERSION, force=force,
                   checked=checked) as f:
        _write(f, result, scene, phase_names)
    return path


def _write(f, result, scene, phase_names):
    values = {
        "rms_slope": result.rms_slope,
        "rms_slope_error": result.rms_slope_error,
        "rms_slope_plain": result.rms_slope_plain,
        "rms_slope_ref": result.reference_slope,
        "fill_factors": np.asarray(result.fill_factors),
        "phase_pressures": np.asarray(result.phase_pressures),
        "normal_force": result.normal_force,
        "E_star": result.E_star,
        "pixel_size": result.pixel_size,
        "n": result.n,
        "rms_height": result.rms_height,
        "rms_slope_ref_error": result.reference_slope_error,
        "mean_pressure": result.mean_pressure,
        "scale": result.scale,
    }
    units = {**_ATTRIBUTES, **_OPTIONAL_ATTRIBUTES}
    if result.wear is not None:
        for name, (value, unit) in wear_file_attributes(result.wear).items():
            values[name] = value
            units[name] = unit
    for name, unit in units.items():
        f.attrs[name] = values[name]
        if unit is not None:
            f.attrs[f"{name}_units"] = unit
    f.attrs["rms_slope_ref_source"] = result.reference_slope_source
    for name, (value, unit) in result.outline.root_attributes().items():
        f.attrs[name] = value
        f.attrs[f"{name}_units"] = unit
    write_outline(f.create_group("outline"), result.outline)
    grid = result.outline.grid(result.n)
    scales = write_grid_coordinates(f, grid.x, grid.y)
    write_phase_names(f, phase_names)
    dtype = np.int8 if result.n_phases < 127 else np.int16
    arrays = {"phase": result.labels.astype(dtype), "pressure": result.pressure,
              "face": result.face, "slope": result.slope}
    for name, (unit, long_name) in _DATASETS.items():
        ds = f.create_dataset(name, data=arrays[name])
        describe(ds, unit, long_name)
        attach_scales(ds, *scales)
    ds = f.create_dataset("scene", data="" if scene is None else scene.text,
                          dtype=h5py.string_dtype())
    describe(ds, None, "scene file (TOML), verbatim")
    ds.attrs["source_path"] = "" if scene is None or scene.source_path is None else str(
        scene.source_path)
    for name, attributes in ({} if scene is None else scene.geometry.file_record()).items():
        f.create_group(name).attrs.update(attributes)


def write_outline(group, outline):
    """A face outline as the attributes (and for a mask the dataset) of ``group``.

    Attribute ``x`` has its udunits unit in ``x_units``: ``area`` (``m2``)
    and the outline's lengths (``m``); then what the outline records
    besides (:meth:`~steady.outline.MaskOutline.group_record`): a mask
    outline's ``source`` and ``mask``, with the dimension scales ``mask_x``
    and ``mask_y`` (m, its pixel centres).

    Parameters
    ----------
    group : h5py.Group
    outline : outline object (:mod:`steady.outline`)
    """
    group.attrs["kind"] = outline.kind
    group.attrs["area"] = outline.area
    group.attrs["area_units"] = "m2"
    for name, (value, unit) in outline.parameters().items():
        group.attrs[name] = value
        group.attrs[f"{name}_units"] = unit
    attributes, arrays = outline.group_record()
    for name, (values, units, long_name, coordinates) in arrays.items():
        ds = group.create_dataset(name, data=values)
        describe(ds, units, long_name)
        scales = []
        for axis, centres in zip("xy", coordinates, strict=True) if coordinates else ():
            scale = group.create_dataset(f"{name}_{axis}", data=centres)
            describe(scale, "m", f"{axis} of the {name}'s pixel centre, from its centre")
            scale.make_scale(f"{name}_{axis}")
            scales.append(scale)
        attach_scales(ds, *scales)
    group.attrs.update(attributes)


def read_outline(group):
    """The outline written by :func:`write_outline`.

    Raises
    ------
    ValueError
        An unknown kind or missing lengths.
    """
    kind = group.attrs.get("kind")
    if isinstance(kind, bytes):
        kind = kind.decode()
    if kind not in OUTLINES:
        raise ValueError(f"unknown outline kind {kind!r} (known: {sorted(OUTLINES)})")
    return OUTLINES[kind].from_group(group.attrs, lambda name: group[name][()])


def _text(value):
    """A string attribute as ``str``."""
    return value.decode() if isinstance(value, bytes) else str(value)


def read_result(path):
    """Read and check a file written by :func:`write_result`.

    Parameters
    ----------
    path : str or path-like

    Returns
    -------
    StoredResult

    Raises
    ------
    FileNotFoundError
        The file does not exist.
    ValueError
        Not a regular file, not HDF5, corrupt, another layout or another
        version (the message names the path and the problem).
    """
    path = pathlib.Path(path)
    if not path.exists():
        raise FileNotFoundError(f"result file {str(path)!r} does not exist")
    if not path.is_file():
        raise ValueError(f"result file {str(path)!r} is not a regular file")
    try:
        is_hdf5 = h5py.is_hdf5(path)
    except OSError as err:
        raise ValueError(f"cannot read result file {str(path)!r}: {err}") from None
    if not is_hdf5:
        raise ValueError(f"result file {str(path)!r} is not an HDF5 file")
    try:
        with h5py.File(path, "r") as f:
            result, scene_text = _read(f, path)
            try:
                names = read_phase_names(f, result.n_phases)
            except ValueError as err:
                raise ValueError(f"result file {str(path)!r}: {err}") from None
            return StoredResult(result, scene_text, path=path, phase_names=names)
    except (OSError, KeyError, TypeError) as err:
        raise ValueError(f"result file {str(path)!r} is corrupt or incomplete: {err}") from None


def _read(f, path):
    fmt = f.attrs.get("format")
    if isinstance(fmt, bytes):
        fmt = fmt.decode()
    if fmt != FORMAT:
        raise ValueError(f"result file {str(path)!r} is not a {FORMAT} file "
                         f"(format attribute {fmt!r})")
    version = f.attrs.get("format_version")
    if isinstance(version, np.generic):
        version = version.item()
    if version not in _READABLE_VERSIONS:
        raise ValueError(f"result file {str(path)!r} has format_version {version!r}; this "
                         f"reader supports {', '.join(map(str, _READABLE_VERSIONS))}")
    missing = [name for name in (*_DATASETS, "scene") if name not in f]
    missing += [name for name in _ATTRIBUTES if name not in f.attrs]
    if version >= 2 and "outline" not in f:
        missing.append("outline")
    if version < 2 and "radius" not in f.attrs:
        missing.append("radius")
    if missing:
        raise ValueError(f"result file {str(path)!r} lacks {missing[0]!r}")
    a = {name: f.attrs[name] for name in _ATTRIBUTES}
    if version >= 2:
        try:
            outline = read_outline(f["outline"])
        except (ValueError, KeyError) as err:
            raise ValueError(f"result file {str(path)!r}: bad outline: {err}") from None
    else:
        outline = Circle(float(f.attrs["radius"]))
    arrays = {name: f[name][()] for name in _DATASETS}
    n = int(a["n"])
    try:
        shape = outline.grid_shape(n)
    except ValueError as err:
        raise ValueError(f"result file {str(path)!r}: {err}") from None
    bad = [name for name, v in arrays.items() if v.shape != shape]
    if bad:
        raise ValueError(f"result file {str(path)!r}: dataset {bad[0]!r} has shape "
                         f"{arrays[bad[0]].shape}, expected {shape}")
    scene_text = f["scene"][()]
    if isinstance(scene_text, bytes):
        scene_text = scene_text.decode("utf-8")
    try:
        wear = wear_law_from_file(f.attrs)
    except ValueError as err:
        raise ValueError(f"result file {str(path)!r}: bad wear law: {err}") from None
    result = SteadyResult(
        labels=arrays["phase"].astype(np.int64),
        pressure=arrays["pressure"],
        phase_pressures=np.atleast_1d(a["phase_pressures"]).astype(float),
        face=arrays["face"],
        slope=arrays["slope"],
        rms_slope=float(a["rms_slope"]),
        reference_slope=float(a["rms_slope_ref"]),
        fill_factors=np.atleast_1d(a["fill_factors"]).astype(float),
        wear=wear,
        normal_force=float(a["normal_force"]),
        E_star=float(a["E_star"]),
        rms_slope_plain=float(a["rms_slope_plain"]),
        rms_slope_error=float(a["rms_slope_error"]),
        rms_height=float(f.attrs.get("rms_height", np.nan)),
        outline=outline,
        reference_slope_error=float(f.attrs.get("rms_slope_ref_error", 0.0)),
        reference_slope_source=_text(f.attrs.get("rms_slope_ref_source",
                                                 "disk: 4 pbar / (pi E*) (eq. 12)")),
    )
    return result, scene_text
