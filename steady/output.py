"""HDF5 files: the atomic writer of the project and the steady result files.

:func:`atomic_h5` writes every HDF5 file that is written whole: a
temporary file beside the target, put in place when complete (linked, so
that a file another writer put there meanwhile is not replaced, or
renamed over the file it may replace), with the layout name and version in
the root attributes ``format`` and ``format_version``.  (Sweep files, which
grow point by point, have their own mechanism: :mod:`steady.sweep`.)

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
    group ``micrograph``: a segmented micrograph's segmentation and placement

An attribute cannot carry attributes, so the unit of attribute ``x`` is the
string attribute ``x_units``, a udunits string like a dataset's ``units``.
Files written before the coordinates and phase names (version 2 without
them, and version 1, disks only, without ``outline``, ``scale``,
``mean_pressure`` and the reference's error and source) are read too.
"""

from __future__ import annotations

import contextlib
import dataclasses
import os
import pathlib
import socket
import tempfile

import h5py
import numpy as np

from .micrograph import Micrograph
from .outline import OUTLINES, Circle, MaskOutline
from .problem import check_phase_names, default_phase_names
from .solution import SteadyResult
from .wear import wear_file_attributes, wear_law_from_file

__all__ = ["DIMENSION_SCALE_ATTRIBUTES", "FORMAT", "FORMAT_VERSION", "AtomicH5", "FileIdentity",
           "OutputAppearedError", "OutputExistsError", "StoredResult", "atomic_h5",
           "attach_scales", "describe", "file_identity", "read_outline", "read_phase_names",
           "read_result", "write_grid_coordinates", "write_outline",
           "write_phase_names", "write_result"]

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
# Root attributes and their units (udunits); the wear coefficients' unit
# depends on the exponent (wear_coefficient_units).
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

#: Attributes the HDF5 dimension-scale API (and netCDF-4) keeps on datasets:
#: the file's structure, not its values.
DIMENSION_SCALE_ATTRIBUTES = frozenset({"CLASS", "NAME", "DIMENSION_LIST", "REFERENCE_LIST",
                                        "_Netcdf4Dimid", "_Netcdf4Coordinates"})


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


def _umask():
    """The process's file-mode creation mask."""
    # Reading the mask means setting it: set it back at once.
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def _write_error(err, tmp, path):
    """An :class:`OSError` of writing ``path`` that names ``path``, not the temporary file."""
    import errno as errno_codes
    import re

    # The first error in the chain with an errno says why (e.g. a failed
    # close reports "file write failed" after the write that hit ENOSPC).
    code, cause, seen = None, err, set()
    while cause is not None and id(cause) not in seen and code is None:
        seen.add(id(cause))
        if isinstance(cause, OSError):
            code = cause.errno
            if code is None:
                # h5py's messages carry the C library's errno inside the text.
                found = re.search(r"errno = (\d+)", str(cause))
                code = int(found.group(1)) if found else None
        cause = cause.__context__
    if code is not None and code in errno_codes.errorcode:
        reason = os.strerror(code)
    else:
        reason = err.strerror or str(err)
        if tmp is not None:
            reason = reason.replace(str(tmp), str(path))
    return OSError(code, f"cannot write {str(path)!r}: {reason}")


def _temporary(target):
    """A new temporary file beside ``target``: ``(fd, path)``, named for this process.

    The name ``.<name>.<host>.<pid>.<random>.tmp`` says which process made
    it, so that a later writer can tell the file of a killed writer (its
    process has ended) from that of a live one (:func:`_remove_dead_temporaries`).
    """
    host = socket.gethostname().replace(os.sep, "_") or "host"
    fd, tmp = tempfile.mkstemp(dir=target.parent, prefix=f".{target.name}.{host}.{os.getpid()}.",
                               suffix=".tmp")
    return fd, pathlib.Path(tmp)


def _remove_dead_temporaries(target):
    """Remove the temporary files beside ``target`` whose writer, on this host, has ended.

    A writer killed (SIGKILL) while it wrote leaves its temporary file; no
    writer can use it any more.  A file whose process is alive, runs on
    another host, or whose name does not say (:func:`_temporary`), is left.
    """
    host = socket.gethostname().replace(os.sep, "_") or "host"
    prefix = f".{target.name}.{host}."
    try:
        names = [p.name for p in target.parent.iterdir()]
    except OSError:
        return
    for name in names:
        if not (name.startswith(prefix) and name.endswith(".tmp")):
            continue
        pid = name[len(prefix):].split(".", 1)[0]
        if not pid.isdigit() or int(pid) == os.getpid() or _alive(int(pid)):
            continue
        with contextlib.suppress(OSError):
            (target.parent / name).unlink()


def _alive(pid):
    """Whether process ``pid`` exists (a zombie, not yet waited for, counts as alive)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # PermissionError: another user's process
        return True
    return True


def _keep_backup(path, backup):
    """Make ``backup`` a copy of ``path`` (a hard link where possible), atomically."""
    if backup.exists() and os.path.samefile(path, backup):
        # A writer killed between this step and its rename left the backup a
        # link of the file itself; renaming a third link over it would do
        # nothing (POSIX) and leave the temporary name behind.
        return
    fd, tmp = _temporary(backup)
    os.close(fd)
    try:
        tmp.unlink()
        try:
            os.link(path, tmp)
        except OSError:
            import shutil  # a file system without hard links: copy

            shutil.copy2(path, tmp)
        os.replace(tmp, backup)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


@dataclasses.dataclass(frozen=True)
class FileIdentity:
    """Which file a path names: device, inode, size and modification time.

    Two identities are equal when the path still names the same, unchanged
    file (the size and time tell a new file that reuses a freed inode).
    Returned by :func:`file_identity` and :attr:`AtomicH5.identity`; given
    to :func:`atomic_h5` as the file it may replace (``replaces``).
    """

    device: int
    inode: int
    size: int
    mtime_ns: int

    @classmethod
    def of(cls, st):
        """The identity of an :func:`os.stat` result."""
        return cls(st.st_dev, st.st_ino, st.st_size, st.st_mtime_ns)


def file_identity(path):
    """The :class:`FileIdentity` of the file ``path`` names, None if there is none.

    Parameters
    ----------
    path : str or path-like

    Returns
    -------
    FileIdentity or None
    """
    try:
        return FileIdentity.of(os.stat(path))
    except (FileNotFoundError, NotADirectoryError):
        return None


class OutputExistsError(ValueError):
    """An output that may not be replaced (no ``force``) exists.

    Attributes
    ----------
    path : pathlib.Path
    """

    def __init__(self, path, message=None):
        super().__init__(message or f"output {str(path)!r} exists (use --force to overwrite)")
        self.path = pathlib.Path(path)


class OutputAppearedError(OutputExistsError):
    """Another writer wrote the output after it was checked: nothing was written.

    Raised when the file is about to be published (or, for a caller that
    checked the output before its work, when the writing starts), so that a
    result computed while another process wrote the same output never
    silently replaces it.
    """

    def __init__(self, path, replaced=False):
        what = ("was replaced meanwhile by another process" if replaced
                else "appeared meanwhile (another process wrote it)")
        super().__init__(path, f"output {str(path)!r} {what}; nothing was written (use "
                               f"--force to overwrite)")


class AtomicH5:
    """The context manager :func:`atomic_h5` returns.

    Attributes
    ----------
    path : pathlib.Path
        The target.
    identity : FileIdentity or None
        After the block: the identity of the file written (None before,
        or if nothing was written).  Give it as ``replaces`` to the next
        write of the same path to replace this file and no other.
    """

    def __init__(self, path, **options):
        self.path = pathlib.Path(path)
        self.identity = None
        self._options = options
        self._writer = None

    def __enter__(self):
        """Check the target, open the temporary file; return the :class:`h5py.File`."""
        self._writer = _write_atomically(self, self.path, **self._options)
        return self._writer.__enter__()

    def __exit__(self, *exc):
        """Publish the file, or drop it on an exception."""
        return self._writer.__exit__(*exc)


def atomic_h5(path, *, format, version, force=False, backup=None, replaces=None,
              checked=False):
    """Write an HDF5 file atomically: a temporary file, then a link or a rename.

    Every HDF5 file of the project that is written whole goes through this
    helper, so that a reader never sees half a file, an interrupted
    write leaves nothing behind, and a file another writer wrote meanwhile
    is never replaced without ``force``.

    Parameters
    ----------
    path : str or path-like
        The file to write; missing parent directories are created.
    format : str
        Layout name, stored in the root attribute ``format``.
    version : int
        Layout version, stored in the root attribute ``format_version``.
    force : bool, optional
        Replace whatever file ``path`` names when the new one is complete
        (default False).
    backup : str or path-like, optional
        Keep the file that ``path`` held before as ``backup`` (replacing
        it), a hard link where the file system allows, else a copy.
        Default: the replaced file is dropped.
    replaces : FileIdentity, optional
        Without ``force``: the file ``path`` may hold, and that the new one
        replaces (e.g. the writer's own previous file, or the file it
        checked before a long computation).  Default None: ``path`` must
        not exist.
    checked : bool, optional
        The caller checked ``path`` before its work (a command's
        :func:`steady.cli.common.prepare_output`, or ``replaces``): a file
        that is not the expected one is then reported as written meanwhile
        (:class:`OutputAppearedError`), not as an existing file.

    Returns
    -------
    AtomicH5
        A context manager that yields the :class:`h5py.File` to fill: the
        temporary file, open for writing, with ``format`` and
        ``format_version`` set.  On leaving the block without an exception
        it is flushed to disk and published as ``path``; on any exception
        (including ``KeyboardInterrupt``) it is removed and the exception
        propagates, leaving an existing ``path`` untouched.  Its
        :attr:`~AtomicH5.identity` is then that of the file written.

    Raises
    ------
    ValueError
        ``path`` is a directory.
    OutputExistsError
        (a ``ValueError``) ``path`` exists, is not the file ``replaces``
        names, and ``force`` is False: on entering the block.
    OutputAppearedError
        (an :class:`OutputExistsError`) The same found when the new file is
        complete, or on entering the block with ``checked`` or ``replaces``:
        another writer wrote ``path`` in the meantime.  Nothing is written,
        the temporary file is removed.
    OSError
        The file cannot be written; the message names ``path`` (not the
        temporary file) and the reason.

    Notes
    -----
    The file is written to the temporary file
    ``.<name>.<host>.<pid>.<random>.tmp`` in the directory of ``path`` (a
    rename across file systems is not atomic) through a Python file object
    (h5py's ``fileobj`` driver), as HDF5 writes it (not built whole in
    memory), so that an operating-system error is an :class:`OSError`,
    recorded even where HDF5 would not report it, and never a truncated
    file.  Temporary files that
    killed writers of ``path`` on this host left are removed first.

    Publishing: without ``force`` and with nothing to replace, the new file
    is hard-linked as ``path`` (:func:`os.link` fails if ``path`` exists,
    atomically, so of two writers exactly one wins), and the temporary
    name removed; on a file system without hard links, ``path`` is
    checked and the file renamed.  With ``replaces``, ``path`` is checked
    to be that file and the new one renamed over it.  With ``force``, it is
    renamed over whatever ``path`` is.  The check and a rename are two
    steps: a writer that renames a file over ``path`` between them (within
    microseconds; only one given ``force`` or ``replaces`` can) is not
    noticed.
    The new file gets the permissions of a file created normally
    (``0o666`` less the umask), not the ``0o600`` of
    :func:`tempfile.mkstemp`.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "example.h5"
    >>> with atomic_h5(path, format="runin.example", version=1) as f:
    ...     f["x"] = [1.0, 2.0]
    >>> sorted(p.name for p in path.parent.iterdir())
    ['example.h5']
    """
    return AtomicH5(path, format=format, version=version, force=force, backup=backup,
                    replaces=replaces, checked=checked)


def _refused(force, replaces, found):
    """Whether a path that names ``found`` (None: nothing) may not be replaced."""
    return not force and found is not None and found != replaces


def _publish(tmp, path, *, force, replaces, backup):
    """Put the complete temporary file in place as ``path`` (see :func:`atomic_h5`)."""
    found = file_identity(path)
    if _refused(force, replaces, found):
        raise OutputAppearedError(path, replaced=replaces is not None)
    if backup is not None and found is not None and path.is_file():
        _keep_backup(path, pathlib.Path(backup))
    if force or found is not None:
        os.replace(tmp, path)
        return
    try:
        os.link(tmp, path)
    except FileExistsError:
        raise OutputAppearedError(path, replaced=replaces is not None) from None
    except OSError as err:
        import errno as errno_codes

        if err.errno not in (errno_codes.EPERM, errno_codes.EOPNOTSUPP, errno_codes.ENOTSUP,
                             errno_codes.EMLINK, errno_codes.ENOSYS):
            raise
        # No hard links here: check and rename (the window of the Notes).
        if file_identity(path) is not None:
            raise OutputAppearedError(path, replaced=replaces is not None) from None
        os.replace(tmp, path)
        return
    tmp.unlink()


class _RecordingFile:
    """A binary file for h5py's ``fileobj`` driver that keeps the first OSError it raised.

    HDF5 turns a failed write into an error of its own, or into none at all
    (a failure while a file is closed is reported in a destructor); the
    recorded error is what :func:`atomic_h5` reports.  Once one call failed,
    every later call raises the same error, so that nothing more is written.

    Parameters
    ----------
    raw : io.BufferedRandom
        The temporary file, open for reading and writing.
    """

    def __init__(self, raw):
        self._raw = raw
        self.error = None

    def _call(self, name, *args):
        if self.error is not None:
            raise self.error
        try:
            return getattr(self._raw, name)(*args)
        except OSError as err:
            self.error = err
            raise

    def seek(self, *args):
        """Seek, see :meth:`io.IOBase.seek`."""
        return self._call("seek", *args)

    def tell(self):
        """The current position, see :meth:`io.IOBase.tell`."""
        return self._call("tell")

    def read(self, *args):
        """Read, see :meth:`io.BufferedIOBase.read`."""
        return self._call("read", *args)

    def readinto(self, buffer):
        """Read into ``buffer``, see :meth:`io.BufferedIOBase.readinto`."""
        return self._call("readinto", buffer)

    def write(self, data):
        """Write all of ``data`` (a buffered write: all or an OSError)."""
        return self._call("write", data)

    def truncate(self, *args):
        """Truncate, see :meth:`io.IOBase.truncate`."""
        return self._call("truncate", *args)

    def flush(self):
        """Flush the buffer to the operating system."""
        return self._call("flush")

    def raise_recorded(self):
        """Raise the recorded error, if a call failed (HDF5 may not have)."""
        if self.error is not None:
            raise self.error


@contextlib.contextmanager
def _write_atomically(receipt, path, *, format, version, force, backup, replaces, checked):
    """The work of :func:`atomic_h5`; the identity written goes to ``receipt.identity``."""
    if path.is_dir():
        raise ValueError(f"output {str(path)!r} is a directory")
    if _refused(force, replaces, file_identity(path)):
        if checked or replaces is not None:
            raise OutputAppearedError(path, replaced=replaces is not None)
        raise OutputExistsError(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        _remove_dead_temporaries(path)
        fd, tmp = _temporary(path)
    except OSError as err:
        raise _write_error(err, None, path) from None
    in_caller, sink = False, None
    try:
        with open(fd, "w+b") as out:
            os.chmod(tmp, 0o666 & ~_umask())
            # HDF5 writes through a Python file object (h5py's ``fileobj``
            # driver), so that a refused write (a full disk, a quota, a size
            # limit) is an OSError of a buffered write, recorded where HDF5
            # may hide it (a close reports failures only in destructors) and
            # raised again after it; the file is never built whole in memory.
            sink = _RecordingFile(out)
            with h5py.File(sink, "w") as f:
                f.attrs["format"] = format
                f.attrs["format_version"] = version
                in_caller = True
                yield f
                in_caller = False
            sink.raise_recorded()
            out.flush()
            os.fsync(out.fileno())
            # A link or a rename keeps the inode, size and time: this is what
            # ``path`` names once published.
            written = FileIdentity.of(os.fstat(out.fileno()))
        _publish(tmp, path, force=force, replaces=replaces, backup=backup)
    except BaseException as err:
        tmp.unlink(missing_ok=True)
        # The caller's own OSErrors pass unchanged; those of this file name it.
        if isinstance(err, Exception) and sink is not None and sink.error is not None:
            raise _write_error(sink.error, tmp, path) from None
        if isinstance(err, OSError) and (not in_caller or tmp.name in str(err)):
            raise _write_error(err, tmp, path) from None
        raise
    receipt.identity = written
    try:  # make the rename itself durable; not every file system allows it
        fd = os.open(path.parent, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)
    except OSError:
        pass


def write_result(path, result, scene=None, *, phase_names=None, force=False, checked=False):
    """Write a steady result (and its scene) to an HDF5 file, atomically.

    See :func:`atomic_h5`: a reader never sees half a file; missing parent
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
        written meanwhile (see :func:`atomic_h5`).

    Returns
    -------
    pathlib.Path

    Raises
    ------
    ValueError
        ``path`` is a directory, or ``phase_names`` are not one distinct
        name per phase.
    OutputExistsError
        (a ``ValueError``) ``path`` exists and ``force`` is False; an
        :class:`OutputAppearedError` if another writer wrote it while this
        result was written (nothing is written then).

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
    if isinstance(result.outline, Circle):
        f.attrs["radius"] = result.outline.radius
        f.attrs["radius_units"] = "m"
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
    if scene is not None and isinstance(scene.geometry, Micrograph):
        _write_micrograph(f.create_group("micrograph"), scene.geometry)


def write_outline(group, outline):
    """A face outline as the attributes (and for a mask the dataset) of ``group``.

    Attribute ``x`` has its udunits unit in ``x_units``: ``area`` (``m2``)
    and the outline's lengths (``m``).  A mask outline's ``mask`` has the
    dimension scales ``mask_x`` and ``mask_y`` (m, its pixel centres).

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
    if isinstance(outline, MaskOutline):
        ds = group.create_dataset("mask", data=outline.mask.astype(np.int8))
        describe(ds, "1", "1 inside the face, 0 outside")
        scales = []
        for axis, name in enumerate(("mask_x", "mask_y")):
            m = outline.mask.shape[axis]
            scale = group.create_dataset(name, data=(np.arange(m) - 0.5 * (m - 1))
                                         * outline.pixel_size)
            describe(scale, "m", f"{name[-1]} of the mask's pixel centre, from its centre")
            scale.make_scale(name)
            scales.append(scale)
        attach_scales(ds, *scales)
        group.attrs["source"] = outline.source


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
    if kind == "mask":
        source = group.attrs.get("source", "stored mask")
        if isinstance(source, bytes):
            source = source.decode()
        return MaskOutline(np.asarray(group["mask"][()], dtype=bool),
                           float(group.attrs["pixel_size"]), source=str(source))
    cls = OUTLINES[kind]
    return cls(**{key.name: float(group.attrs[key.name]) for key in cls.keys if key.required})


def _write_micrograph(group, geometry):
    """The segmentation and placement of a micrograph map, as attributes of ``group``."""
    seg = geometry.segmentation
    values = {
        "source": geometry.source,
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
        "pixel_size": geometry.pixel_size,
        "pixel_size_units": "m",
        "cover": geometry.cover,
        "offset": np.asarray(geometry.offset),
        "offset_units": "m",
        # Counts of pixels: dimensionless for udunits (docs/files.md says pixels).
        "smoothing_units": "1",
        "min_speck_units": "1",
    }
    for name, value in values.items():
        group.attrs[name] = value


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
    ValueError
        Missing file, not HDF5, corrupt, another layout or another version
        (the message names the path and the problem).
    """
    path = pathlib.Path(path)
    if not path.is_file():
        raise ValueError(f"result file {str(path)!r} does not exist")
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
