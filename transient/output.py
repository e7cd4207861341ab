"""HDF5 run files (layout ``runin.transient``, version 5), checksummed and written by one writer.

A run file holds a run-in, finished or in progress (a checkpoint): the
state a resumed run needs (:class:`transient.result.RunState`), the
history, the snapshots, the inputs that identify the run and, once the run
is steady, its agreement with the steady face.  It is written whole and
atomically by the project's one HDF5 writer (:func:`steady.safe_files.atomic_h5`),
so a reader never sees half a file and a killed run leaves its last
checkpoint intact.  It follows the CF conventions (root attribute
``Conventions``) and opens in xarray (``xarray.open_datatree(path,
engine="h5netcdf")``, one node per group) as labelled arrays;
docs/files.md lists every variable and attribute.

Layout (root group)::

    attributes    format "runin.transient", format_version 5, Conventions,
                  status, message, scheme, reference_slope_source (where
                  grad_f0 comes from, in words), wear_law_kind, wear_law (in
                  words), the caller's text attributes (scene, ...; one given
                  as None is left out), coating_<event>_reason (depth runs)
    0-d variables distance (m), steps, rejected, failures, solves,
                  iterations, wall_time (s), offset (m), approach (m),
                  depth_scale (m), distance_scale (m), fast_distance (m),
                  pixel_mean_pressure (Pa), reference_slope,
                  steady_rms_slope, steady_rms_slope_error, sliding_speed
                  (m s-1, NaN if none), previous_step (m, NaN if none),
                  next_step (m, NaN if none), jumps (jumps to the steady state
                  so far); the problem's inputs (:func:`problem_inputs`, when
                  the result knows its problem): n, normal_force (N), E_star
                  (Pa), the wear law's numbers (the power law's exponent), the sliding
                  kinematics unless a translation (sliding_kind and its keys
                  as sliding_<key>, e.g. sliding_track_radius (m));
                  with the face's outline: reference_slope_error, scale (m,
                  the outline's L), pixel_size (m) and, for a disk only,
                  radius (m); the caller's quantities; a depth run's
                  coating_<event>_distance (m) and ..._s_star (1)
    x, y          (nx,), (ny,) m: pixel centres, the dimension scales of
                  every field
    phase_name    (P,) the phase names: the dimension scale ``phase_name``,
                  of the wear law's numbers per phase (wear_coefficients)
    worn_depth    (y, x) m, NaN off the face
    face          (y, x) m, the face's elevation (:attr:`transient.result.RunResult.face`:
                  approach - recession, ``K p`` on the contact), NaN off the face; layout 5 on
    pressure      (y, x) Pa
    phase         (y, x) the phase map, and the caller's fields
    state/        recession, initial_recession, previous_recession, previous_rate
                  (y, x); pressure_history, pressure_history_displacement
                  (kept_solve, y, x)
    history/      one variable per :data:`transient.result.HISTORY_UNITS` name,
                  along the dimension scale ``distance`` (m), but the spatial
                  errors while empty; 0-d distance_scale (s*, m); under a load
                  programme load_breakpoints (m, a dimension scale),
                  load_forces (N), load_initial_force (N); a depth run's also
                  :data:`transient.result.DEPTH_HISTORY_UNITS` (phase_fraction
                  also along ``phase_name``) and, under a coating,
                  :data:`transient.result.COATING_HISTORY_UNITS`
    snapshots/    distance (k,) m (a dimension scale), recession (distance, y, x)
                  m, pressure (distance, y, x) Pa (byte shuffle and deflate,
                  except in a checkpoint); for a depth run section (distance,
                  y, x) int8, the phase map of the section at the worn depth;
                  under a load programme force (distance,) N and the
                  programme as in history/
    columns/      a depth run only, not in a checkpoint (the problem's
                  :class:`steady.depth.DepthColumns`): interfaces
                  (interface, y, x) m, phases (segment, y, x) int8, 0-d n_phases;
                  a checkpoint holds their digest instead, the root
                  attribute columns_sha256
    comparison/   :class:`transient.comparison.SteadyComparison` (steady runs):
                  0-d variables, the phase pressures along ``phase_name``,
                  the flag rms_slope_agrees an attribute
    run_in_distance/  the run-in distances within 1 % and 0.1 % (dimension ``within``):
                  distance, distance_s_star, uncertainty, low, high, mean_worn_depth,
                  rim_worn_depth, time, time_uncertainty, reached, each with ``units``
                  and ``long_name`` (:func:`transient.run_in_distance.distance_table`;
                  absent when the history lacks the figures)
    outline/      the face's outline, as :func:`steady.output.write_outline`
                  writes it (kind, area, its lengths; a mask's ``mask``)

Every variable carries the CF attributes ``units`` (udunits: ``"m"``,
``"Pa"``, ``"1"``; none for text and codes) and ``long_name``.  A field is
indexed ``[i, j]`` in memory, ``i`` along x (the grid of the outline,
:class:`steady.outline.FaceGrid`; ``n x n`` for a disk), and stored
transposed, ``(y, x)`` (:func:`steady.output.write_field`), so that
xarray draws x across.  Files of layouts 2 to 4 (the quantities as root
and group attributes with their unit in ``x_units``, the fields stored
``(nx, ny)``; layout 2 without coordinates, phase names and the problem's
own inputs) are read and resumed too.  Files written before the face
outlines (disks only) lack the group ``outline`` and the reference slope's
error and source: :func:`read_run` reads their outline as the disk of their
``radius`` attribute (None without it) and the source as eq. 12's.

Checksums
---------
Every dataset carries the attribute ``sha256``: the SHA-256 of its dtype,
shape and bytes and of its other attributes (except the dimension scales'
references, :data:`steady.safe_files.DIMENSION_SCALE_ATTRIBUTES`); every group, the
root included, carries in ``sha256`` the SHA-256 of its attributes
(:func:`steady.safe_files.dataset_digest`, :func:`~steady.safe_files.attributes_digest`).
:func:`read_run` verifies all of them, so that a flipped bit anywhere in
what a resumed run depends on (the state, the pressure, the counters, the
history, the snapshots, the inputs) is noticed, and raises
:class:`DamagedRunFileError` naming the first part that does not match (or
the reason the file cannot be read at all).  A file without a root
``sha256`` is read unverified.

Writers
-------
A run file has one writer at a time: :class:`steady.safe_files.RunLock`
holds an exclusive lock (:func:`fcntl.flock`) on ``RUN.h5.lock`` beside it,
which records the writer's process id; a second writer is refused at once
with :class:`~steady.safe_files.RunLockedError`.  The kernel drops the lock of a process that dies,
so a lock file left by a killed run is taken over (its pid is reported).
``write_run(..., backup=True)`` keeps the file it replaces as
``RUN.h5.prev`` (:func:`steady.safe_files.backup_path`): a checkpoint damaged after it was
written can be replaced by the one before it.  Without ``force``,
``write_run`` replaces only the file it is told it may (``replaces``, the
identity it returned for the previous checkpoint), so that a file another
writer put at the run's path meanwhile is refused, not replaced
(:func:`steady.safe_files.atomic_h5`).
"""

from __future__ import annotations

import dataclasses
import math
import os
import pathlib
import types

import h5py
import numpy as np

from steady.depth import DepthColumns
from steady.load_programme import LoadProgramme
from steady.outline import Circle
from steady.output import (
    CONVENTIONS,
    attach_scales,
    describe,
    field_from_file,
    read_outline,
    wear_long_names,
    write_field,
    write_grid_coordinates,
    write_outline,
    write_phase_names,
    write_quantity,
    write_record,
)
from steady.safe_files import (
    CHECKSUM_ATTRIBUTE,
    atomic_h5,
    attributes_digest,
    backup_path,
    dataset_digest,
    seal_groups,
)
from steady.sliding import sliding_file_attributes
from steady.wear import wear_file_attributes

from .result import (
    COATING_HISTORY_UNITS,
    DEPTH_HISTORY_UNITS,
    HISTORY_UNITS,
    PROGRAMME_HISTORY_UNITS,
    RunResult,
    RunState,
)
from .run_in_distance import COATING_EVENTS, coating_distance, distance_table

__all__ = [
    "FORMAT",
    "FORMAT_VERSION",
    "DamagedRunFileError",
    "history_cf",
    "problem_inputs",
    "read_run",
    "verify_run",
    "write_run",
]

#: ``format`` attribute of a run file.
FORMAT = "runin.transient"
#: Layout version of a run file (``format_version`` attribute).
FORMAT_VERSION = 5
#: Versions :func:`read_run` reads (2: without coordinates, phase names and
#: the problem's inputs; 2 and 3: the face's recession under the name
#: ``height``, :data:`_FORMER_DATASETS`; 2 to 4: the quantities as attributes,
#: the fields stored (nx, ny)).  A run of any of them resumes.
_READABLE_VERSIONS = (2, 3, 4, 5)
#: The first version that stores the quantities as variables and the fields (y, x).
_CF_VERSION = 5

# Root scalar attributes and their units.
_SCALARS = {
    "status": "", "message": "", "scheme": "", "distance": "m", "steps": "1",
    "rejected": "1", "failures": "1", "solves": "1", "iterations": "1", "wall_time": "s",
    "offset": "m", "approach": "m", "depth_scale": "m", "distance_scale": "m",
    "fast_distance": "m", "pixel_mean_pressure": "Pa", "reference_slope": "1",
}
# Root attributes of the result that files written before them lack: read as NaN (a sliding
# speed of NaN is none: None).  Files that name the distance scale run_in_distance are read too.
_LATER_SCALARS = {"steady_rms_slope": "1", "steady_rms_slope_error": "1", "sliding_speed": "m s-1"}
_FORMER_NAMES = {"run_in_distance": "distance_scale"}
# Datasets of layout versions 2 and 3 under the names layout 4 gives them: the face's
# recession (larger = deeper) was called its height.
_FORMER_DATASETS = {"state/height": "state/recession",
                    "state/initial_height": "state/initial_recession",
                    "state/previous_height": "state/previous_recession",
                    "snapshots/height": "snapshots/recession"}
# Root attributes of the state (RunState); a step absent is stored as NaN.
_OPTIONAL_SCALARS = {"previous_step": "m", "next_step": "m"}
# Root attributes of the state that files written before them lack: read as these defaults.
_LATER_STATE_SCALARS = {"jumps": ("1", 0)}
# Written with the outline; files of disks written before outlines lack them.
_REFERENCE_UNITS = {"reference_slope_error": "1", "scale": "m", "pixel_size": "m"}
# Long names of the root quantities (the wear law's and the outline's: steady.output).
_LONG_NAMES = {
    "status": "how the run ended: running, steady, stopped or failed",
    "distance": "sliding distance reached",
    "steps": "accepted steps", "rejected": "rejected steps", "failures": "failed step attempts",
    "solves": "contact solves", "iterations": "iterations of the contact solver",
    "wall_time": "computing time",
    "offset": "constant removed from the recession (the rigid part of the wear)",
    "approach": "rigid approach, in the frame of the recession",
    "depth_scale": "depth scale f*",
    "distance_scale": "run-in distance scale s* (not a distance the run took)",
    "fast_distance": "fastest relaxation distance h / (k_max E*)",
    "pixel_mean_pressure": "load over the face's pixel area",
    "reference_slope": "grad_f0, the rms slope of the homogeneous face of the outline under "
                       "the same load",
    "steady_rms_slope": "rms slope of the steady face",
    "steady_rms_slope_error": "error bar of steady_rms_slope",
    "sliding_speed": "sliding speed (NaN: none given)",
    "previous_step": "length of the last accepted step (NaN: none)",
    "next_step": "length of the next step (NaN: none)",
    "jumps": "jumps to the steady state so far",
    "reference_slope_error": "uncertainty of reference_slope (0 for a closed form)",
    "scale": "length scale L of the outline (a disk's radius)",
    "pixel_size": "side h of the grid's square pixels",
    "n": "pixels of the grid along the face's longer side",
    "normal_force": "normal force F_N",
    "E_star": "effective modulus E* of the counter-body",
    "thickness": "thickness of the counter-body's layer on a rigid flat",
    "poisson": "Poisson's ratio of the counter-body's layer",
}
# Quantities of the group history beside the history itself (layout 5 on; attributes before).
_HISTORY_RECORD = ("distance_scale", "load_breakpoints", "load_forces", "load_initial_force")
# History datasets that stay empty unless a companion run fills them
# (transient.spatial_error): left out of the file while empty (layout 5 on).
_EMPTY_UNLESS_FILLED = ("rms_slope_spatial_error", "companion_deviation_low",
                        "companion_deviation_high")
_DISK_SOURCE = "disk: 4 pbar / (pi E*) (eq. 12)"
# Root attributes that belong to the state (RunState) rather than to the result.
_STATE_SCALARS = ("offset", "approach")
_INTEGERS = ("steps", "rejected", "failures", "solves", "iterations")
_STRINGS = ("status", "message", "scheme")
_STATE_UNITS = {"recession": "m", "initial_recession": "m", "previous_recession": "m",
                "previous_rate": "1", "pressure_history": "Pa",
                "pressure_history_displacement": "m"}
_STATE_NAMES = {"recession": "recession of the face (worn depth plus the initial face's "
                             "recession; larger = deeper), minus offset",
                "initial_recession": "recession of the face the run started from (larger = "
                                     "deeper), NaN off the face",
                "previous_recession": "recession of the face at the previous step, minus "
                                      "offset (larger = deeper)",
                "previous_rate": "wear rate at the previous step (m of wear per m of sliding)",
                "pressure_history": "recent contact pressures (warm start of the contact solve)",
                "pressure_history_displacement": "their surface displacements K p"}
# State datasets every checkpoint has; the others are None before the first step.
_REQUIRED_STATE = ("recession", "initial_recession")


class DamagedRunFileError(ValueError):
    """A run file that cannot be trusted: unreadable, truncated, or failing its checksums.

    Attributes
    ----------
    path : pathlib.Path
        The file.
    """

    def __init__(self, path, reason):
        super().__init__(f"run file {str(path)!r} is damaged: {reason}")
        self.path = pathlib.Path(path)


# Snapshots of a finished or stopped run: byte shuffle then deflate (level 1), smaller and
# quicker than deflate alone (docs/benchmarks.md, "Run-in speed").
_SNAPSHOT_FILTERS = {"compression": "gzip", "compression_opts": 1, "shuffle": True}


def _put(group, name, value, unit, long_name=None, *, dims=(), **options):
    """Create a dataset with its CF ``units`` and ``long_name`` and its ``sha256``.

    ``unit`` None writes no ``units`` (text, codes); ``dims`` are the
    dimension scales of its leading axes (:func:`steady.output.attach_scales`).
    """
    ds = group.create_dataset(name, data=value, **options)
    describe(ds, unit, long_name or name.replace("_", " "))
    if ds.dtype.kind == "O":  # strings: digest them as a reader gets them (bytes)
        data = ds[()]
    else:
        data = np.asarray(value).astype(ds.dtype, copy=False).reshape(ds.shape)
    ds.attrs[CHECKSUM_ATTRIBUTE] = dataset_digest(data, dict(ds.attrs))
    attach_scales(ds, *dims)
    return ds


def history_cf(name):
    """CF attributes of a history dataset: ``(units, long_name)`` from :data:`HISTORY_UNITS`.

    ``HISTORY_UNITS`` gives a unit and, in parentheses, what the values are;
    a ``code`` has no unit (its meaning, the codes included, goes to the
    long name); a power is written without a caret (``"m3"``).

    Parameters
    ----------
    name : str
        A key of :data:`transient.result.HISTORY_UNITS`,
        :data:`transient.result.DEPTH_HISTORY_UNITS`,
        :data:`transient.result.COATING_HISTORY_UNITS` or
        :data:`transient.result.PROGRAMME_HISTORY_UNITS`.

    Returns
    -------
    units : str or None
    long_name : str

    Examples
    --------
    >>> history_cf("normalised_rms_slope")
    ('1', 'rms_slope / grad_f0')
    >>> history_cf("distance")
    ('m', 'sliding distance')
    """
    text = (HISTORY_UNITS.get(name) or DEPTH_HISTORY_UNITS.get(name)
            or COATING_HISTORY_UNITS.get(name) or PROGRAMME_HISTORY_UNITS[name])
    unit, _, meaning = text.partition(" (")
    meaning = meaning[:-1] if meaning.endswith(")") else meaning
    if not meaning:
        meaning = _HISTORY_NAMES.get(name, name.replace("_", " "))
    if unit == "code":
        return None, f"{name.replace('_', ' ')} code ({meaning})"
    return unit.replace("^", ""), meaning  # one spelling of powers: "m3", as "Pa-1"


def _per_relief(datasets):
    """Whether the file's ``face_deviation`` is relative to the steady relief (layouts <= 4)."""
    entry = datasets.get("history/face_deviation")
    if entry is None:
        return False
    text = entry[1].get("long_name", entry[1].get("units", ""))
    if isinstance(text, bytes):
        text = text.decode("utf-8", "replace")
    return "relief" in str(text)


#: History datasets of earlier layouts that are read no longer.
_RETIRED = ("face_deviation_spatial_error", "rms_slope_deviation_spatial_error")

# Long names of history datasets whose HISTORY_UNITS entry is a bare unit.
_HISTORY_NAMES = {"distance": "sliding distance", "step": "length of the step to this distance",
                  "peak_pressure": "largest contact pressure",
                  "contact_fraction": "fraction of the face's pixels in contact",
                  "approach": "rigid approach", "worn_volume": "volume worn off since the start",
                  "solves": "contact solves so far"}


def _quantity(group, name, value, unit, long_name=None, dims=()):
    """A quantity as a checksummed variable of ``group`` (:func:`steady.output.write_quantity`)."""
    return write_quantity(group, name, value, unit, long_name or name.replace("_", " "), dims,
                          put=_put)


def _field(group, name, value, unit, long_name, scales, **options):
    """A checksummed field, stored (..., y, x) (:func:`steady.output.write_field`)."""
    return write_field(group, name, value, unit, long_name, scales, put=_put, **options)


def _index(group, name, length, long_name):
    """An index ``0..length-1`` made the dimension scale ``name`` (a leading axis of fields)."""
    ds = _put(group, name, np.arange(length), "1", long_name)
    ds.make_scale(name)
    return ds


def problem_inputs(problem):
    """What a run file stores of the problem a run solved: root quantities and datasets.

    Parameters
    ----------
    problem : steady.problem.Problem

    Returns
    -------
    attrs : dict of str to (value, units)
        ``n``, ``normal_force`` (N), ``E_star`` (Pa), the wear law
        (:func:`steady.wear.wear_file_attributes`: ``wear_law_kind``,
        ``wear_law`` in words, and the law's own, for the power law
        ``wear_coefficients`` (Pa-m) and ``exponent``) and the sliding
        kinematics (:func:`steady.sliding.sliding_file_attributes`:
        ``sliding_kind`` and its keys, none for a translation) and the
        counter-body's layer (``thickness`` in m and ``poisson``, none for a
        half-space); a value with a unit is stored as a variable, text as an
        attribute.
    arrays : dict of str to ndarray
        ``phase``, the phase map (-1 off the face).
    names : tuple of str
        The phase names, phase 0 first.
    """
    attrs = {"n": (problem.n, "1"), "normal_force": (problem.normal_force, "N"),
             "E_star": (problem.E_star, "Pa"), **wear_file_attributes(problem.wear),
             **sliding_file_attributes(problem.sliding),
             **{name: (value, unit) for name, (value, unit, _)
                in problem.counterbody.file_attributes().items()}}
    return attrs, {"phase": np.asarray(problem.labels)}, tuple(problem.phase_names)


# -- writing ----------------------------------------------------------------
def write_run(path, result, *, attrs=None, quantities=None, arrays=None, comparison=None,
              backup=False, force=True, replaces=None, checked=False):
    """Write a run (or a checkpoint) to HDF5, atomically, replacing ``path``.

    The file holds the run's inputs when the result knows its problem (a
    result of :func:`transient.runin.run_in`): load, modulus, wear law,
    phase map, phase names and outline, whoever calls this function.

    Parameters
    ----------
    path : str or path-like
    result : transient.result.RunResult
    attrs : mapping of str to str, optional
        Extra root attributes (scene text, options); those whose value is
        None are left out.
    quantities : mapping of str to (value, str, str), optional
        Extra root quantities, ``name -> (value, units, long_name)``, each
        a variable (0-d for a scalar), replacing the run's own of the same
        name (e.g. the scene's ``normal_force``); those whose value is None
        are left out.
    arrays : mapping of str to ndarray, optional
        Extra root fields, shape (nx, ny) (e.g. ``phase``), replacing the
        problem's of the same name.
    comparison : transient.comparison.SteadyComparison, optional
        Stored in the group ``comparison``.
    backup : bool, optional
        Keep the file that ``path`` held as :func:`steady.safe_files.backup_path` (default
        False: it is replaced).
    force : bool, optional
        Replace whatever file ``path`` names (default True).  False: only
        the file ``replaces`` names, or none.
    replaces : steady.safe_files.FileIdentity, optional
        With ``force`` False: the file this one may replace, e.g. the
        identity this function returned for the previous checkpoint.
    checked : bool, optional
        ``path`` was checked before the run: a file found in the place of
        the expected one was written meanwhile (see
        :func:`steady.safe_files.atomic_h5`).

    Returns
    -------
    steady.safe_files.FileIdentity
        The identity of the file written.

    Raises
    ------
    OSError
        The file cannot be written; the message names ``path``.
    steady.safe_files.OutputAppearedError
        (a ``ValueError``) Without ``force``: ``path`` names another file
        than ``replaces`` (another writer wrote it); nothing is written.
    """
    writer = atomic_h5(path, format=FORMAT, version=FORMAT_VERSION, force=force,
                       replaces=replaces, checked=checked,
                       backup=backup_path(path) if backup else None)
    problem = getattr(result, "problem", None)
    inputs, input_arrays, names = ({}, {}, None) if problem is None else problem_inputs(problem)
    with writer as f:
        f.attrs["Conventions"] = CONVENTIONS
        scales = _write_coordinates(f, result, names)
        _write_root(f, result, inputs, quantities or {}, scales[2])
        if result.outline is not None:
            _write_outline(f, result)
        for name, value in (attrs or {}).items():
            if value is not None:
                f.attrs[name] = value
        _field(f, "worn_depth", result.worn_depth, "m", "depth worn off since the start, NaN "
               "off the face", scales[:2])
        # What RunResult.face gives, the run's face to compare with the steady one (ds.face).
        _field(f, "face", result.face, "m", "elevation of the worn face, approach - recession "
               "(the steady face's convention, K p on the contact), NaN off the face",
               scales[:2])
        _field(f, "pressure", result.pressure, "Pa", "contact pressure", scales[:2])
        for name, value in {**input_arrays, **(arrays or {})}.items():
            _field(f, name, value, "1", _ARRAY_NAMES.get(name, name.replace("_", " ")),
                   scales[:2])
        _write_state(f, result, scales[:2])
        _write_history(f, result, scales[2])
        _write_snapshots(f, result, scales[:2])
        if result.columns is not None:
            _write_columns(f, result, scales[:2])
        _write_run_in_distances(f, result)
        if comparison is not None:
            _write_comparison(f, comparison, scales[2])
        seal_groups(f)
    return writer.identity


# Long names of the input datasets the command and the problem store.
_ARRAY_NAMES = {"phase": "phase index, -1 off the face"}


def _write_root(f, result, inputs, quantities, phase_scale):
    """The result's and the state's root quantities, the problem's inputs, the caller's.

    Text (status, message, scheme, the wear law's name) goes to attributes.
    """
    record = {name: (getattr(result, name), unit or None) for name, unit in _SCALARS.items()}
    for name, unit in _OPTIONAL_SCALARS.items():
        value = getattr(result.state, name)
        record[name] = (np.nan if value is None else value, unit)
    for name, (unit, _) in _LATER_STATE_SCALARS.items():
        record[name] = (getattr(result.state, name), unit)
    for name, unit in _LATER_SCALARS.items():
        value = getattr(result, name)
        record[name] = (np.nan if value is None else value, unit)
    if result.outline is not None:
        values = {"reference_slope_error": result.reference_slope_error,
                  "scale": result.outline.scale, "pixel_size": result.pixel_size}
        record.update({name: (values[name], unit) for name, unit in _REFERENCE_UNITS.items()})
        record.update(result.outline.root_attributes())
    record.update(inputs)
    long_names = dict(_LONG_NAMES)
    problem = getattr(result, "problem", None)
    if problem is not None:
        long_names.update(wear_long_names(problem.wear))
    for name, (value, unit, long_name) in quantities.items():
        if value is not None:
            record[name] = (value, unit)
            long_names[name] = long_name
    write_record(f, record, phase_scale, put=_put, long_names=long_names)


def _write_coordinates(f, result, names):
    """Root datasets ``x``, ``y`` (m; None, None without an outline) and ``phase_name``.

    Returns the scales ``(x, y, phase_name)``, None for those not written.
    """
    x = y = phase = None
    if result.outline is not None:
        grid = result.outline.grid(max(result.shape))
        if grid.shape == result.shape:
            x, y = write_grid_coordinates(f, grid.x, grid.y, put=_put)
    if names is not None:
        phase = write_phase_names(f, names, put=_put)
    return x, y, phase


def _write_state(f, result, grid_scales):
    """The group ``state``: the arrays a resumed run needs, stored (..., y, x)."""
    st = f.create_group("state")
    st.attrs["description"] = "everything a resumed run needs (face up to offset)"
    kept = None
    for name, unit in _STATE_UNITS.items():
        value = getattr(result.state, name)
        if value is None:
            continue
        leading = ()
        if np.ndim(value) == 3:
            if kept is None:
                kept = _index(st, "kept_solve", len(value),
                              "index of a kept contact solve (warm start), newest first")
            leading = (kept,)
        _field(st, name, value, unit, _STATE_NAMES[name], (*leading, *grid_scales))


def _write_history(f, result, phase_scale=None):
    """The group ``history``: one dataset per recorded quantity along ``distance``.

    A quantity per phase (``phase_fraction``, shape (K, P)) is also along
    ``phase_scale``, the root's ``phase_name``.  A dataset still empty in
    a history that is not (a spatial error no companion run filled) is
    left out: a dimension of length 0 would leave xarray no row to show.
    """
    hist = f.create_group("history")
    _quantity(hist, "distance_scale", result.distance_scale, "m", _LONG_NAMES["distance_scale"])
    distance = None
    if "distance" in result.history:
        distance = _put(hist, "distance", result.history["distance"], *history_cf("distance"))
        distance.make_scale("distance")
    length = len(result.history.get("distance", ()))
    for name, value in result.history.items():
        if name == "distance" or (name in _EMPTY_UNLESS_FILLED and np.size(value) == 0):
            continue
        dims = (distance,) if np.ndim(value) < 2 else (distance, phase_scale)
        if np.ndim(value) == 1 and (distance is None or len(value) != length):
            dims = ()  # a dimension of its own
        _quantity(hist, name, value, *history_cf(name), dims=dims)
    _write_load_programme(hist, result.load_programme)


def _write_load_programme(group, programme):
    """A load programme: breakpoints (m, a dimension scale), forces (N), initial force (N)."""
    if programme is None:
        return
    breakpoints = _quantity(group, "load_breakpoints", np.array(programme.breakpoints), "m",
                            "distance s_i from which the load programme's force F_i holds")
    _quantity(group, "load_forces", np.array(programme.forces), "N",
              "force F_i of the load programme from s_i on", dims=(breakpoints,))
    _quantity(group, "load_initial_force", programme.initial_force, "N",
              "normal force before the load programme's first breakpoint")


def _read_load_programme(values):
    """The :class:`LoadProgramme` of :func:`_write_load_programme`'s values, or None."""
    if "load_breakpoints" not in values:
        return None
    pairs = zip(np.ravel(values["load_breakpoints"]), np.ravel(values["load_forces"]),
                strict=True)
    return LoadProgramme(float(values["load_initial_force"]), tuple(pairs))


def _write_snapshots(f, result, grid_scales):
    """The group ``snapshots``: faces and pressures at chosen distances."""
    snaps = f.create_group("snapshots")
    distance = _put(snaps, "distance", result.snapshot_distance, "m",
                    "sliding distance of the snapshot")
    distance.make_scale("distance")
    # A checkpoint is rewritten whole every few seconds: compressing its
    # snapshots each time would cost more than the rest of the file.
    packed = {} if result.status == "running" else _SNAPSHOT_FILTERS
    scales = (distance, *grid_scales)
    _field(snaps, "recession", result.snapshot_recession, "m", "recession of the face: worn "
           "depth plus the initial face's recession (larger = deeper), NaN off the face",
           scales, **packed)
    _field(snaps, "pressure", result.snapshot_pressure, "Pa", "contact pressure", scales,
           **packed)
    sections = result.snapshot_sections
    if sections is not None:
        _field(snaps, "section", sections.astype(_section_dtype(result.columns)), "1",
               "phase index of the section at the worn depth, -1 off the face", scales,
               **packed)
    programme = result.load_programme
    if programme is not None:
        _quantity(snaps, "force", np.array([programme.force_at(s)
                                            for s in result.snapshot_distance], dtype=float),
                  "N", "normal force of the load programme at the snapshot", dims=(distance,))
        _write_load_programme(snaps, programme)


def _section_dtype(columns):
    """The smallest signed integer type of the phase indices: int8, or int16 beyond 127 phases."""
    return np.int8 if columns.n_phases <= np.iinfo(np.int8).max else np.int16


def _write_columns(f, result, grid_scales):
    """The group ``columns`` of a depth run (not of a checkpoint) and its coating distances.

    ``interfaces`` (interface, y, x) m and ``phases`` (segment, y, x) of
    :class:`steady.depth.DepthColumns` (``(S, nx, ny)`` and ``(S + 1, nx,
    ny)`` in memory), the 0-d ``n_phases``; the root quantities
    ``coating_<event>_distance`` (m) and ``..._distance_s_star`` (1) and
    the attribute ``..._reason`` (text, "" when reached) for each event of
    :data:`transient.run_in_distance.COATING_EVENTS` (NaN with the reason
    when there is no coating or the event did not happen).  A checkpoint
    has the root's but not the group (compressed, it would cost more than
    the rest of the file; the resumed run's problem has the columns), but
    their digest, ``columns_sha256`` (:attr:`steady.depth.DepthColumns.digest`),
    which a resumed run's columns must match.
    """
    columns = result.columns
    for event in COATING_EVENTS:
        found = coating_distance(result, event)
        words = event.replace("_", " ")
        _quantity(f, f"coating_{event}_distance", found.distance_m, "m",
                  f"sliding distance at which the coating is {words} (NaN: not reached)")
        _quantity(f, f"coating_{event}_distance_s_star", found.distance_s_star, "1",
                  f"the same over s*: the coating {words}")
        f.attrs[f"coating_{event}_reason"] = found.reason
    if result.status == "running":
        # A checkpoint is rewritten every few seconds; the scene rebuilds the columns.
        f.attrs["columns_sha256"] = columns.digest
        return
    g = f.create_group("columns")
    g.attrs["description"] = ("the phase below every face pixel as a function of the worn depth "
                              "(steady.depth.DepthColumns)")
    _quantity(g, "n_phases", columns.n_phases, "1", "number of phases")
    interface = _index(g, "interface", len(columns.interfaces),
                       "index of the interface below a pixel, shallowest first")
    segment = _index(g, "segment", len(columns.phases),
                     "index of the segment between interfaces, from the face down")
    _field(g, "interfaces", columns.interfaces, "m", "depths of the phase changes below each "
           "pixel, ascending, inf beyond the pixel's last", (interface, *grid_scales),
           **_SNAPSHOT_FILTERS)
    _field(g, "phases", columns.phases.astype(_section_dtype(columns)), "1",
           "phase index of each segment between interfaces, -1 off the face",
           (segment, *grid_scales), **_SNAPSHOT_FILTERS)


def _read_columns(path, datasets, groups):
    """The :class:`steady.depth.DepthColumns` of the group ``columns``, or None without it."""
    if "columns/interfaces" not in datasets:
        return None
    try:
        return DepthColumns(datasets["columns/interfaces"][0],
                            datasets["columns/phases"][0].astype(np.int64),
                            int(groups["columns"]["n_phases"]))
    except (KeyError, TypeError, ValueError) as err:
        raise DamagedRunFileError(path, f"its columns are malformed ({err})") from None


# The comparison's long names and units (Pa for its arrays, one value per phase; 1 for the
# rest but the lengths); a flag is an attribute.
_COMPARISON_NAMES = {
    "face_error": "max |face - f_inf| over the face (best constant removed) / relief of f_inf",
    "face_rms_error": "rms of face - f_inf over the face (least-squares constant removed) / "
                      "relief of f_inf",
    "rms_slope": "rms slope of the run's final face",
    "rms_slope_uncertainty": "error bar of rms_slope",
    "steady_rms_slope": "rms slope of the steady face f_inf",
    "steady_rms_slope_uncertainty": "error bar of steady_rms_slope",
    "rms_slope_error": "rms_slope / steady_rms_slope - 1",
    "rms_slope_plain": "plain pixel rms slope of the run's final face",
    "steady_rms_slope_plain": "plain pixel rms slope of f_inf",
    "rms_height": "rms height of the run's final face about its least-squares plane",
    "steady_rms_height": "rms height of f_inf about its least-squares plane",
    "phase_pressures": "mean pressure on each phase, run",
    "steady_phase_pressures": "pressure on each phase, steady state (eq. 7)",
    "phase_pressure_error": "max_i |p_i / p_i,steady - 1|",
}
_COMPARISON_UNITS = {"rms_height": "m", "steady_rms_height": "m"}


def _write_comparison(f, comparison, phase_scale):
    """The group ``comparison``: :class:`transient.comparison.SteadyComparison`."""
    g = f.create_group("comparison")
    for fld in dataclasses.fields(comparison):
        value = getattr(comparison, fld.name)
        long_name = _COMPARISON_NAMES.get(fld.name, fld.name.replace("_", " "))
        if isinstance(value, np.ndarray):
            _quantity(g, fld.name, value, "Pa", long_name, dims=(phase_scale,))
        elif isinstance(value, (bool, np.bool_)):
            g.attrs[fld.name] = value
        else:
            _quantity(g, fld.name, value, _COMPARISON_UNITS.get(fld.name, "1"), long_name)


def _write_run_in_distances(f, result):
    """The group ``run_in_distance`` (:func:`transient.run_in_distance.distance_table`)."""
    table = distance_table(result)
    if table:
        g = f.create_group("run_in_distance")
        g.attrs["long_name"] = ("run-in distances: where the rms slope and the face stay within "
                                "each tolerance of the steady state (docs/model.md)")
        within = _put(g, "within", *table.pop("within"))
        within.make_scale("within")
        for name, (value, unit, long_name) in table.items():
            _put(g, name, value, unit, long_name, dims=(within,))


def _write_outline(f, result):
    """The outline group and the reference slope's source (the root's quantities: _write_root)."""
    f.attrs["reference_slope_source"] = result.reference_slope_source
    group = f.create_group("outline")
    write_outline(group, result.outline)
    for ds in group.values():  # a mask's pixels and the lengths: checksummed like every dataset
        ds.attrs[CHECKSUM_ATTRIBUTE] = dataset_digest(ds[()], dict(ds.attrs))


def _read_outline(path, datasets, groups, root):
    """The outline of a run file: its group, else the disk of ``radius``, else None."""
    if "outline" not in groups:
        radius = _plain(root.get("radius"))
        if isinstance(radius, (int, float)) and math.isfinite(radius) and radius > 0:
            return Circle(float(radius))
        return None
    # read_outline reads an h5py group: give it a view of what was loaded (the fields
    # already in the library's order).
    own = {name[len("outline/"):]: value for name, (value, _) in datasets.items()
           if name.startswith("outline/")}
    try:
        return read_outline(_LoadedGroup(groups["outline"], own), stored_yx=False)
    except (KeyError, TypeError, ValueError) as err:
        raise DamagedRunFileError(path, f"its outline cannot be read ({err})") from None


class _LoadedGroup:
    """A loaded group's attributes and datasets, as :func:`steady.output.read_outline` reads."""

    def __init__(self, attrs, datasets):
        self.attrs = attrs
        self._datasets = datasets

    def __getitem__(self, name):
        return _LoadedDataset(self._datasets[name])

    def __iter__(self):
        return iter(self._datasets)


class _LoadedDataset:
    def __init__(self, value):
        self._value = value

    def __getitem__(self, key):
        return self._value[key]


# -- reading ----------------------------------------------------------------
def _load(f):
    """Every dataset (values and attributes) and every group's attributes, by path."""
    datasets, groups = {}, {"": dict(f.attrs)}

    def visit(name, obj):
        if isinstance(obj, h5py.Dataset):
            datasets[name] = (obj[()], dict(obj.attrs))
        else:
            groups[name] = dict(obj.attrs)

    f.visititems(visit)
    return datasets, groups


def _verify(path, datasets, groups):
    """Raise :class:`DamagedRunFileError` for the first part that fails its checksum."""
    for name, (data, attrs) in sorted(datasets.items()):
        stored = attrs.get(CHECKSUM_ATTRIBUTE)
        if stored is None or dataset_digest(data, attrs) != stored:
            raise DamagedRunFileError(path, f"dataset {name!r} does not match its checksum")
    for name, attrs in sorted(groups.items()):
        stored = attrs.get(CHECKSUM_ATTRIBUTE)
        if stored is None or attributes_digest(attrs) != stored:
            what = "the root attributes" if not name else f"the attributes of group {name!r}"
            raise DamagedRunFileError(path, f"{what} do not match their checksum")


def _plain(value):
    return value.item() if isinstance(value, np.generic) else value


def verify_run(path):
    """Check every checksum of a run file, one dataset at a time.

    What :func:`read_run` verifies, without holding the whole file in
    memory (the largest dataset at most): for a file just written, whose
    contents are still in memory.

    Parameters
    ----------
    path : str or path-like

    Raises
    ------
    DamagedRunFileError
        The file cannot be read, is not a run file, carries no checksums,
        or a part of it does not match its checksum (the message names it).
    """
    path = pathlib.Path(path)
    damage = (OSError, RuntimeError, KeyError, TypeError, IndexError, ValueError)
    try:
        with h5py.File(path, "r") as f:
            if _plain(f.attrs.get("format")) != FORMAT:
                raise DamagedRunFileError(path, "it is not a run file")
            if CHECKSUM_ATTRIBUTE not in f.attrs:
                raise DamagedRunFileError(path, "it carries no checksums")
            names = []
            f.visit(names.append)
            for name in ["", *sorted(names)]:
                obj = f[name] if name else f
                attrs = dict(obj.attrs)
                stored = attrs.get(CHECKSUM_ATTRIBUTE)
                if isinstance(obj, h5py.Dataset):
                    if stored is None or dataset_digest(obj[()], attrs) != stored:
                        raise DamagedRunFileError(
                            path, f"dataset {name!r} does not match its checksum")
                elif stored is None or attributes_digest(attrs) != stored:
                    what = "the root attributes" if not name else f"the attributes of group " \
                                                                   f"{name!r}"
                    raise DamagedRunFileError(path, f"{what} do not match their checksum")
    except damage as err:
        if isinstance(err, DamagedRunFileError):
            raise
        raise DamagedRunFileError(path, f"cannot be read ({str(err)[:200]})") from None


def read_run(path):
    """Read a run file written by :func:`write_run`, verifying its checksums.

    Parameters
    ----------
    path : str or path-like

    Returns
    -------
    result : transient.result.RunResult
    attrs : dict
        All root attributes and, by name, the root's quantities (its 0-d
        variables and those along ``phase_name``, stored as attributes
        before layout 5); ``attrs["sha256"]`` absent: an unverified file
        without checksums.
    arrays : dict
        Root datasets other than ``worn_depth``, ``face``, ``pressure``,
        ``x`` and ``y``, fields indexed ``[i, j]``.

    Raises
    ------
    DamagedRunFileError
        The file is empty, truncated, unreadable or fails a checksum, or
        lacks part of the state (a :class:`ValueError`).
    FileNotFoundError
        The file does not exist.
    ValueError
        A directory, not a run file (another ``format``), or an unknown
        layout version.
    """
    path = pathlib.Path(path)
    if not os.path.lexists(path):  # a loop of links is there, and named as one
        raise FileNotFoundError(f"run file {str(path)!r} does not exist")
    if not path.is_file():
        raise ValueError(f"run file {str(path)!r} is not a regular file")
    if path.stat().st_size == 0:
        raise DamagedRunFileError(path, "the file is empty (0 bytes)")
    # h5py reports damage with many exception types; these are all it raises for it.
    damage = (OSError, RuntimeError, KeyError, TypeError, IndexError, ValueError)
    try:
        if not h5py.is_hdf5(path):
            raise DamagedRunFileError(path, "no HDF5 signature (not an HDF5 file)")
        f = h5py.File(path, "r")
    except damage as err:
        if isinstance(err, DamagedRunFileError):
            raise
        raise DamagedRunFileError(path, f"cannot be opened ({str(err)[:200]})") from None
    with f:
        try:
            fmt = _plain(f.attrs.get("format"))
            version = _plain(f.attrs.get("format_version", -1))
        except damage as err:
            raise DamagedRunFileError(path, f"cannot be read ({str(err)[:200]})") from None
        if fmt != FORMAT:
            raise ValueError(f"{str(path)!r} is not a run file (format {fmt!r}, expected "
                             f"{FORMAT!r})")
        if not isinstance(version, (int, np.integer)) or int(version) not in _READABLE_VERSIONS:
            raise ValueError(f"{str(path)!r} has layout version {version!r}, expected "
                             f"{' or '.join(map(str, _READABLE_VERSIONS))}")
        try:
            datasets, groups = _load(f)
        except damage as err:
            raise DamagedRunFileError(path, f"cannot be read ({str(err)[:200]})") from None
    if CHECKSUM_ATTRIBUTE in groups[""]:
        _verify(path, datasets, groups)
    if int(version) >= _CF_VERSION:
        datasets, groups = _as_attributes(datasets, groups)
    return _result(path, datasets, groups)


def _as_attributes(datasets, groups):
    """The contents of a file of layout 5 on as the earlier layouts held them.

    Every 0-d variable, the root's quantities of one dimension (but its
    coordinates) and the load programme among the attributes of their
    group; every field back in the library's order ``[..., i, j]``; the
    history's datasets left out while empty, empty again.
    """
    datasets, groups = dict(datasets), {name: dict(attrs) for name, attrs in groups.items()}
    for name, (value, attrs) in list(datasets.items()):
        group, _, own = name.rpartition("/")
        quantity = (np.ndim(value) == 0 or own in _HISTORY_RECORD
                    or (not group and np.ndim(value) == 1 and own not in ("x", "y", "phase_name")))
        if quantity:
            del datasets[name]
            groups[group][own] = value.decode("utf-8") if isinstance(value, bytes) else value
        elif np.ndim(value) >= 2 and group != "history":
            datasets[name] = (field_from_file(value), attrs)
    if "history/distance" in datasets:
        for name in _EMPTY_UNLESS_FILLED:
            datasets.setdefault(f"history/{name}", (np.zeros(0), {}))
    return datasets, groups


def _result(path, datasets, groups):
    """The :class:`RunResult` of a run file's contents."""
    root = dict(groups[""])
    for old, new in _FORMER_NAMES.items():
        if new not in root and old in root:
            root[new] = root[old]
    for old, new in _FORMER_DATASETS.items():
        if new not in datasets and old in datasets:
            datasets[new] = datasets.pop(old)
    needed = ["pressure", "history/distance", "snapshots/distance", "snapshots/recession",
              "snapshots/pressure"] + [f"state/{name}" for name in _REQUIRED_STATE]
    missing = [name for name in needed if name not in datasets]
    missing += [name for name in (*_SCALARS, *_OPTIONAL_SCALARS) if name not in root]
    if missing:
        raise DamagedRunFileError(path, f"it lacks {missing[0]!r}")
    attrs = {k: _plain(v) for k, v in root.items()}
    kw = {name: attrs[name] for name in _SCALARS if name not in _STATE_SCALARS}
    state = {name: attrs[name] for name in _STATE_SCALARS}
    try:
        for name in _INTEGERS:
            kw[name] = int(kw[name])
        for name in _STRINGS:
            kw[name] = str(kw[name])
        for name in _OPTIONAL_SCALARS:
            v = float(attrs[name])
            state[name] = None if math.isnan(v) else v
        for name, (_, default) in _LATER_STATE_SCALARS.items():
            value = attrs.get(name, default)
            if int(value) != value or value < 0:
                raise ValueError(f"{name} = {value!r} is not a count")
            state[name] = int(value)
        for name in _LATER_SCALARS:
            kw[name] = float(attrs.get(name, math.nan))
    except (TypeError, ValueError) as err:
        raise DamagedRunFileError(path, f"a root attribute is malformed ({err})") from None
    if math.isnan(kw["sliding_speed"]):
        kw["sliding_speed"] = None
    state.update({name: datasets[f"state/{name}"][0] if f"state/{name}" in datasets else None
                  for name in _STATE_UNITS})
    # The first-order companion errors of the deviations (layouts up to 4) are no longer
    # what the run-in distance reads (the companions' own deviations are): left unread.
    history = {name[len("history/"):]: value for name, (value, _) in datasets.items()
               if name.startswith("history/") and name[len("history/"):] not in _RETIRED}
    outline = _read_outline(path, datasets, groups, root)
    shape = np.shape(datasets["pressure"][0])
    if outline is not None:
        try:
            expected = outline.grid_shape(max(shape)) if len(shape) == 2 else None
        except ValueError:
            expected = None
        if expected != shape:
            raise DamagedRunFileError(path, f"its pressure of shape {shape} is not on a grid of "
                                            f"its {outline.describe()}")
    try:
        ref_error = float(attrs.get("reference_slope_error", 0.0))
    except (TypeError, ValueError) as err:
        raise DamagedRunFileError(path, f"a root attribute is malformed ({err})") from None
    source = attrs.get("reference_slope_source")
    if isinstance(source, bytes):
        source = source.decode("utf-8", "replace")
    if source is None:  # a file of a disk written before the outlines, or none at all
        source = _DISK_SOURCE if outline is not None and "outline" not in groups else ""
    result = RunResult(
        **kw, state=RunState(**state, pressure=datasets["pressure"][0]),
        history=types.MappingProxyType(history),
        snapshot_distance=datasets["snapshots/distance"][0],
        snapshot_recession=datasets["snapshots/recession"][0],
        snapshot_pressure=datasets["snapshots/pressure"][0],
        outline=outline, reference_slope_error=ref_error,
        reference_slope_source=str(source),
        load_programme=_read_load_programme(groups.get("history", {})),
        columns=_read_columns(path, datasets, groups),
        face_deviation_per_relief=_per_relief(datasets))
    arrays = {name: value for name, (value, _) in datasets.items()
              if "/" not in name and name not in ("worn_depth", "face", "pressure", "x", "y")}
    return result, attrs, arrays
