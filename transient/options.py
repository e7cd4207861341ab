"""Options of a run-in: one declaration per option, for the library, the scene and the command.

Every option of :func:`transient.runin.run_in` is a field of
:class:`RunOptions` that carries its scene key (:class:`steady.schema.Key`:
type, unit, range, meaning) in the field's metadata.  From that one
declaration come

- the check of a :class:`RunOptions` built from Python;
- the keys of the scene section ``[transient]``
  (:func:`transient.scene.parse_transient`, :func:`options_from_table`);
- the flags of ``runin-transient`` that override them (the fields marked
  ``flag``: :func:`add_option_flags`, :func:`options_from_flags`).

Adding an option is one field here (and its use in the run).  Distances and
lengths are in m, times in s, as everywhere in the project; the run-in's
distance scale ``s* = L / (k_min E*)`` (``L`` the face outline's scale, the
radius ``a`` of a disk) is only ever a unit that a name says
(``snapshots_s_star``, ``jump_step_s_star``).  The names of the options that
were in s* before they were in m are refused with the value converted
(:data:`RENAMED`, :func:`options_from_table`).
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import sys

from steady.schema import Key, read_table
from steady.text import shorten

from .stepping import get_scheme

__all__ = ["RENAMED", "RunOptions", "add_option_flags", "option_keys", "options_from_flags",
           "options_from_table"]

#: Options that were distances in units of s* under another name: ``old -> new``.  A
#: scene (or a script) that names one is refused, with the value in m where s* is known.
RENAMED = {"step": "fixed_step", "initial_step": "first_step", "max_distance": "distance_limit",
           "snapshots": "snapshot_distances", "jump_step": "jump_step_s_star"}


def _option(default, key, *, flag=False):
    """A field of :class:`RunOptions` with its scene key (and whether a flag overrides it)."""
    return dataclasses.field(default=default, metadata={"key": key, "flag": flag})


@dataclasses.dataclass(frozen=True)
class RunOptions:
    """Options of :func:`transient.runin.run_in`; distances in m.

    Each attribute is also the ``[transient]`` key of the same name; those
    marked (flag) also a flag of ``runin-transient`` (``--spread-tol`` for
    ``spread_tol``).

    Attributes
    ----------
    scheme : str
        Registered integrator (default ``"esdirk3"``, third order;
        docs/benchmarks.md, "Run-in speed") (flag).
    tol : float
        Local error per step, rms over the face of the shape error in units
        of ``f*`` (default 1e-5; at most 1, as the face's relief is a
        fraction of ``f*``) (flag).
    fixed_step : float or None
        Fixed step, m (no adaptivity, no jump); default None (adaptive).
    first_step : float or None
        First adaptive step, m; default ``0.01 sqrt(tol) (h/L) s*`` (the
        fast scale, where the flat punch's edge relaxes).
    spread_tol : float
        Steady when the wear-rate spread is below this (default 1e-6) ...
        (flag)
    shape_tol : float
        ... and the shape changes by less than this many ``f*`` per s*
        (default 1e-6) (flag).
    jump_spread : float
        Jump to the steady state once the spread is below this (default
        1e-3; 0 disables, ``inf`` jumps at once) (flag).
    jump_step_s_star : float
        Length of a jump, in units of s* (default 1e8): a step many times
        the slowest relaxation, whatever the scene.
    distance_limit : float
        Stop (resumable, status ``"stopped"``) beyond this sliding distance,
        m (default inf: no limit) (flag).
    max_steps : int
        Stop after this many accepted steps (default 100000) (flag).
    end_depth : float or None
        End the run (status ``"depth"``) once the mean worn depth over the
        face reaches this, m; steps land on it.  Default None.
    snapshot_distances : tuple of float
        Sliding distances, m, at which the face and the pressure are
        stored; steps land on them exactly.
    snapshots_s_star : tuple of float
        More of them, in units of s* (the run's distance scale, known once
        the problem is): :meth:`snapshots` merges both.
    max_failures : int
        Consecutive failed attempts before the run stops (default 20).
    checkpoint_interval : float
        Least wall-clock seconds between checkpoints (default 10; 0 = every
        step); further apart where writing one takes over 5 % of the time
        between them (:func:`transient.control.checkpoint_due`) (flag).
    contact_rtol : float
        Relative tolerance of every contact solve, the floor of the solves
        of a regular step (default 1e-10); the run sets its problem's
        :attr:`transient.problem.WearProblem.contact_rtol` to it.
    """

    scheme: str = _option("esdirk3", Key(
        "scheme", "string", doc="registered integrator (transient.stepping.SCHEMES)"), flag=True)
    # A tolerance below the precision of a double cannot be met (and times f* may
    # underflow to 0); one above 1 lets a step err by more than the face's whole relief
    # (a fraction of f*), so that the step controller accepts what no estimate resolves.
    tol: float = _option(1e-5, Key(
        "tol", "number", unit="f*", low=sys.float_info.epsilon, high=1.0, high_open=False,
        doc="local error per step, shape rms / f* (at most 1: f* bounds the face's relief, "
            "a looser step resolves nothing)"), flag=True)
    fixed_step: float | None = _option(None, Key(
        "fixed_step", "number", unit="m", low=0.0,
        doc="fixed steps, no adaptivity (default: adaptive)"))
    first_step: float | None = _option(None, Key(
        "first_step", "number", unit="m", low=0.0, doc="first adaptive step"))
    spread_tol: float = _option(1e-6, Key(
        "spread_tol", "number", unit="1", low=0.0,
        doc="steady when (max - min) / mean of k p^m is below this"), flag=True)
    shape_tol: float = _option(1e-6, Key(
        "shape_tol", "number", unit="f*/s*", low=0.0,
        doc="... and the shape changes less than this (f*) per s*"), flag=True)
    jump_spread: float = _option(1e-3, Key(
        "jump_spread", "number", unit="1", low=0.0, low_open=False, finite=False,
        doc="jump to the steady state once the spread is below this (inf: at once, 0: never)"),
        flag=True)
    jump_step_s_star: float = _option(1e8, Key(
        "jump_step_s_star", "number", unit="s*", low=0.0, finite=False,
        doc="length of a jump, in units of s*"))
    distance_limit: float = _option(math.inf, Key(
        "distance_limit", "number", unit="m", low=0.0, finite=False,
        doc="stop (resumable) beyond this sliding distance (default: none)"), flag=True)
    max_steps: int = _option(100000, Key(
        "max_steps", "integer", low=1, low_open=False, doc="stop after this many steps"),
        flag=True)
    end_depth: float | None = _option(None, Key(
        "end_depth", "number", unit="m", low=0.0,
        doc="end once the mean worn depth over the face reaches this"))
    snapshot_distances: tuple = _option((), Key(
        "snapshot_distances", "numbers", unit="m", low=0.0, low_open=False,
        doc="sliding distances at which face and pressure are stored"))
    snapshots_s_star: tuple = _option((), Key(
        "snapshots_s_star", "numbers", unit="s*", low=0.0, low_open=False,
        doc="more of them, in units of s*"))
    max_failures: int = _option(20, Key(
        "max_failures", "integer", low=1, low_open=False,
        doc="consecutive failed attempts before the run stops"))
    checkpoint_interval: float = _option(10.0, Key(
        "checkpoint_interval", "number", unit="s", low=0.0, low_open=False,
        doc="wall-clock seconds between checkpoints (0: every step; the first one follows the "
            "first step)"), flag=True)
    contact_rtol: float = _option(1e-10, Key(
        "contact_rtol", "number", unit="1", low=0.0, high=1.0,
        doc="relative tolerance of every contact solve (floor)"))

    def __post_init__(self):
        """Check every option against its key; store the snapshots sorted and without repeats."""
        get_scheme(self.scheme)
        for field in dataclasses.fields(self):
            value, key = getattr(self, field.name), field.metadata["key"]
            if value is None and field.default is None:
                continue
            if key.type == "integer" and isinstance(value, float) and value.is_integer():
                value = int(value)  # max_steps = 1e3 from Python
            elif key.type == "numbers" and isinstance(value, tuple):
                value = list(value)  # the scene's array, given as a tuple from Python
            key.parse(value, "")
        for name in ("snapshot_distances", "snapshots_s_star"):
            values = tuple(float(s) for s in getattr(self, name))
            object.__setattr__(self, name, tuple(sorted(set(values))))

    def snapshots(self, distance_scale):
        """Every snapshot distance, m, sorted: ``snapshot_distances`` and ``snapshots_s_star``.

        Parameters
        ----------
        distance_scale : float, m
            The run's ``s*``.
        """
        return tuple(sorted({*self.snapshot_distances,
                             *(s * distance_scale for s in self.snapshots_s_star)}))

    def settings(self):
        """The options as plain values (JSON-ready), as the run file records them."""
        values = dataclasses.asdict(self)
        for name in ("snapshot_distances", "snapshots_s_star"):
            values[name] = list(values[name])
        return values


def option_keys():
    """The ``[transient]`` keys, in the order of :class:`RunOptions`' fields."""
    return tuple(field.metadata["key"] for field in dataclasses.fields(RunOptions))


def options_from_table(table, base_dir=".", *, distance_scale=None):
    """The :class:`RunOptions` of a scene's ``[transient]`` table (absent keys: defaults).

    Parameters
    ----------
    table : dict
    base_dir : path-like, optional
    distance_scale : float, optional, m
        The scene's ``s*``, which the refusal of a key renamed from s* to m
        (:data:`RENAMED`) uses to give the value in m.

    Raises
    ------
    ValueError
        An unknown or renamed key or a bad value, named.
    """
    if isinstance(table, dict):
        for old, new in RENAMED.items():
            if old in table:
                raise ValueError(_renamed(old, new, table[old], distance_scale))
    values = read_table(table, "[transient]", option_keys(), base_dir)
    try:
        return RunOptions(**values)
    except ValueError as err:
        raise ValueError(f"[transient] {err}") from None


def _renamed(old, new, value, distance_scale):
    """The refusal of ``[transient] old``, a distance in s* that is now ``new``, in m."""
    if new.endswith("_s_star"):
        return (f"[transient] {old} is now {new} (the same value, in units of s*): write "
                f"{new} = {shorten(value)}")
    converted = ""
    numbers = value if isinstance(value, list) else [value]
    if distance_scale is not None and all(isinstance(v, (int, float)) and not isinstance(
            v, bool) for v in numbers):
        metres = [float(f"{v * distance_scale:.6g}") for v in numbers]
        shown = metres if isinstance(value, list) else metres[0]
        converted = (f" ({shorten(value)} s* with this scene's s* = {distance_scale:.6g} m is "
                     f"{new} = {shorten(shown)})")
    also = (", or snapshots_s_star = " + shorten(value) + " to keep them in s*"
            if old == "snapshots" else "")
    return (f"[transient] {old} was a distance in units of s*; distances are now in m: "
            f"{new}{converted}{also}")


def _flag_type(key):
    """The argparse type of a flag: its key's check (:meth:`Key.parse_text`), one line."""
    def parse(text):
        try:
            return key.parse_text(text)
        except ValueError as err:
            raise argparse.ArgumentTypeError(str(err)) from None
    return parse


def add_option_flags(parser, choices=None):
    """Add a flag for every :class:`RunOptions` field marked ``flag`` (``--spread-tol``).

    Parameters
    ----------
    parser : argparse.ArgumentParser
    choices : mapping of str to sequence, optional
        Choices of string options (``{"scheme": sorted(SCHEMES)}``).
    """
    choices = choices or {}
    for field in dataclasses.fields(RunOptions):
        if not field.metadata["flag"]:
            continue
        key = field.metadata["key"]
        flag = "--" + field.name.replace("_", "-")
        unit = f"{key.unit}; " if key.unit not in ("", "1") and key.unit not in key.doc else ""
        help_text = f"{key.doc} ({unit}overrides [transient] {field.name})"
        if field.name in choices:
            parser.add_argument(flag, choices=choices[field.name], help=help_text)
        else:
            metavar = field.name.upper().split("_")[-1]
            parser.add_argument(flag, type=_flag_type(key), metavar=metavar, help=help_text)


def options_from_flags(options, args):
    """``options`` with the fields the flags in ``args`` override."""
    overrides = {field.name: getattr(args, field.name) for field in dataclasses.fields(options)
                 if field.metadata["flag"] and getattr(args, field.name, None) is not None}
    return dataclasses.replace(options, **overrides)
