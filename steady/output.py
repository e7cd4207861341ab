"""Steady result files, and the HDF5 helpers every file layout of the project shares.

The result, run and fit files follow the CF conventions as netCDF tools read
them (root attribute ``Conventions``, :data:`CONVENTIONS`): every quantity is
a variable with the CF attributes ``units`` (udunits) and ``long_name``
(:func:`describe`) -- a scalar result a 0-d variable (:func:`write_quantity`,
:func:`write_record`), a value per phase a variable along ``phase_name`` --
and text stays in attributes.  The pixel centres and the phase names are
dimension scales (:func:`write_grid_coordinates`, :func:`write_phase_names`,
:func:`attach_scales`); a field of the face, indexed ``[i, j]`` with ``i``
along x in memory, is stored ``[j, i]`` on ``(y, x)`` (:func:`write_field`,
:func:`field_from_file`), so that xarray draws x across.  The face's outline
has a group of its own (:func:`write_outline`, :func:`read_outline`).  The
fit files (:mod:`steady.fit_files`) and the run files use these helpers too;
every file is written whole and atomically by
:func:`steady.safe_files.atomic_h5`.

Steady result files (layout ``runin.steady``, version 3): see docs/files.md
for every variable and attribute with its unit and meaning.  In short::

    root variables (CF attributes ``units``, udunits, and ``long_name``)
        x (nx,), y (ny,)  m      pixel centres from the outline's centre: the
                                 dimension scales of every field
        phase_name (P,) string   the phase names, phase 0 first: the dimension
                                 scale ``phase_name``
        phase     (ny, nx) int   phase index, -1 off the face          units "1"
        pressure  (ny, nx) float steady pressure                       units "Pa"
        face      (ny, nx) float limiting face f_inf, NaN off the face units "m"
        slope     (ny, nx) float |grad f_inf|, NaN off the face        units "1"
        scene     scalar string  the scene TOML (attribute ``source_path``)
        0-d: rms_slope, rms_slope_error, rms_slope_plain, rms_slope_ref
        (grad_f0), rms_slope_ref_error, mean_pressure (Pa), rms_height (m),
        normal_force (N), E_star (Pa), pixel_size (m), radius (m, disks
        only), scale (m), n (pixels along the longer side), the wear law's
        numbers (the power law's exponent); on a layered counter-body its
        thickness (m) and poisson (1), absent on a half-space
        (phase_name): fill_factors, phase_pressures (Pa), the wear law's
        numbers per phase (the power law's wear_coefficients, Pa-m)
    root attributes: format "runin.steady", format_version 3, Conventions,
        rms_slope_ref_source, wear_law_kind (its ``[wear] law``), wear_law
        (in words)
    group ``outline``: the face's outline (:func:`write_outline`)
    groups the phase map records (:meth:`steady.phases.PhaseMap.file_record`):
        ``micrograph``, a segmented micrograph's segmentation and placement
    group ``face_psd``: the face's radially averaged power spectral density
        (:attr:`steady.solution.SteadyResult.face_psd`), ``psd`` (K,) in m4
        along the dimension scale ``wavevector`` (K,) in m-1

Files of version 2 (the quantities as root attributes, the unit of ``x`` in
``x_units``; the fields stored ``(nx, ny)``), of version 2 without the
coordinates and phase names, and of version 1 (disks only, without
``outline``, ``scale``, ``mean_pressure`` and the reference's error and
source) are read too.
"""

from __future__ import annotations

import dataclasses
import os
import pathlib

import h5py
import numpy as np

from .counterbody import Counterbody
from .outline import OUTLINES, Circle
from .problem import check_phase_names, default_phase_names
from .safe_files import atomic_h5
from .solution import SteadyResult
from .wear import wear_file_attributes, wear_law_from_file

__all__ = ["CONVENTIONS", "FORMAT", "FORMAT_VERSION", "StoredResult", "attach_scales",
           "describe", "field_from_file", "read_outline", "read_phase_names", "read_result",
           "read_values", "wear_long_names", "write_field", "write_grid_coordinates",
           "write_outline", "write_phase_names", "write_quantity", "write_record",
           "write_result"]

FORMAT = "runin.steady"
FORMAT_VERSION = 3
#: Versions :func:`read_result` reads (1 and 2: the quantities as root attributes, the
#: fields stored (nx, ny)).
_READABLE_VERSIONS = (1, 2, 3)

#: The root attribute ``Conventions`` of the result, run and fit files.
CONVENTIONS = "CF-1.10"

# Fields: (units, long_name).
_DATASETS = {
    "phase": ("1", "phase index, -1 off the face"),
    "pressure": ("Pa", "steady contact pressure, zero off the face"),
    "face": ("m", "limiting worn face f_inf = K p, NaN off the face"),
    "slope": ("1", "magnitude of the gradient of the limiting face, NaN off the face"),
}
# Root quantities (0-d, or along phase_name): (units, long_name); the wear law's come from
# the law (steady.wear.wear_file_attributes), the outline's from the outline.
_ATTRIBUTES = {
    "rms_slope": ("1", "rms slope over the face, best estimate (energy-corrected)"),
    "rms_slope_error": ("1", "estimated discretisation error of rms_slope (NaN: not "
                             "estimated, inf: no bound)"),
    "rms_slope_plain": ("1", "plain pixel rms of slope over the face"),
    "rms_slope_ref": ("1", "grad_f0, the rms slope of the homogeneous face of the outline "
                           "under the same load"),
    "fill_factors": ("1", "realised area fraction of each phase"),
    "phase_pressures": ("Pa", "steady contact pressure on each phase"),
    "normal_force": ("N", "normal force F_N"),
    "E_star": ("Pa", "effective modulus E* of the counter-body"),
    "pixel_size": ("m", "side h of the grid's square pixels"),
    "n": ("1", "pixels of the grid along the face's longer side"),
}
# Quantities written by this version and read when present (files written
# before they existed still read, with NaN).
_OPTIONAL_ATTRIBUTES = {
    "rms_height": ("m", "rms of the limiting face about its least-squares plane"),
    "rms_slope_ref_error": ("1", "uncertainty of rms_slope_ref (0 for a closed form)"),
    "mean_pressure": ("Pa", "mean pressure pbar = F_N / A"),
    "scale": ("m", "length scale L of the outline (a disk's radius)"),
}
# Long names of the quantities the wear laws and the outlines record (others: the key's doc).
_RECORD_NAMES = {
    "wear_coefficients": "wear coefficient k_i of each phase in dw/ds = k_i p^m",
    "exponent": "exponent m of the pressure in dw/ds = k_i p^m",
    "wear_thresholds": "threshold pressure p_th,i of each phase: no wear at or below it",
    "radius": "radius of the disk",
    "area": "area of the face",
    "width": "width of the rectangle (along x)",
    "length": "length of the rectangle (along y)",
    "semi_axis_x": "semi-axis of the ellipse along x",
    "semi_axis_y": "semi-axis of the ellipse along y",
    "inner_radius": "radius of the annulus's inner circle",
    "outer_radius": "radius of the annulus's outer circle",
    "pixel_size": "side of the mask's pixels",
    "mask_pixels_x": "pixels of the mask along x",
    "mask_pixels_y": "pixels of the mask along y",
}


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


def field_from_file(values):
    """A field as the files store it, ``[..., j, i]`` on ``(..., y, x)``, indexed ``[..., i, j]``.

    The library indexes a field ``[i, j]`` with ``i`` along x; the files
    store it transposed (:func:`write_field`), x last, so that netCDF tools
    draw x across.  The array returned is C-contiguous, as the library's.

    Parameters
    ----------
    values : ndarray, shape (..., ny, nx)

    Returns
    -------
    ndarray, shape (..., nx, ny)
    """
    return np.ascontiguousarray(np.swapaxes(np.asarray(values), -1, -2))


def write_field(group, name, values, units, long_name, scales=(), put=None, **options):
    """A field ``[..., i, j]`` (``i`` along x) stored ``[..., j, i]`` on the scales ``(..., y, x)``.

    xarray's ``plot`` puts the last dimension across: stored so, a face
    opened with ``xarray.open_dataset`` draws with x across and y up.
    :func:`field_from_file` reads it back.

    Parameters
    ----------
    group : h5py.Group
    name : str
    values : ndarray, shape (..., nx, ny)
    units : str or None
    long_name : str
    scales : sequence of h5py.Dataset or None, optional
        The dimension scales of the library's axes, ``(..., x, y)``; None
        leaves an axis bare.
    put : callable, optional
        As for :func:`write_grid_coordinates`.
    **options
        Passed to the dataset's creation (compression, ...).

    Returns
    -------
    h5py.Dataset
    """
    ds = _create(group, name, np.swapaxes(np.asarray(values), -1, -2), units, long_name, put,
                 **options)
    if scales:
        *leading, x, y = scales
        attach_scales(ds, *leading, y, x)
    return ds


def write_quantity(group, name, value, units, long_name, dims=(), put=None):
    """A quantity as a variable of ``group``: 0-d for a scalar, else on the scales ``dims``.

    A 1-d quantity without a scale is made a dimension scale of its own (a
    coordinate, as netCDF tools need one for every dimension).

    Parameters
    ----------
    group : h5py.Group
    name : str
    value : float, int, str or ndarray
    units : str or None
        udunits (``"m"``, ``"1"``, ...); None for a code.
    long_name : str
    dims : sequence of h5py.Dataset, optional
        The dimension scales of its axes.
    put : callable, optional
        As for :func:`write_grid_coordinates`.

    Returns
    -------
    h5py.Dataset
    """
    ds = _create(group, name, value, units, long_name, put)
    if dims:
        attach_scales(ds, *dims)
    elif ds.ndim == 1:
        ds.make_scale(name)
    return ds


def write_record(group, record, phase_scale=None, put=None, long_names=None):
    """A record ``name -> (value, units)``: quantities as variables, text as attributes.

    A value with a unit is a quantity: a variable (:func:`write_quantity`),
    along ``phase_scale`` when it holds one value per phase.  A value
    without one (text, the law's name) is an attribute.

    Parameters
    ----------
    group : h5py.Group
    record : mapping of str to (object, str or None)
        E.g. :func:`steady.wear.wear_file_attributes`,
        :meth:`~steady.outline.Circle.parameters`.
    phase_scale : h5py.Dataset, optional
        The dimension scale ``phase_name``.
    put : callable, optional
        As for :func:`write_grid_coordinates`.
    long_names : mapping of str to str, optional
        Long names of the record's quantities; default the project's
        (wear laws, outlines), else the name in words.
    """
    names = {**_RECORD_NAMES, **(long_names or {})}
    for name, (value, units) in record.items():
        if units is None:
            group.attrs[name] = value
            continue
        per_phase = (phase_scale is not None and np.ndim(value) == 1
                     and len(value) == phase_scale.shape[0])
        write_quantity(group, name, value, units, names.get(name, name.replace("_", " ")),
                       (phase_scale,) if per_phase else (), put)


def read_values(group, skip=()):
    """A group's attributes and the values of its datasets, by name (text as ``str``).

    What :func:`write_quantity` and :func:`write_record` wrote as variables
    reads back as the attributes of the earlier layouts did: numpy scalars
    and arrays.

    Parameters
    ----------
    group : h5py.Group
    skip : collection of str, optional
        Datasets not to read (the fields, the coordinates).

    Returns
    -------
    dict
    """
    values = dict(group.attrs)
    for name, obj in group.items():
        if isinstance(obj, h5py.Dataset) and name not in skip:
            value = obj[()]
            values[name] = value.decode("utf-8") if isinstance(value, bytes) else value
    return values


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
    ...     print(ds["rms_slope"].attrs["units"], ds["phase_pressures"].dims)
    ('y', 'x') m ['phase 0', 'phase 1']
    1 ('phase_name',)
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
    f.attrs["Conventions"] = CONVENTIONS
    grid = result.outline.grid(result.n)
    scales = write_grid_coordinates(f, grid.x, grid.y)
    phase_scale = write_phase_names(f, phase_names)
    _write_quantities(f, result, phase_scale)
    write_outline(f.create_group("outline"), result.outline)
    _write_fields(f, result, scales)
    _write_scene(f, scene)
    _write_face_psd(f.create_group("face_psd"), result.face_psd)


def _write_quantities(f, result, phase_scale):
    """The result's figures and inputs: root variables, 0-d or along ``phase_name``."""
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
    quantities = {**_ATTRIBUTES, **_OPTIONAL_ATTRIBUTES}
    write_record(f, {name: (values[name], unit) for name, (unit, _) in quantities.items()},
                 phase_scale, long_names={name: words for name, (_, words) in quantities.items()})
    if result.wear is not None:
        write_record(f, wear_file_attributes(result.wear), phase_scale,
                     long_names=wear_long_names(result.wear))
    f.attrs["rms_slope_ref_source"] = result.reference_slope_source
    write_record(f, result.outline.root_attributes())
    layer = Counterbody(result.E_star, result.thickness, result.poisson).file_attributes()
    if layer:  # a half-space's file has none of them
        write_record(f, {name: (value, unit) for name, (value, unit, _) in layer.items()},
                     long_names={name: words for name, (_, _, words) in layer.items()})


def _write_fields(f, result, scales):
    """The phase map, the pressure, the face and its slope, stored (y, x)."""
    dtype = np.int8 if result.n_phases < 127 else np.int16
    arrays = {"phase": result.labels.astype(dtype), "pressure": result.pressure,
              "face": result.face, "slope": result.slope}
    for name, (unit, long_name) in _DATASETS.items():
        write_field(f, name, arrays[name], unit, long_name, scales)


def _write_scene(f, scene):
    """The scene's text and source path, and the records of its phase map."""
    ds = f.create_dataset("scene", data="" if scene is None else scene.text,
                          dtype=h5py.string_dtype())
    describe(ds, None, "scene file (TOML), verbatim")
    ds.attrs["source_path"] = "" if scene is None or scene.source_path is None else str(
        scene.source_path)
    for name, attributes in ({} if scene is None else scene.geometry.file_record()).items():
        f.create_group(name).attrs.update(attributes)


def _write_face_psd(group, spectrum):
    """The steady face's ``C^iso(q)`` (:attr:`SteadyResult.face_psd`) as datasets of ``group``."""
    q = group.create_dataset("wavevector", data=spectrum.wavevector)
    describe(q, "m-1", "wavevector magnitude q = 2 pi / wavelength, mean over the bin")
    q.make_scale("wavevector")
    ds = group.create_dataset("psd", data=spectrum.density)
    describe(ds, "m4", "radially averaged power spectral density of the face about its "
                       "least-squares plane, Hann-windowed (SurfaceTopography's C^iso)")
    attach_scales(ds, q)


def wear_long_names(wear):
    """Long names of what a file records of a wear law (:func:`steady.wear.wear_file_attributes`).

    The project's own for the power and threshold laws' numbers; for
    another law's ``wear_<key>``, its key's ``doc``.

    Parameters
    ----------
    wear : steady.wear.WearLaw

    Returns
    -------
    dict of str to str
    """
    return {f"wear_{key.name}": f"[wear] {key.name}: {key.doc}" for key in wear.keys
            if key.doc and f"wear_{key.name}" not in _RECORD_NAMES}


def write_outline(group, outline):
    """A face outline as the attribute ``kind`` and the variables of ``group``.

    0-d variables ``area`` (``m2``) and the outline's lengths (``m``,
    :meth:`~steady.outline.Circle.parameters`); then what the outline
    records besides (:meth:`~steady.outline.MaskOutline.group_record`): a
    mask outline's attribute ``source`` and its ``mask``, a field stored
    ``(mask_y, mask_x)`` (:func:`write_field`) on the dimension scales
    ``mask_x`` and ``mask_y`` (m, its pixel centres).

    Parameters
    ----------
    group : h5py.Group
    outline : outline object (:mod:`steady.outline`)
    """
    group.attrs["kind"] = outline.kind
    write_record(group, {"area": (outline.area, "m2"), **outline.parameters()})
    attributes, arrays = outline.group_record()
    for name, (values, units, long_name, coordinates) in arrays.items():
        scales = []
        for axis, centres in zip("xy", coordinates, strict=True) if coordinates else ():
            scale = group.create_dataset(f"{name}_{axis}", data=centres)
            describe(scale, "m", f"{axis} of the {name}'s pixel centre, from its centre")
            scale.make_scale(f"{name}_{axis}")
            scales.append(scale)
        if np.ndim(values) == 2:
            write_field(group, name, values, units, long_name, scales)
        else:
            write_quantity(group, name, values, units, long_name, scales)
    group.attrs.update(attributes)


def read_outline(group, *, stored_yx=True):
    """The outline written by :func:`write_outline`.

    Parameters
    ----------
    group : h5py.Group
        Or any object with its ``attrs``, its dataset names (iteration) and
        their values (``group[name][()]``).
    stored_yx : bool, optional
        Whether its 2-d datasets are stored ``(y, x)`` (default True: result
        layout 3, run layout 5, fit layout 3 on); False for the earlier
        layouts, whose lengths are attributes and whose mask is ``(mx, my)``.

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
    values = dict(group.attrs)
    for name in group:
        value = group[name][()]
        if np.ndim(value) == 0:
            values.setdefault(name, value)

    def read(name):
        value = group[name][()]
        return field_from_file(value) if stored_yx and np.ndim(value) == 2 else value

    return OUTLINES[kind].from_group(values, read)


def _layer_value(values, name):
    """``thickness`` or ``poisson`` of a file's counter-body layer as a float; None: absent."""
    return float(values[name]) if name in values else None


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
    if not os.path.lexists(path):  # a loop of links is there, and named as one
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
    # Layout 3 stores the quantities as variables and the fields (y, x); 1 and 2 as root
    # attributes and (nx, ny).
    stored_yx = version >= 3
    values = read_values(f, skip=(*_DATASETS, "scene")) if stored_yx else dict(f.attrs)
    missing = [name for name in (*_DATASETS, "scene") if name not in f]
    missing += [name for name in _ATTRIBUTES if name not in values]
    if version >= 2 and "outline" not in f:
        missing.append("outline")
    if version < 2 and "radius" not in values:
        missing.append("radius")
    if missing:
        raise ValueError(f"result file {str(path)!r} lacks {missing[0]!r}")
    a = {name: values[name] for name in _ATTRIBUTES}
    if version >= 2:
        try:
            outline = read_outline(f["outline"], stored_yx=stored_yx)
        except (ValueError, KeyError) as err:
            raise ValueError(f"result file {str(path)!r}: bad outline: {err}") from None
    else:
        outline = Circle(float(values["radius"]))
    arrays = {name: f[name][()] for name in _DATASETS}
    if stored_yx:
        arrays = {name: field_from_file(v) if v.ndim == 2 else v for name, v in arrays.items()}
    n = int(a["n"])
    try:
        shape = outline.grid_shape(n)
    except ValueError as err:
        raise ValueError(f"result file {str(path)!r}: {err}") from None
    bad = [name for name, v in arrays.items() if v.shape != shape]
    if bad:
        shown = arrays[bad[0]].shape[::-1] if stored_yx else arrays[bad[0]].shape
        raise ValueError(f"result file {str(path)!r}: dataset {bad[0]!r} has shape "
                         f"{shown}, expected {shape[::-1] if stored_yx else shape}")
    scene_text = f["scene"][()]
    if isinstance(scene_text, bytes):
        scene_text = scene_text.decode("utf-8")
    try:
        wear = wear_law_from_file(values)
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
        rms_height=float(values.get("rms_height", np.nan)),
        outline=outline,
        reference_slope_error=float(values.get("rms_slope_ref_error", 0.0)),
        reference_slope_source=_text(values.get("rms_slope_ref_source",
                                                "disk: 4 pbar / (pi E*) (eq. 12)")),
        thickness=_layer_value(values, "thickness"),
        poisson=_layer_value(values, "poisson"),
    )
    return result, scene_text
