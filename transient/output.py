"""HDF5 run files (layout ``runin.transient``, version 2).

A run file holds a run-in, finished or in progress (a checkpoint): the
state a resumed run needs, the history, the snapshots, the inputs that
identify the run and, once the run is steady, its agreement with the
steady face.  It is written whole and atomically by the project's one
HDF5 writer (:func:`steady.output.atomic_h5`), so a reader never sees half
a file and a killed run leaves its last checkpoint intact.

Layout (root group)::

    attributes    format "runin.transient", format_version 2
                  status, message, scheme, distance (m), steps, rejected,
                  failures, solves, iterations, wall_time (s), offset (m),
                  approach (m), depth_scale (m), run_in_distance (m),
                  fast_distance (m), pixel_mean_pressure (Pa),
                  reference_slope, previous_step (m, NaN if none),
                  next_step (m, NaN if none); the unit of attribute ``x``
                  in ``x_units``; the caller's input attributes (scene...)
    worn_depth    (n, n) m, NaN off the face
    pressure      (n, n) Pa
    <arrays>      the caller's input datasets (e.g. ``phase``)
    state/        height, initial_height, previous_height, previous_rate
    history/      one dataset per :data:`transient.runin.HISTORY_UNITS` name
    snapshots/    distance (k,) m, height (k, n, n) m, pressure (k, n, n) Pa
    comparison/   :class:`transient.comparison.SteadyComparison` (steady runs)

Every dataset carries a ``units`` attribute.
"""

from __future__ import annotations

import dataclasses
import math
import pathlib
import types

import h5py
import numpy as np

from steady.output import atomic_h5

from .runin import HISTORY_UNITS, RunResult

__all__ = ["FORMAT", "FORMAT_VERSION", "read_run", "write_run"]

#: ``format`` attribute of a run file.
FORMAT = "runin.transient"
#: Layout version of a run file (``format_version`` attribute).
FORMAT_VERSION = 2

# Root scalar attributes and their units.
_SCALARS = {
    "status": "", "message": "", "scheme": "", "distance": "m", "steps": "1",
    "rejected": "1", "failures": "1", "solves": "1", "iterations": "1", "wall_time": "s",
    "offset": "m", "approach": "m", "depth_scale": "m", "run_in_distance": "m",
    "fast_distance": "m", "pixel_mean_pressure": "Pa", "reference_slope": "1",
}
_OPTIONAL_SCALARS = {"previous_step": "m", "next_step": "m"}
_INTEGERS = ("steps", "rejected", "failures", "solves", "iterations")
_STRINGS = ("status", "message", "scheme")
_STATE_UNITS = {"height": "m", "initial_height": "m", "previous_height": "m",
                "previous_rate": "1"}


def write_run(path, result, *, attrs=None, arrays=None, comparison=None):
    """Write a run (or a checkpoint) to HDF5, atomically, replacing ``path``.

    Parameters
    ----------
    path : str or path-like
    result : transient.runin.RunResult
    attrs : mapping, optional
        Extra root attributes (scene text, parameters).
    arrays : mapping of str to ndarray, optional
        Extra root datasets (e.g. ``phase``).
    comparison : transient.comparison.SteadyComparison, optional
        Stored in the group ``comparison``.
    """
    with atomic_h5(path, format=FORMAT, version=FORMAT_VERSION, force=True) as f:
        for name, unit in _SCALARS.items():
            f.attrs[name] = getattr(result, name)
            if unit:
                f.attrs[f"{name}_units"] = unit
        for name, unit in _OPTIONAL_SCALARS.items():
            value = getattr(result, name)
            f.attrs[name] = np.nan if value is None else value
            f.attrs[f"{name}_units"] = unit
        for name, value in (attrs or {}).items():
            f.attrs[name] = value
        f.create_dataset("worn_depth", data=result.worn_depth).attrs["units"] = "m"
        f.create_dataset("pressure", data=result.pressure).attrs["units"] = "Pa"
        for name, value in (arrays or {}).items():
            f.create_dataset(name, data=value).attrs["units"] = "1"
        st = f.create_group("state")
        st.attrs["description"] = "everything a resumed run needs (face up to offset)"
        for name, unit in _STATE_UNITS.items():
            value = getattr(result, name)
            if value is not None:
                st.create_dataset(name, data=value).attrs["units"] = unit
        hist = f.create_group("history")
        for name, value in result.history.items():
            hist.create_dataset(name, data=value).attrs["units"] = HISTORY_UNITS[name]
        snaps = f.create_group("snapshots")
        snaps.create_dataset("distance", data=result.snapshot_distance).attrs["units"] = "m"
        snaps.create_dataset("height", data=result.snapshot_height,
                             compression="gzip").attrs["units"] = "m"
        snaps.create_dataset("pressure", data=result.snapshot_pressure,
                             compression="gzip").attrs["units"] = "Pa"
        if comparison is not None:
            g = f.create_group("comparison")
            for fld in dataclasses.fields(comparison):
                value = getattr(comparison, fld.name)
                if isinstance(value, np.ndarray):
                    g.create_dataset(fld.name, data=value).attrs["units"] = "Pa"
                else:
                    g.attrs[fld.name] = value


def read_run(path):
    """Read a run file written by :func:`write_run`.

    Parameters
    ----------
    path : str or path-like

    Returns
    -------
    result : transient.runin.RunResult
    attrs : dict
        All root attributes.
    arrays : dict
        Root datasets other than ``worn_depth`` and ``pressure``.

    Raises
    ------
    ValueError
        Not a run file, an unknown layout version, or a damaged file.
    """
    path = pathlib.Path(path)
    try:
        f = h5py.File(path, "r")
    except OSError as err:
        raise ValueError(f"cannot read run file {str(path)!r}: {err}") from None
    with f:
        if f.attrs.get("format") != FORMAT:
            raise ValueError(f"{str(path)!r} is not a run file (format "
                             f"{f.attrs.get('format')!r}, expected {FORMAT!r})")
        version = f.attrs.get("format_version", -1)
        if int(version) != FORMAT_VERSION:
            raise ValueError(f"{str(path)!r} has layout version {version!r}, expected "
                             f"{FORMAT_VERSION}")
        attrs = {k: (v.item() if isinstance(v, np.generic) else v) for k, v in f.attrs.items()}
        st = f["state"]
        kw = {name: attrs[name] for name in _SCALARS}
        for name in _INTEGERS:
            kw[name] = int(kw[name])
        for name in _STRINGS:
            kw[name] = str(kw[name])
        for name in _OPTIONAL_SCALARS:
            v = float(attrs[name])
            kw[name] = None if math.isnan(v) else v
        result = RunResult(
            **kw,
            height=st["height"][()], initial_height=st["initial_height"][()],
            pressure=f["pressure"][()],
            previous_height=st["previous_height"][()] if "previous_height" in st else None,
            previous_rate=st["previous_rate"][()] if "previous_rate" in st else None,
            history=types.MappingProxyType({k: v[()] for k, v in f["history"].items()}),
            snapshot_distance=f["snapshots/distance"][()],
            snapshot_height=f["snapshots/height"][()],
            snapshot_pressure=f["snapshots/pressure"][()])
        arrays = {k: f[k][()] for k in f if isinstance(f[k], h5py.Dataset)
                  and k not in ("worn_depth", "pressure")}
    return result, attrs, arrays
