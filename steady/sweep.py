"""Parameter sweeps on an executor, written to HDF5 point by point and resumable.

A sweep evaluates one task function at many parameter points.  The points
run on a :class:`concurrent.futures.Executor`: local processes by default
(:class:`~concurrent.futures.ProcessPoolExecutor`), or a Dask cluster when a
scheduler address is given (``dask.distributed.Client(address).get_executor()``,
the optional extra ``dask``).  The parent process writes every finished
point to the sweep file as soon as it arrives, so that

- an interrupted sweep leaves a readable file with every point finished so
  far (each point is written under a temporary name and renamed when
  complete; the file is closed between points);
- two sweeps on one file share it: the file is created whole and linked
  into place (:func:`steady.safe_files.atomic_h5`), so that the second never
  truncates what the first has written, and each point is written under
  HDF5's file lock;
- running the same sweep again skips the points already in the file
  (resume), and a larger sweep with the same settings adds only the new
  points.

File layout (``runin.sweep``, version 1)::

    attributes   format "runin.sweep", format_version 1,
                 settings (JSON text: what every point shares, e.g. the grid)
    points/<id>  one group per finished point; <id> is a hash of its key
        attributes   key (JSON text of the point's parameters), and the
                     parameters themselves
        datasets     the task's results, each with a ``units`` attribute

The task is a module-level (picklable) function ``task(point) -> dict``
taking the point's parameters (a dict of JSON-serialisable values) and
returning ``{name: scalar or array}``.
"""

from __future__ import annotations

import concurrent.futures
import contextlib
import dataclasses
import hashlib
import json
import logging
import os
import pathlib
import time

import h5py
import numpy as np

from .safe_files import OutputExistsError, atomic_h5
from .schema import Key

__all__ = [
    "DEFAULT_WORKERS",
    "FORMAT",
    "FORMAT_VERSION",
    "LOCK_WAIT",
    "SweepFile",
    "SweepPoint",
    "open_executor",
    "point_key",
    "run_sweep",
]

logger = logging.getLogger(__name__)

FORMAT = "runin.sweep"
FORMAT_VERSION = 1

#: Seconds to wait for a sweep file locked by another process.
LOCK_WAIT = 60.0

#: Local worker processes by default: at most two (the machines these
#: sweeps are meant for share their cores).
DEFAULT_WORKERS = 2

#: Local worker processes asked for.
_WORKERS = Key("workers", "integer", low=1, low_open=False)


def point_key(point):
    """Canonical text of a parameter point (sorted JSON).

    Parameters
    ----------
    point : mapping of str to JSON-serialisable values

    Returns
    -------
    str
    """
    try:
        return json.dumps(dict(point), sort_keys=True, separators=(",", ":"),
                          default=_json_default)
    except TypeError as err:
        raise ValueError(f"sweep point {point!r} is not JSON-serialisable: {err}") from None


def _json_default(value):
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, np.floating):
        return float(value)
    if isinstance(value, np.ndarray):
        return value.tolist()
    raise TypeError(f"{type(value).__name__} is not JSON-serialisable")


def _group_name(key):
    return hashlib.sha1(key.encode()).hexdigest()[:24]


@dataclasses.dataclass(frozen=True)
class SweepPoint:
    """One finished point read back from a sweep file.

    Attributes
    ----------
    params : dict
        The point's parameters.
    values : dict of str to ndarray
        The task's results (0-d arrays for scalars).
    units : dict of str to str
        Unit of each result.
    """

    params: dict
    values: dict
    units: dict


class SweepFile:
    """An HDF5 sweep file (see the module notes for the layout).

    Parameters
    ----------
    path : str or path-like
    settings : mapping, optional
        What every point shares (JSON-serialisable).  A new file stores
        them; an existing file must hold the same settings, else
        ``ValueError`` (a resumed sweep must not mix two set-ups).  ``None``
        opens an existing file for reading without the check.

    Raises
    ------
    FileNotFoundError
        The file does not exist and ``settings`` is None.
    ValueError
        Not a sweep file, or different settings.
    """

    def __init__(self, path, settings=None):
        self.path = pathlib.Path(path)
        self.settings_text = None if settings is None else point_key(settings)
        if not os.path.lexists(self.path):  # a loop of links is there
            if settings is None:
                raise FileNotFoundError(f"sweep file {str(self.path)!r} does not exist")
            self._create()
        self._check_settings()
        self._drop_incomplete()

    def _create(self):
        """Create the empty file; join it if another sweep created it meanwhile.

        Created whole and linked into place (:func:`steady.safe_files.atomic_h5`):
        a sweep that starts beside another one on the same file never
        truncates the points the other one has written.
        """
        try:
            with atomic_h5(self.path, format=FORMAT, version=FORMAT_VERSION) as f:
                f.attrs["settings"] = self.settings_text
                f.create_group("points")
        except OutputExistsError:
            logger.info("%s: created by another sweep meanwhile; joining it", self.path)

    def _check_settings(self):
        """Refuse a file that is not a sweep file of these settings."""
        with self._open("r") as f:
            if f.attrs.get("format") != FORMAT:
                raise ValueError(f"{str(self.path)!r} is not a sweep file "
                                 f"(format {f.attrs.get('format')!r})")
            version = int(f.attrs.get("format_version", -1))
            if version != FORMAT_VERSION:
                raise ValueError(f"{str(self.path)!r} has sweep layout version {version}, "
                                 f"this code reads version {FORMAT_VERSION}")
            stored = str(f.attrs["settings"])
        if self.settings_text is not None and stored != self.settings_text:
            raise ValueError(f"sweep file {str(self.path)!r} was written with settings "
                             f"{stored}, not {self.settings_text}; use another file")
        self.settings_text = stored

    @property
    def settings(self):
        """The shared settings, as a dict."""
        return json.loads(self.settings_text)

    def _open(self, mode):
        # HDF5 locks the file while it is open: another process reading or
        # writing the same sweep file (a second study sharing it) holds it
        # for a moment.  Wait for it rather than lose a finished point.
        deadline = time.monotonic() + LOCK_WAIT
        while True:
            try:
                return h5py.File(self.path, mode)
            except OSError as err:
                locked = "lock" in str(err).lower()
                if not locked or time.monotonic() > deadline:
                    raise ValueError(f"cannot open sweep file {str(self.path)!r}: "
                                     f"{err}") from None
                time.sleep(0.05)

    def _drop_incomplete(self):
        """Remove groups left half-written by an interrupted sweep."""
        with self._open("r") as f:
            stale = [name for name in f["points"] if name.startswith("tmp-")]
        if stale:
            with self._open("a") as f:
                for name in stale:
                    del f["points"][name]
            logger.info("%s: dropped %d incomplete point(s)", self.path, len(stale))

    def keys(self):
        """Keys of the finished points, a set of str."""
        with self._open("r") as f:
            return {str(g.attrs["key"]) for g in f["points"].values()}

    def write(self, point, values, units=None):
        """Store one finished point.

        Parameters
        ----------
        point : mapping
            The point's parameters.
        values : mapping of str to scalar or ndarray
            The task's results.
        units : mapping of str to str, optional
            Unit of each result (default ``"1"``).
        """
        key = point_key(point)
        name = _group_name(key)
        units = units or {}
        with self._open("a") as f:
            points = f["points"]
            if name in points:
                del points[name]
            tmp = points.create_group(f"tmp-{name}")
            tmp.attrs["key"] = key
            for k, v in point.items():
                if v is not None:  # the key holds everything; attributes are for browsing
                    tmp.attrs[k] = v if np.ndim(v) == 0 else np.asarray(v)
            for k, v in values.items():
                ds = tmp.create_dataset(k, data=np.asarray(v))
                ds.attrs["units"] = units.get(k, "1")
            # The rename marks the point complete: a crash before it leaves
            # a tmp- group that the next open drops.
            points.move(f"tmp-{name}", name)

    def read(self):
        """All finished points, in no particular order.

        Returns
        -------
        list of SweepPoint
        """
        out = []
        with self._open("r") as f:
            for g in f["points"].values():
                params = json.loads(str(g.attrs["key"]))
                values = {k: ds[()] for k, ds in g.items()}
                units = {k: str(ds.attrs.get("units", "1")) for k, ds in g.items()}
                out.append(SweepPoint(params=params, values=values, units=units))
        return out


@contextlib.contextmanager
def open_executor(*, workers=None, scheduler=None):
    """An executor for :func:`run_sweep`, closed on exit.

    Parameters
    ----------
    workers : int, optional
        Local worker processes (default ``min(2, cpu count)``).  Ignored
        with ``scheduler``.
    scheduler : str or distributed.Client, optional
        Address of a Dask scheduler (``"tcp://host:8786"``) or a connected
        ``Client``.  Needs ``dask[distributed]`` (the extra ``dask``).  A
        client opened here is closed on exit; a client passed in is not.

    Yields
    ------
    concurrent.futures.Executor
    """
    if scheduler is None:
        n = (min(DEFAULT_WORKERS, os.cpu_count() or 1) if workers is None
             else _WORKERS.parse(workers, ""))
        with concurrent.futures.ProcessPoolExecutor(max_workers=n) as executor:
            yield executor
        return
    try:
        from distributed import Client
    except ImportError:
        raise ValueError("a Dask scheduler needs dask.distributed: "
                         "pip install 'runin[dask]' (or 'dask[distributed]')") from None
    own = not isinstance(scheduler, Client)
    client = Client(scheduler) if own else scheduler
    try:
        # pure=False: every point is computed, even if two share arguments.
        executor = client.get_executor(pure=False)
        yield executor
        executor.shutdown(wait=True)
    finally:
        if own:
            client.close()


def run_sweep(task, points, path, *, settings, units=None, executor=None, workers=None,
              scheduler=None, progress=False, description="sweep"):
    """Evaluate ``task`` at every point not yet in the sweep file.

    Parameters
    ----------
    task : callable
        Module-level function ``task(point) -> dict`` (picklable).
    points : sequence of mapping
        Parameter points (JSON-serialisable values); duplicates are run once.
    path : str or path-like
        Sweep file: created if missing, else resumed (see :class:`SweepFile`).
    settings : mapping
        What every point shares; stored in the file and checked on resume.
        The task does not see it: put what the task needs into the points.
    units : mapping of str to str, optional
        Unit of each result of the task.
    executor : concurrent.futures.Executor, optional
        Run on this executor (not shut down here).  Default: one from
        :func:`open_executor` with ``workers`` and ``scheduler``.
    workers : int, optional
    scheduler : str or distributed.Client, optional
    progress : bool, optional
        Draw a :mod:`tqdm` progress bar on stderr (default False).
    description : str, optional
        Label of the progress bar.

    Returns
    -------
    SweepFile
        The file, holding every point.

    Raises
    ------
    Exception
        The first exception a task raised; points finished before it are in
        the file, so that running again resumes after them.
    """
    sweep = SweepFile(path, settings)
    done = sweep.keys()
    todo, seen = [], set(done)
    for p in points:
        key = point_key(p)
        if key not in seen:
            seen.add(key)
            todo.append(dict(p))
    total = len(todo) + len(done & {point_key(p) for p in points})
    logger.info("%s: %d point(s), %d already in %s", description, total, total - len(todo),
                sweep.path)
    if not todo:
        return sweep
    bar = None
    if progress:
        from tqdm import tqdm  # deferred: only the command line draws a bar
        bar = tqdm(total=total, initial=total - len(todo), desc=description, unit="pt",
                   dynamic_ncols=True)
    try:
        if executor is None:
            with open_executor(workers=workers, scheduler=scheduler) as ex:
                _drain(ex, task, todo, sweep, units, bar)
        else:
            _drain(executor, task, todo, sweep, units, bar)
    finally:
        if bar is not None:
            bar.close()
    return sweep


def _drain(executor, task, todo, sweep, units, bar):
    futures = {executor.submit(task, p): p for p in todo}
    try:
        for future in concurrent.futures.as_completed(futures):
            values = future.result()
            sweep.write(futures[future], values, units)
            if bar is not None:
                bar.update(1)
    except BaseException:
        for future in futures:
            future.cancel()
        raise
