"""Safe files: atomic HDF5 writes, file identity, backups, checksums and the writers' lock.

Every file of the project that is written whole goes through
:func:`atomic_h5`: a temporary file beside the target, put in place when
complete (hard-linked, so that a file another writer put there meanwhile is
not replaced, or renamed over the file it may replace), with the layout
name and version in the root attributes ``format`` and ``format_version``.
A reader never sees half a file, an interrupted write leaves nothing behind,
and the file a path names is told apart by its :class:`FileIdentity`.
(Sweep files, which grow point by point, have their own mechanism:
:mod:`steady.sweep`.)

Checksums
---------
:func:`dataset_digest` is the SHA-256 of a dataset's dtype, shape and bytes
and of its other attributes, :func:`attributes_digest` that of a group's
attributes (the dimension scales' references,
:data:`DIMENSION_SCALE_ATTRIBUTES`, left out); :func:`seal_groups` stores
the digest of every group's attributes in :data:`CHECKSUM_ATTRIBUTE`.  Run
files carry them on every dataset and group, so that a reader can tell a
flipped bit from the file written.

Writers
-------
A file rewritten again and again (a run's checkpoints) has one writer at a
time: :class:`RunLock` holds an exclusive lock (:func:`fcntl.flock`) on
``FILE.lock`` beside it (:func:`lock_path`), which records the writer's
process id; a second writer is refused at once with :class:`RunLockedError`.
``atomic_h5(..., backup=backup_path(path))`` keeps the file it replaces as
``FILE.prev``.

This module imports nothing of the numerics: the file formats build on it.
"""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import os
import pathlib
import socket
import tempfile

import h5py
import numpy as np

try:
    import fcntl
except ImportError:  # not a POSIX system: writers are not locked
    fcntl = None

__all__ = [
    "CHECKSUM_ATTRIBUTE",
    "DIMENSION_SCALE_ATTRIBUTES",
    "AtomicH5",
    "FileIdentity",
    "OutputAppearedError",
    "OutputExistsError",
    "RunLock",
    "RunLockedError",
    "atomic_h5",
    "attributes_digest",
    "backup_path",
    "dataset_digest",
    "file_identity",
    "lock_path",
    "remove_temporaries",
    "seal_groups",
]

#: Attributes the HDF5 dimension-scale API (and netCDF-4) keeps on datasets:
#: the file's structure, not its values (left out of the checksums).
DIMENSION_SCALE_ATTRIBUTES = frozenset({"CLASS", "NAME", "DIMENSION_LIST", "REFERENCE_LIST",
                                        "_Netcdf4Dimid", "_Netcdf4Coordinates"})

#: Attribute holding the SHA-256 of a dataset or of a group's attributes.
CHECKSUM_ATTRIBUTE = "sha256"


# -- the atomic writer --------------------------------------------------------------
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
        if not pid.isdigit() or int(pid) == os.getpid() or _running(int(pid)):
            continue
        with contextlib.suppress(OSError):
            (target.parent / name).unlink()


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



# -- checksums ----------------------------------------------------------------------
def _update(h, value):
    """Feed one attribute value or array, as h5py returns it, to a hash."""
    if isinstance(value, str):
        h.update(b"s" + value.encode("utf-8", "surrogatepass"))
    elif isinstance(value, bytes):
        h.update(b"b" + value)
    else:
        a = np.asarray(value)
        if a.dtype.hasobject:  # variable-length strings
            h.update(b"o" + repr(a.tolist()).encode("utf-8", "surrogatepass"))
        else:
            h.update(f"a{a.dtype.str}{a.shape}".encode())
            h.update(np.ascontiguousarray(a).reshape(-1).view(np.uint8))  # no copy
    h.update(b"\0")


def attributes_digest(attrs):
    """SHA-256 (hex) of a mapping of attributes, its own ``sha256`` left out."""
    h = hashlib.sha256()
    for name in sorted(attrs):
        # The dimension scales' bookkeeping holds references (object
        # addresses in the file), not values: structure, left out.
        if name != CHECKSUM_ATTRIBUTE and name not in DIMENSION_SCALE_ATTRIBUTES:
            h.update(name.encode("utf-8", "surrogatepass") + b"\0")
            _update(h, attrs[name])
    return h.hexdigest()


def dataset_digest(data, attrs):
    """SHA-256 (hex) of a dataset's values (dtype, shape, bytes) and its other attributes."""
    h = hashlib.sha256()
    _update(h, data)
    h.update(attributes_digest(attrs).encode())
    return h.hexdigest()



def seal_groups(f):
    """Store the digest of every group's attributes; the root's last."""
    groups = []
    f.visititems(lambda name, obj: groups.append(obj) if isinstance(obj, h5py.Group) else None)
    for g in groups + [f]:
        g.attrs[CHECKSUM_ATTRIBUTE] = attributes_digest(dict(g.attrs))


# -- backups and the writers' lock ----------------------------------------------------
class RunLockedError(ValueError):
    """Another process is writing the run file (it holds its :class:`RunLock`).

    Attributes
    ----------
    pid : int or None
        The writer's process id, if it has recorded it.
    """

    def __init__(self, path, pid, message=None):
        who = "pid not yet recorded" if pid is None else f"pid {pid}"
        super().__init__(message or f"another run is writing {str(path)!r} ({who})")
        self.pid = pid


def backup_path(path):
    """``RUN.h5.prev``: where a writer that keeps a backup keeps the file it replaced."""
    path = pathlib.Path(path)
    return path.with_name(path.name + ".prev")


def lock_path(path):
    """``RUN.h5.lock``: the lock file of a run file (see :class:`RunLock`)."""
    path = pathlib.Path(path)
    return path.with_name(path.name + ".lock")



def remove_temporaries(path):
    """Remove the temporary files killed writers of ``path`` left beside it.

    Call it only while holding the run's :class:`RunLock` (no other writer
    can be using them).

    Parameters
    ----------
    path : str or path-like
        The run file.

    Returns
    -------
    list of pathlib.Path
        The files removed (``.<name>.*.tmp`` beside ``path``).
    """
    path = pathlib.Path(path)
    removed = []
    for tmp in path.parent.glob(f".{path.name}.*.tmp"):
        try:
            tmp.unlink()
        except OSError:
            continue
        removed.append(tmp)
    return removed


def _running(pid):
    """Whether process ``pid`` exists and has not ended (a zombie, not yet reaped, has)."""
    if pid <= 0:  # os.kill would signal a process group
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # another user's process
        return True
    except (OSError, OverflowError, ValueError):  # not a process id
        return False
    try:
        with open(f"/proc/{pid}/stat", "rb") as f:
            state = f.read().rpartition(b")")[2].split()[:1]
    except OSError:  # no /proc: it exists
        return True
    return state not in ([b"Z"], [b"X"])


class RunLock:
    """Exclusive lock of a run file, so that two runs never write it at once.

    ``RUN.h5.lock`` beside the run file is opened (created if need be),
    locked with :func:`fcntl.flock` (``LOCK_EX | LOCK_NB``) and its content
    replaced by this process's id.  A second writer fails at once with
    :class:`RunLockedError`, naming the pid.  The kernel releases the lock
    of a process that dies, so a lock file left by a killed run does not
    block: it is taken over and :attr:`previous_pid` names the dead writer.
    A free lock whose file names a process that is still running (a lock
    file copied, or written on another machine) is refused too: that
    process may be writing the run.  :meth:`release` removes the file.

    Parameters
    ----------
    path : str or path-like
        The run file (not the lock file).

    Attributes
    ----------
    path : pathlib.Path
        The lock file.
    previous_pid : int or None
        Pid found in a lock file left behind by a writer that ended without
        releasing it (killed), else None.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> run = pathlib.Path(tempfile.mkdtemp()) / "run.h5"
    >>> with RunLock(run) as lock:
    ...     try:
    ...         RunLock(run).acquire()
    ...     except RunLockedError as err:
    ...         print("refused:", err.pid == os.getpid())
    refused: True
    >>> lock.path.exists()
    False
    """

    def __init__(self, path):
        self.run_path = pathlib.Path(path)
        self.path = lock_path(path)
        self.previous_pid = None
        self._fd = None

    @staticmethod
    def _pid(fd):
        os.lseek(fd, 0, os.SEEK_SET)
        text = os.read(fd, 64).decode("ascii", "replace").strip()
        return int(text) if text.isdigit() else None

    def acquire(self):
        """Take the lock or raise :class:`RunLockedError`; returns ``self``."""
        if fcntl is None:
            return self
        while True:
            fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o666)
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError:  # BlockingIOError: held by a live process
                pid = self._pid(fd)
                os.close(fd)
                raise RunLockedError(self.run_path, pid) from None
            # The holder may have removed the file between our open and flock:
            # then this lock is on a file nobody else will see; start again.
            try:
                same = os.path.samestat(os.fstat(fd), os.stat(self.path))
            except FileNotFoundError:
                same = False
            if same:
                break
            os.close(fd)
        previous = self._pid(fd)
        self.previous_pid = previous if previous not in (None, os.getpid()) else None
        if self.previous_pid is not None and _running(self.previous_pid):
            os.close(fd)
            raise RunLockedError(self.run_path, previous, (
                f"the lock {str(self.path)!r} names process {previous}, which is running though "
                f"it does not hold the lock; if no run is writing {str(self.run_path)!r}, remove "
                f"the lock file"))
        os.ftruncate(fd, 0)
        os.lseek(fd, 0, os.SEEK_SET)
        os.write(fd, f"{os.getpid()}\n".encode())
        self._fd = fd
        return self

    def release(self):
        """Remove the lock file and drop the lock (idempotent)."""
        if self._fd is None:
            return
        # Unlink while still holding the lock: a waiter that opened the old
        # file notices it is gone (acquire checks) and starts again.
        try:
            self.path.unlink()
        except OSError:
            pass
        os.close(self._fd)
        self._fd = None

    def __enter__(self):
        """Acquire."""
        return self.acquire()

    def __exit__(self, *exc):
        """Release."""
        self.release()
