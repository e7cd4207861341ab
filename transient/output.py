"""HDF5 run files (layout ``runin.transient``, version 3), checksummed and written by one writer.

A run file holds a run-in, finished or in progress (a checkpoint): the
state a resumed run needs (:class:`transient.result.RunState`), the
history, the snapshots, the inputs that identify the run and, once the run
is steady, its agreement with the steady face.  It is written whole and
atomically by the project's one HDF5 writer (:func:`steady.safe_files.atomic_h5`),
so a reader never sees half a file and a killed run leaves its last
checkpoint intact.  It opens in xarray (``xarray.open_dataset(path,
engine="h5netcdf")``, ``group="history"`` or ``"snapshots"``) as labelled
arrays; docs/files.md lists every dataset and attribute.

Layout (root group)::

    attributes    format "runin.transient", format_version 3
                  status, message, scheme, distance (m), steps, rejected,
                  failures, solves, iterations, wall_time (s), offset (m),
                  approach (m), depth_scale (m), distance_scale (m),
                  fast_distance (m), pixel_mean_pressure (Pa),
                  reference_slope, steady_rms_slope, steady_rms_slope_error,
                  sliding_speed (m s-1, NaN if none), previous_step (m, NaN if none),
                  next_step (m, NaN if none), jumps (jumps to the steady
                  state so far; files written before it was stored lack
                  it and are read as 0);
                  the problem's inputs (:func:`problem_inputs`, when the
                  result knows its problem): n, normal_force (N), E_star
                  (Pa), the wear law (wear_law_kind, wear_law in words and
                  the law's own attributes: exponent, wear_coefficients
                  (Pa-m) for the power law);
                  the caller's input attributes (scene...; an attribute
                  given as None is left out);
                  with the face's outline known (every run since version 2):
                  reference_slope_error, reference_slope_source (where
                  grad_f0 comes from, in words), scale (m, the outline's
                  L), pixel_size (m) and, for a disk only, radius (m)
    x, y          (nx,), (ny,) m: pixel centres, the dimension scales of
                  every (nx, ny) axis pair
    phase_name    (P,) the phase names: the dimension scale ``phase_name``
    worn_depth    (nx, ny) m, NaN off the face
    pressure      (nx, ny) Pa
    phase         (nx, ny) the phase map, and the caller's input datasets
    state/        recession, initial_recession, previous_recession, previous_rate,
                  pressure_history, pressure_history_displacement
    history/      one dataset per :data:`transient.result.HISTORY_UNITS` name,
                  along the dimension scale ``distance`` (m); attribute
                  distance_scale (s*, m); a depth run's also
                  :data:`transient.result.DEPTH_HISTORY_UNITS` (phase_fraction
                  also along ``phase_name``) and, under a coating,
                  :data:`transient.result.COATING_HISTORY_UNITS`
    snapshots/    distance (k,) m (a dimension scale), recession (k, nx, ny) m,
                  pressure (k, nx, ny) Pa (byte shuffle and deflate, except
                  in a checkpoint); for a depth run section (k, nx, ny)
                  int8, the phase map of the section at the worn depth
    columns/      a depth run only, not in a checkpoint (the problem's
                  :class:`steady.depth.DepthColumns`): interfaces
                  (S, nx, ny) m, phases (S + 1, nx, ny) int8, attribute
                  n_phases; with the root attributes
                  coating_worn_through_distance, coating_gone_distance (m),
                  their ..._s_star (1) and ..._reason (text)
    comparison/   :class:`transient.comparison.SteadyComparison` (steady runs)
    run_in_distance/  the run-in distances within 1 % and 0.1 % (dimension ``within``):
                  distance, distance_s_star, uncertainty, low, high, mean_worn_depth,
                  rim_worn_depth, time, time_uncertainty, reached, each with ``units``
                  and ``long_name`` (:func:`transient.run_in_distance.distance_table`;
                  absent when the history lacks the figures)
    outline/      the face's outline, as :func:`steady.output.write_outline`
                  writes it (kind, area, its lengths; a mask's ``mask``)

Every dataset carries the CF attributes ``units`` (udunits: ``"m"``,
``"Pa"``, ``"1"``; none for text and codes) and ``long_name``; the unit of
a root attribute ``x`` is the udunits string ``x_units``.  Arrays are
``(nx, ny)``, the grid of the outline (:class:`steady.outline.FaceGrid`;
``n x n`` for a disk).  Version 2 files (without coordinates, phase names
and the problem's own inputs) are read too.  Files written before the face
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
import pathlib
import types

import h5py
import numpy as np

from steady.depth import DepthColumns
from steady.load_programme import LoadProgramme
from steady.outline import Circle
from steady.output import (
    attach_scales,
    describe,
    read_outline,
    write_grid_coordinates,
    write_outline,
    write_phase_names,
)
from steady.safe_files import (
    CHECKSUM_ATTRIBUTE,
    atomic_h5,
    attributes_digest,
    backup_path,
    dataset_digest,
    seal_groups,
)
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
FORMAT_VERSION = 4
#: Versions :func:`read_run` reads (2: without coordinates, phase names and
#: the problem's inputs; 2 and 3: the face's recession under the name
#: ``height``, :data:`_FORMER_DATASETS`).  A run of any of them resumes.
_READABLE_VERSIONS = (2, 3, 4)

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


# Long names of history datasets whose HISTORY_UNITS entry is a bare unit.
_HISTORY_NAMES = {"distance": "sliding distance", "step": "length of the step to this distance",
                  "peak_pressure": "largest contact pressure",
                  "contact_fraction": "fraction of the face's pixels in contact",
                  "approach": "rigid approach", "worn_volume": "volume worn off since the start",
                  "solves": "contact solves so far"}


def _attribute(attrs, name, value, unit):
    """Root attribute ``name`` and, for a quantity, its udunits unit in ``name_units``."""
    attrs[name] = value
    if unit is not None:
        attrs[f"{name}_units"] = unit


def problem_inputs(problem):
    """What a run file stores of the problem a run solved: root attributes and datasets.

    Parameters
    ----------
    problem : steady.problem.Problem

    Returns
    -------
    attrs : dict of str to (value, units)
        ``n``, ``normal_force`` (N), ``E_star`` (Pa) and the wear law
        (:func:`steady.wear.wear_file_attributes`: ``wear_law_kind``,
        ``wear_law`` in words, and the law's own, for the power law
        ``wear_coefficients`` (Pa-m) and ``exponent``).
    arrays : dict of str to ndarray
        ``phase``, the phase map (-1 off the face).
    names : tuple of str
        The phase names, phase 0 first.
    """
    attrs = {"n": (problem.n, "1"), "normal_force": (problem.normal_force, "N"),
             "E_star": (problem.E_star, "Pa"), **wear_file_attributes(problem.wear)}
    return attrs, {"phase": np.asarray(problem.labels)}, tuple(problem.phase_names)


# -- writing ----------------------------------------------------------------
def write_run(path, result, *, attrs=None, arrays=None, comparison=None, backup=False,
              force=True, replaces=None, checked=False):
    """Write a run (or a checkpoint) to HDF5, atomically, replacing ``path``.

    The file holds the run's inputs when the result knows its problem (a
    result of :func:`transient.runin.run_in`): load, modulus, wear law,
    phase map, phase names and outline, whoever calls this function.

    Parameters
    ----------
    path : str or path-like
    result : transient.result.RunResult
    attrs : mapping, optional
        Extra root attributes (scene text, parameters); those whose value is
        None are left out.  They replace the problem's of the same name.
    arrays : mapping of str to ndarray, optional
        Extra root datasets (e.g. ``phase``), replacing the problem's of
        the same name.
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
        _write_scalars(f, result)
        for name, (value, unit) in inputs.items():
            _attribute(f.attrs, name, value, unit)
        if result.outline is not None:
            _write_outline(f, result)
        for name, value in (attrs or {}).items():
            if value is not None:
                f.attrs[name] = value
        scales = _write_coordinates(f, result, names)
        _put(f, "worn_depth", result.worn_depth, "m", "depth worn off since the start, NaN "
             "off the face", dims=scales[:2])
        _put(f, "pressure", result.pressure, "Pa", "contact pressure", dims=scales[:2])
        for name, value in {**input_arrays, **(arrays or {})}.items():
            _put(f, name, value, "1", _ARRAY_NAMES.get(name), dims=scales[:2])
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


def _write_scalars(f, result):
    """The result's and the state's root attributes, each with its unit."""
    for name, unit in _SCALARS.items():
        _attribute(f.attrs, name, getattr(result, name), unit or None)
    for name, unit in _OPTIONAL_SCALARS.items():
        value = getattr(result.state, name)
        _attribute(f.attrs, name, np.nan if value is None else value, unit)
    for name, (unit, _) in _LATER_STATE_SCALARS.items():
        _attribute(f.attrs, name, getattr(result.state, name), unit)
    for name, unit in _LATER_SCALARS.items():
        value = getattr(result, name)
        _attribute(f.attrs, name, np.nan if value is None else value, unit)


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
    """The group ``state``: the arrays a resumed run needs."""
    st = f.create_group("state")
    st.attrs["description"] = "everything a resumed run needs (face up to offset)"
    for name, unit in _STATE_UNITS.items():
        value = getattr(result.state, name)
        if value is not None:
            dims = grid_scales if np.ndim(value) == 2 else (None, *grid_scales)
            _put(st, name, value, unit, _STATE_NAMES[name], dims=dims)


def _write_history(f, result, phase_scale=None):
    """The group ``history``: one dataset per recorded quantity along ``distance``.

    A quantity per phase (``phase_fraction``, shape (K, P)) is also along
    ``phase_scale``, the root's ``phase_name``.
    """
    hist = f.create_group("history")
    _attribute(hist.attrs, "distance_scale", result.distance_scale, "m")
    distance = None
    if "distance" in result.history:
        distance = _put(hist, "distance", result.history["distance"], *history_cf("distance"))
        distance.make_scale("distance")
    for name, value in result.history.items():
        if name == "distance":
            continue
        dims = (distance,) if np.ndim(value) < 2 else (distance, phase_scale)
        ds = _put(hist, name, value, *history_cf(name), dims=dims)
        if np.ndim(value) == 1 and (distance is None or len(value) != len(distance)):
            ds.make_scale(name)  # e.g. an empty spatial error: a dimension of its own
    _write_load_programme(hist.attrs, result.load_programme)


def _write_load_programme(attrs, programme):
    """A load programme's breakpoints (m), forces (N) and initial force as attributes."""
    if programme is None:
        return
    _attribute(attrs, "load_breakpoints", np.array(programme.breakpoints), "m")
    _attribute(attrs, "load_forces", np.array(programme.forces), "N")
    _attribute(attrs, "load_initial_force", programme.initial_force, "N")


def _read_load_programme(attrs):
    """The :class:`LoadProgramme` of :func:`_write_load_programme`'s attributes, or None."""
    if "load_breakpoints" not in attrs:
        return None
    pairs = zip(np.ravel(attrs["load_breakpoints"]), np.ravel(attrs["load_forces"]), strict=True)
    return LoadProgramme(float(attrs["load_initial_force"]), tuple(pairs))


def _write_snapshots(f, result, grid_scales):
    """The group ``snapshots``: faces and pressures at chosen distances."""
    snaps = f.create_group("snapshots")
    distance = _put(snaps, "distance", result.snapshot_distance, "m",
                    "sliding distance of the snapshot")
    distance.make_scale("distance")
    # A checkpoint is rewritten whole every few seconds: compressing its
    # snapshots each time would cost more than the rest of the file.
    packed = {} if result.status == "running" else _SNAPSHOT_FILTERS
    _put(snaps, "recession", result.snapshot_recession, "m", "recession of the face: worn depth "
         "plus the initial face's recession (larger = deeper), NaN off the face",
         dims=(distance, *grid_scales), **packed)
    _put(snaps, "pressure", result.snapshot_pressure, "Pa", "contact pressure",
         dims=(distance, *grid_scales), **packed)
    sections = result.snapshot_sections
    if sections is not None:
        _put(snaps, "section", sections.astype(_section_dtype(result.columns)), "1",
             "phase index of the section at the worn depth, -1 off the face",
             dims=(distance, *grid_scales), **packed)
    programme = result.load_programme
    if programme is not None:
        _put(snaps, "force", np.array([programme.force_at(s) for s in result.snapshot_distance],
                                      dtype=float),
             "N", "normal force of the load programme at the snapshot", dims=(distance,))
        _write_load_programme(snaps.attrs, programme)


def _section_dtype(columns):
    """The smallest signed integer type of the phase indices: int8, or int16 beyond 127 phases."""
    return np.int8 if columns.n_phases <= np.iinfo(np.int8).max else np.int16


def _write_columns(f, result, grid_scales):
    """The group ``columns`` of a depth run (not of a checkpoint) and its coating distances.

    ``interfaces`` (S, nx, ny) m and ``phases`` (S + 1, nx, ny) of
    :class:`steady.depth.DepthColumns`, attribute ``n_phases``; the root
    attributes ``coating_<event>_distance`` (m), ``..._distance_s_star``
    (1) and ``..._reason`` (text, "" when reached) for each event of
    :data:`transient.run_in_distance.COATING_EVENTS` (NaN with the reason
    when there is no coating or the event did not happen).  A checkpoint
    has the attributes but not the group (compressed, it would cost more
    than the rest of the file; the resumed run's problem has the columns).
    """
    columns = result.columns
    for event in COATING_EVENTS:
        found = coating_distance(result, event)
        _attribute(f.attrs, f"coating_{event}_distance", found.distance_m, "m")
        _attribute(f.attrs, f"coating_{event}_distance_s_star", found.distance_s_star, "1")
        f.attrs[f"coating_{event}_reason"] = found.reason
    if result.status == "running":
        return  # a checkpoint is rewritten every few seconds; the scene rebuilds the columns
    g = f.create_group("columns")
    g.attrs["description"] = ("the phase below every face pixel as a function of the worn depth "
                              "(steady.depth.DepthColumns)")
    _attribute(g.attrs, "n_phases", columns.n_phases, "1")
    _put(g, "interfaces", columns.interfaces, "m", "depths of the phase changes below each "
         "pixel, ascending, inf beyond the pixel's last", dims=(None, *grid_scales),
         **_SNAPSHOT_FILTERS)
    _put(g, "phases", columns.phases.astype(_section_dtype(columns)), "1",
         "phase index of each segment between interfaces, -1 off the face",
         dims=(None, *grid_scales), **_SNAPSHOT_FILTERS)


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


# The comparison's arrays (Pa, one value per phase) and its lengths; the rest is 1 or a flag.
_COMPARISON_NAMES = {"phase_pressures": "mean pressure on each phase, run",
                     "steady_phase_pressures": "pressure on each phase, steady state (eq. 7)"}
_COMPARISON_UNITS = {"rms_height": "m", "steady_rms_height": "m"}


def _write_comparison(f, comparison, phase_scale):
    """The group ``comparison``: :class:`transient.comparison.SteadyComparison`."""
    g = f.create_group("comparison")
    for fld in dataclasses.fields(comparison):
        value = getattr(comparison, fld.name)
        if isinstance(value, np.ndarray):
            _put(g, fld.name, value, "Pa", _COMPARISON_NAMES.get(fld.name), dims=(phase_scale,))
        else:
            unit = None if isinstance(value, (bool, np.bool_)) else _COMPARISON_UNITS.get(
                fld.name, "1")
            _attribute(g.attrs, fld.name, value, unit)


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
    """The outline group, the reference slope's attributes and the outline's root attributes."""
    outline = result.outline
    values = {"reference_slope_error": result.reference_slope_error,
              "scale": outline.scale, "pixel_size": result.pixel_size}
    for name, unit in _REFERENCE_UNITS.items():
        _attribute(f.attrs, name, values[name], unit)
    f.attrs["reference_slope_source"] = result.reference_slope_source
    for name, (value, unit) in outline.root_attributes().items():
        _attribute(f.attrs, name, value, unit)
    group = f.create_group("outline")
    write_outline(group, outline)
    for ds in group.values():  # a mask's pixels: checksummed like every dataset
        ds.attrs[CHECKSUM_ATTRIBUTE] = dataset_digest(ds[()], dict(ds.attrs))


def _read_outline(path, datasets, groups, root):
    """The outline of a run file: its group, else the disk of ``radius``, else None."""
    if "outline" not in groups:
        radius = _plain(root.get("radius"))
        if isinstance(radius, (int, float)) and math.isfinite(radius) and radius > 0:
            return Circle(float(radius))
        return None
    # read_outline reads an h5py group: give it a view of what was loaded.
    mask = datasets.get("outline/mask")
    try:
        return read_outline(_LoadedGroup(groups["outline"],
                                         {} if mask is None else {"mask": mask[0]}))
    except (KeyError, TypeError, ValueError) as err:
        raise DamagedRunFileError(path, f"its outline cannot be read ({err})") from None


class _LoadedGroup:
    """A loaded group's attributes and datasets, as :func:`steady.output.read_outline` reads."""

    def __init__(self, attrs, datasets):
        self.attrs = attrs
        self._datasets = datasets

    def __getitem__(self, name):
        return _LoadedDataset(self._datasets[name])


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
        All root attributes (``attrs["sha256"]`` absent: an unverified file
        without checksums).
    arrays : dict
        Root datasets other than ``worn_depth`` and ``pressure``.

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
    if not path.exists():
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
    return _result(path, datasets, groups)


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
    history = {name[len("history/"):]: value for name, (value, _) in datasets.items()
               if name.startswith("history/")}
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
        columns=_read_columns(path, datasets, groups))
    arrays = {name: value for name, (value, _) in datasets.items()
              if "/" not in name and name not in ("worn_depth", "pressure", "x", "y")}
    return result, attrs, arrays
