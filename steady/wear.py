"""Local wear laws: how fast each phase wears under a pressure.

A wear law gives the local wear rate ``dw/ds = g_i(p)`` of phase ``i``
(m of depth per m of sliding) at the contact pressure ``p``.  Every law is
a :class:`WearLaw`: the class states, once, what the model asks of a law,
and every caller asks the law (its methods and its capabilities), never
which class it is.

- Identity: ``n_phases`` (:meth:`WearLaw.check_phase_count` refuses a map of
  another count), ``describe()``, its ``[wear]`` values as a scene
  file writes them (:meth:`WearLaw.scene_values`, :meth:`WearLaw.scene_words`
  for messages) and the attributes result and run files record
  (:meth:`WearLaw.file_attributes`, read back by :func:`wear_law_from_file`).
- The steady state (paper eq. 3-7): every point wears at the same rate,
  ``g_i(p_i) = C``, and the phases carry the load, ``sum_i A_i p_i = F``:
  :meth:`WearLaw.phase_pressures` inverts it; :meth:`WearLaw.restrict` is
  the law of some of the phases (a section of a depth-varying map).
- The run-in (:mod:`transient`): the per-pixel field of a phase map
  (:meth:`WearLaw.wear_field`), the rate of every pixel
  (:meth:`WearLaw.rate`), the linearisation of an implicit stage about a
  pressure (:meth:`WearLaw.linearisation`), the largest ``g'`` that bounds an
  explicit step (:meth:`WearLaw.largest_rate_slope`) and the rate constant
  ``g'(pbar)`` that sets the natural distances (:meth:`WearLaw.rate_constant`).
- Capabilities, which a law states and callers ask: :attr:`WearLaw.linear`
  (``g_i = k_i p``: the run-in's linear path) and :attr:`WearLaw.factor`
  (``g_i = k_i g(p)`` with one ``g`` for every phase, a
  :class:`Factorisation`: a per-pixel factor on ``k`` -- the sliding speed,
  the coefficients of a section met at depth -- is then a field of ``k``;
  its ``exponent`` says whether ``g = p^m``, the model of the fit of wear
  ratios).

Laws are registered in :data:`WEAR_LAWS` with their ``[wear]`` keys
(``[wear] law``, default ``"power"``); docs/model.md ("The code") shows how
a law is added.  The laws here are the power law ``g_i(p) = k_i p^m`` and
Archard's ``k_i p`` (paper eq. 1-2), the power law with ``m = 1``; the
threshold law ``k_i max(p - p_th,i, 0)^m`` (:class:`ThresholdLaw`) and a
tabulated monotone rate ``g_i(p)`` (:class:`TableLaw`).  The last two key
their per-pixel field by phase (phase + 1, 0 off the face), are not linear
(the run-in takes its Newton path) and do not factorise.

Examples
--------
>>> law = PowerLaw((1e-13, 1e-12))
>>> law.phase_pressures([50, 50], 11.0, 1.0)       # eq. 7: 10 : 1
array([0.2 , 0.02])
>>> law.linear, law.n_phases, law.factor.exponent
(True, 2, 1.0)
>>> law.restrict([1]).coefficients
(1e-12,)
"""

from __future__ import annotations

import abc
import dataclasses
import json
import math

import numpy as np

from .labels import validate_labels
from .pressures import phase_pressures
from .schema import Context, Key, KindRegistry
from .text import shorten

__all__ = ["WEAR_LAWS", "ArchardLaw", "Factorisation", "PowerLaw", "TableLaw", "ThresholdLaw",
           "WearLaw", "as_wear_law", "pressure_field", "wear_coefficient_units",
           "same_wear_law", "wear_file_attributes", "wear_law_from_file",
           "wear_law_from_table"]

#: Registered wear laws, by ``[wear] law`` (default ``"power"``).
WEAR_LAWS = KindRegistry("wear law", "law", default="power", entry_point_group="runin.wear_laws")


def wear_coefficient_units(exponent):
    """The udunits unit of the coefficients ``k`` of the wear law ``dw/ds = k p^m``: ``Pa-m``.

    Parameters
    ----------
    exponent : float
        ``m``.

    Returns
    -------
    str
        ``"Pa-1"`` for Archard's law; udunits has integer powers only, so
        a fractional exponent gives ``"Pa^-1.5"``, which it cannot parse.

    Examples
    --------
    >>> wear_coefficient_units(1.0), wear_coefficient_units(2), wear_coefficient_units(1.5)
    ('Pa-1', 'Pa-2', 'Pa^-1.5')
    """
    m = float(exponent)
    return f"Pa-{m:.0f}" if m == round(m) else f"Pa^-{m:g}"


def _plain(value):
    """A value as TOML would hold it: floats, lists of floats (no numpy scalars or tuples)."""
    if isinstance(value, (list, tuple, np.ndarray)):
        return [_plain(v) for v in value]
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    return float(value)


class Factorisation(abc.ABC):
    """A law whose rate is ``k_i g(p)``: a coefficient per phase times one function of ``p``.

    Such a law's per-pixel field (:meth:`WearLaw.wear_field`) is the
    coefficient ``k`` itself, so a factor on it -- the sliding speed
    ``v / v_ref``, the coefficients of the section a pixel has worn down to
    -- is again a field the law takes.

    Attributes
    ----------
    coefficients : tuple of float, shape (P,)
        ``k_i`` of the phases.
    exponent : float or None
        ``m`` when ``g(p) = p^m`` (the fit's model, and closed forms), else
        None.
    """

    coefficients = ()
    exponent = None

    @abc.abstractmethod
    def rate(self, pressure):
        """``g(p)`` of every entry (the rate of a unit coefficient), m/m per unit ``k``."""

    @abc.abstractmethod
    def pixel_pressures(self, coefficients, normal_force, pixel_area):
        """Steady pressure of pixels of coefficients ``k_j``: ``k_j g(p_j) = C``, load ``F``.

        Every face pixel is its own phase: ``sum_j h^2 p_j = F``.

        Parameters
        ----------
        coefficients : ndarray, shape (nx, ny)
            ``k`` of every pixel (times any factor), positive on the face,
            zero off it.
        normal_force : float, N
        pixel_area : float, m^2

        Returns
        -------
        ndarray, shape (nx, ny), Pa
            Zero off the face.
        """


@dataclasses.dataclass(frozen=True)
class PowerFactorisation(Factorisation):
    """``k_i p^m``: the factorisation of the power law (:attr:`PowerLaw.factor`)."""

    coefficients: tuple
    exponent: float

    def rate(self, pressure):
        """``max(p, 0)^m``."""
        p = np.maximum(pressure, 0.0)
        return p if self.exponent == 1.0 else p ** self.exponent

    def pixel_pressures(self, coefficients, normal_force, pixel_area):
        """Eq. 7 with every face pixel its own phase (:func:`steady.pressures.phase_pressures`).

        ``p_j = F (k_j)^(-1/m) / (h^2 sum_l k_l^(-1/m))``.
        """
        coefficients = np.asarray(coefficients, dtype=float)
        on = coefficients > 0
        pressure = np.zeros(coefficients.shape)
        k = coefficients[on]
        pressure[on] = phase_pressures(np.ones(k.size), k, normal_force, pixel_area,
                                       exponent=self.exponent)
        return pressure


class WearLaw(abc.ABC):
    """The contract of a local wear law ``dw/ds = g_i(p)`` of each phase.

    A law is a frozen object built from its values (:meth:`from_values`,
    what a scene's ``[wear]`` table holds once checked through the keys it
    is registered with, :data:`WEAR_LAWS`).  The abstract methods are what
    every law provides; the concrete ones derive from them and from the
    keys, and a law overrides them only where its files or messages differ.

    Attributes
    ----------
    kind : str
        ``[wear] law`` (set by :meth:`steady.schema.Registry.register`; ""
        for a law that is not registered).
    keys : tuple of steady.schema.Key
        Its ``[wear]`` keys; those marked ``per_phase`` hold one entry per
        phase (:meth:`restrict` keeps the entries of the phases kept).
    linear : bool
        Whether ``g_i(p) = k_i p`` (Archard): the run-in then solves each
        implicit stage once, with the stitched preconditioner's phase levels
        and the warm start's kept Gram matrices.  Default False: Newton.
    factor : Factorisation or None
        The factorisation ``g_i = k_i g(p)``, if the law has one (default
        None): needed by non-uniform sliding (``[sliding]``), run-ins across
        interfaces (a depth-varying map) and, with ``exponent``, the fit of
        wear ratios.
    rate_constant_words : str
        What :meth:`rate_constant` is, in the law's terms, for messages
        (default ``"dg/dp at pbar"``; the power law's ``"dg/dp at pbar =
        k m pbar^(m-1)"``).
    """

    kind = ""
    keys = ()
    linear = False
    factor = None
    #: The rate constant in the law's terms, for messages (:meth:`rate_constant`).
    rate_constant_words = "dg/dp at pbar"

    # -- identity ----------------------------------------------------------
    @property
    @abc.abstractmethod
    def n_phases(self):
        """Number of phases ``P``."""

    @abc.abstractmethod
    def describe(self):
        """The law in words (summaries, files)."""

    @abc.abstractmethod
    def scene_values(self):
        """The law's ``[wear]`` values, by key, as a scene file writes them.

        Returns
        -------
        dict of str to float, list of float or list of list of float
            One entry per key of :attr:`keys` (without ``law``).
        """

    @classmethod
    @abc.abstractmethod
    def from_values(cls, values, context):
        """The law of its checked ``[wear]`` values (:meth:`scene_values` read back).

        ``context`` is a :class:`steady.schema.Context`: its ``n_phases``,
        when not None, is the number of phases the law must have.
        """

    def scene_words(self):
        """The law as a scene names it, for messages: ``[wear] law = 'threshold', k = ...``."""
        words = ", ".join(f"{name} = {shorten(value)}"
                          for name, value in self.scene_values().items())
        # The default law goes without saying, as a scene file may leave it out.
        law = f"law = {self.kind!r}, " if self.kind not in ("", WEAR_LAWS.default) else ""
        return f"[wear] {law}{words}"

    def check_phase_count(self, n_phases, what="the phase map", key=None):
        """Refuse a phase map of another number of phases than the law's.

        Parameters
        ----------
        n_phases : int
            The phases of ``what``.
        what : str, optional
            What has them, for the message (default ``"the phase map"``).
        key : str, optional
            The key of ``what`` that gives ``n_phases``, named with its value
            (``[phases] map n_phases = 10``); default None: none does.

        Raises
        ------
        ValueError
            ``n_phases`` is not :attr:`n_phases`; the message names the
            law's first per-phase key (:attr:`keys`) and its values.
        """
        if n_phases == self.n_phases:
            return
        has = (f"{what} {key} = {shorten(n_phases)}" if key is not None
               else f"{what} has {shorten(n_phases)} phases")
        values = self.scene_values()
        per_phase = next((k for k in self.keys if k.per_phase), None)
        if per_phase is None:
            raise ValueError(f"{self.scene_words()} is a law of {self.n_phases} phase(s) but "
                             f"{has}")
        entries = "values" if per_phase.type == "numbers" else "lists"
        raise ValueError(f"[wear] {per_phase.name} has {len(values[per_phase.name])} {entries} "
                         f"{shorten(values[per_phase.name])} but {has}")

    def file_attributes(self):
        """What result and run files record of the law: ``name -> (value, udunits unit)``.

        By default ``wear_<key>`` for each key: numbers as float arrays, a
        list of lists as JSON text.  :func:`wear_law_from_file` reads them
        back (:meth:`from_file_attributes`).
        """
        values, out = self.scene_values(), {}
        for key in self.keys:
            value = values[key.name]
            if key.type == "number_lists":
                value = json.dumps(value)
            elif key.type in ("numbers", "integers", "pairs"):
                value = np.asarray(value, dtype=float)
            out[f"wear_{key.name}"] = (value, key.unit or None)
        return out

    @classmethod
    def from_file_attributes(cls, attrs):
        """The law of the attributes :meth:`file_attributes` wrote (a mapping ``name -> value``).

        Raises
        ------
        ValueError
            An attribute missing or not a value of its key.
        """
        values = {}
        for key in cls.keys:
            name = f"wear_{key.name}"
            if name not in attrs:
                if key.required:
                    raise ValueError(f"the {cls.kind} wear law lacks the attribute {name!r}")
                continue
            value = attrs[name]
            if isinstance(value, bytes):
                value = value.decode()
            value = json.loads(value) if key.type == "number_lists" else _plain(
                np.atleast_1d(value) if key.type in ("numbers", "integers", "pairs") else value)
            values[key.name] = key.parse(value, "")
        return cls.from_values(values, Context())

    def restrict(self, phases):
        """The law of some of the phases only, renumbered ``0..len(phases)-1`` in that order.

        A section that lacks a phase (:meth:`steady.problem.Problem.section`)
        has the steady state of the law of its present phases: the absent one
        carries no load.  By default the entries of the keys marked
        ``per_phase`` are kept for those phases and the law rebuilt.

        Parameters
        ----------
        phases : sequence of int
            Phases kept, each in ``0..P-1``.
        """
        phases = [int(i) for i in phases]
        if not phases or min(phases) < 0 or max(phases) >= self.n_phases:
            raise ValueError(f"phases {phases} must be a non-empty subset of "
                             f"0..{self.n_phases - 1}")
        values = dict(self.scene_values())
        for key in self.keys:
            if key.per_phase:
                values[key.name] = tuple(values[key.name][i] for i in phases)
        return type(self).from_values(values, Context(n_phases=len(phases)))

    # -- the steady state ----------------------------------------------------
    @abc.abstractmethod
    def phase_pressures(self, counts, normal_force, pixel_area):
        """Steady pressure of each phase: ``g_i(p_i) = C`` with ``sum_i A_i p_i = F`` (eq. 3-7).

        Parameters
        ----------
        counts : array_like, shape (P,)
            Face pixels of each phase (or any measure proportional to the
            phase areas, e.g. fill factors with ``pixel_area`` 1); a phase
            of count 0 carries no load.
        normal_force : float, N
        pixel_area : float, m^2

        Returns
        -------
        ndarray, shape (P,), Pa

        Raises
        ------
        ValueError
            No steady state with every phase wearing, in the law's terms.
        """

    # -- the run-in, pixel by pixel ------------------------------------------
    @abc.abstractmethod
    def wear_field(self, labels):
        """The law's per-pixel field of a phase map (``labels < 0`` off the face: 0 there).

        Whatever :meth:`rate` and the other run-in methods take: ``k`` of the
        pixel's phase for a law with a :attr:`factor`, a phase key otherwise.

        Parameters
        ----------
        labels : ndarray of int, shape (nx, ny)

        Returns
        -------
        ndarray, shape (nx, ny)
        """

    @abc.abstractmethod
    def rate(self, pressure, wear_field):
        """Wear rate ``g(p)`` of every pixel, m/m; zero off the face and for ``p <= 0``.

        Parameters
        ----------
        pressure : ndarray, shape (nx, ny), Pa
        wear_field : ndarray, shape (nx, ny)
            :meth:`wear_field`.
        """

    @abc.abstractmethod
    def linearisation(self, recession, c, pressure, wear_field, face_mask, floor):
        """The implicit stage ``w = recession + c g(P(w))`` linearised about ``pressure``.

        ``g(p) ~ g(p0) + g'(p0) (p - p0)`` turns the stage into the contact
        problem with the shift ``c g'(p0)`` and the recession
        ``recession + c (g(p0) - g'(p0) p0)``.

        Parameters
        ----------
        recession : ndarray, shape (nx, ny), m
        c : float, m
            Sliding distance multiplying the implicit rate.
        pressure : ndarray, shape (nx, ny), Pa
            The linearisation point ``p0``.
        wear_field : ndarray, shape (nx, ny)
        face_mask : ndarray of bool, shape (nx, ny)
        floor : float, Pa
            Least linearisation pressure where ``g'`` is infinite at 0.

        Returns
        -------
        shift : ndarray, shape (nx, ny), m/Pa
        recession : ndarray, shape (nx, ny), m
        """

    @abc.abstractmethod
    def largest_rate_slope(self, pressure, coefficients, floor):
        """``max dg/dp`` over the pixels given, 1/Pa (m/Pa per m of sliding).

        Parameters
        ----------
        pressure : ndarray, Pa
        coefficients : ndarray
            Their :meth:`wear_field` entries, the same shape.
        floor : float, Pa
            Least pressure taken where ``g'`` is infinite at 0.
        """

    @abc.abstractmethod
    def rate_constant(self, field, mean_pressure):
        """The slope ``g'`` of the rate at the mean pressure, of pixels of the given field, 1/Pa.

        The rate at which a pressure difference wears the face flat; with
        ``E*`` and a length it sets the natural sliding distances
        (``s* = L / (g' E*)``): ``dg/dp`` at ``pbar`` for a smooth law
        (:attr:`rate_constant_words` says which slope), positive wherever
        the law has a steady state.  ``field`` holds :meth:`wear_field`
        entries (one per phase: ``wear_field(np.arange(P))``).
        """


def _per_phase(values, key):
    """The values of a per-phase ``key`` given in Python, checked through the key.

    ``values`` may be any sequence or array, or a number for one phase; the
    scale range (of a threshold pressure) is a problem's to check.
    """
    try:
        array = np.atleast_1d(np.asarray(values, dtype=float))
    except (TypeError, ValueError):
        array = None
    if array is None or array.ndim != 1 or not array.size:
        raise ValueError(f"wear {key.name} must be {key.describe()}, one per phase, got "
                         f"{shorten(values)}")
    return key.parse(array.tolist(), "wear", scale=False)


#: The power law's keys; a law built in Python checks its values through them too.
_COEFFICIENTS = Key("coefficients", "numbers", unit="1/Pa", low=0.0, required=True,
                    per_phase=True,
                    doc="k_i = k_wear,i / sigma_0,i, one per phase (Pa^-m for an exponent "
                        "m != 1)")
_EXPONENT = Key("exponent", "number", unit="1", low=0.0, default=1.0,
                doc="m in dw/ds = k p^m (default 1: Archard)")


@WEAR_LAWS.register("power", (_COEFFICIENTS, _EXPONENT),
                    doc="dw/ds = k_i p^m: Archard's law for m = 1, the paper's")
@dataclasses.dataclass(frozen=True)
class PowerLaw(WearLaw):
    """The power law ``dw/ds = k_i p^m`` of each phase (Archard's for ``m = 1``).

    Parameters
    ----------
    coefficients : sequence of float, shape (P,), 1/Pa (Pa^-m)
        ``k_i = k_wear,i / sigma_0,i`` of each phase, positive and finite.
    exponent : float, optional
        ``m``, positive and finite (default 1, Archard).

    Raises
    ------
    ValueError
        A coefficient or the exponent not positive and finite; the message
        gives the values.
    """

    coefficients: tuple
    exponent: float = 1.0
    rate_constant_words = "dg/dp at pbar = k m pbar^(m-1)"

    def __post_init__(self):
        """Check the coefficients and the exponent; store them as floats."""
        k = _per_phase(self.coefficients, _COEFFICIENTS)
        m = _EXPONENT.parse(self.exponent, "wear")
        object.__setattr__(self, "coefficients", k)
        object.__setattr__(self, "exponent", m)

    @classmethod
    def from_values(cls, values, context):
        """From the checked ``[wear]`` keys; their count must be the phase map's."""
        law = cls(values["coefficients"], values["exponent"])
        if context.n_phases is not None:
            law.check_phase_count(context.n_phases)
        return law

    # -- what every law says -------------------------------------------
    @property
    def n_phases(self):
        """Number of phases ``P``."""
        return len(self.coefficients)

    @property
    def linear(self):
        """Whether the rate is linear in the pressure (``m = 1``, Archard)."""
        return self.exponent == 1.0

    @property
    def factor(self):
        """``k_i p^m``: the coefficients and ``g(p) = p^m`` (:class:`PowerFactorisation`)."""
        return PowerFactorisation(self.coefficients, self.exponent)

    def describe(self):
        """The law in words."""
        k = ", ".join(f"{v:.4g}" for v in self.coefficients)
        if self.linear:
            return f"Archard's law dw/ds = k p, k = [{k}] 1/Pa"
        return f"power law dw/ds = k p^{self.exponent:g}, k = [{k}] Pa^-{self.exponent:g}"

    def scene_values(self):
        """``coefficients`` and ``exponent``."""
        return {"coefficients": list(self.coefficients), "exponent": self.exponent}

    def file_attributes(self):
        """``wear_coefficients`` (unit ``Pa-m``) and ``exponent``."""
        return {"wear_coefficients": (np.asarray(self.coefficients, dtype=float),
                                      wear_coefficient_units(self.exponent)),
                "exponent": (self.exponent, "1")}

    @classmethod
    def from_file_attributes(cls, attrs):
        """The law of ``wear_coefficients`` and ``exponent`` (:meth:`file_attributes`)."""
        missing = [name for name in ("wear_coefficients", "exponent") if name not in attrs]
        if missing:
            raise ValueError(f"the {cls.kind} wear law lacks the attribute {missing[0]!r}")
        k = tuple(float(v) for v in np.atleast_1d(attrs["wear_coefficients"]))
        return cls.from_values({"coefficients": k, "exponent": float(attrs["exponent"])},
                               Context())

    # -- the steady state ----------------------------------------------
    def phase_pressures(self, counts, normal_force, pixel_area):
        """Steady pressure of each phase: ``k_i p_i^m = C`` with ``sum_i A_i p_i = F`` (eq. 7).

        Parameters
        ----------
        counts : array_like, shape (P,) or (..., P)
            Face pixels of each phase (or any measure proportional to the
            phase areas, e.g. fill factors with ``pixel_area`` 1).
        normal_force : float, N
        pixel_area : float, m^2

        Returns
        -------
        ndarray, shape of ``counts``, Pa
            :func:`steady.pressures.phase_pressures`.
        """
        return phase_pressures(counts, self.coefficients, normal_force, pixel_area,
                               exponent=self.exponent)

    # -- the run-in, pixel by pixel ------------------------------------
    def wear_field(self, labels):
        """``k`` of every pixel's phase, zero off the face (``labels < 0``), 1/Pa.

        Parameters
        ----------
        labels : ndarray of int, shape (nx, ny)

        Returns
        -------
        ndarray, shape (nx, ny)
        """
        k = np.asarray(self.coefficients)
        return np.where(labels >= 0, k[np.maximum(labels, 0)], 0.0)

    def rate(self, pressure, wear_field):
        """Wear rate ``k p^m`` of every pixel, dimensionless (m/m); zero where ``k`` is.

        Parameters
        ----------
        pressure : ndarray, shape (nx, ny), Pa
            Negative values count as 0.
        wear_field : ndarray, shape (nx, ny), 1/Pa
            :meth:`wear_field`.
        """
        p = np.maximum(pressure, 0.0)
        if self.linear:
            return wear_field * p
        return wear_field * p ** self.exponent

    def linearisation(self, recession, c, pressure, wear_field, face_mask, floor):
        """The stage linearised about ``pressure`` (:meth:`WearLaw.linearisation`).

        ``g' = k m p0^(m-1)``, with ``p0`` floored at ``floor`` for ``m < 1``
        (``g'`` is infinite at 0); ``floor`` is not used for ``m >= 1``.
        """
        m = self.exponent
        floor = floor if m < 1.0 else 0.0
        # Off the face the wear coefficient is 0; 1 keeps p^(m-1) finite there.
        pl = np.where(face_mask, np.maximum(pressure, floor), 1.0)
        shift = c * wear_field * m * pl ** (m - 1.0)
        h_lin = recession + c * wear_field * (1.0 - m) * pl ** m
        return shift, h_lin

    def largest_rate_slope(self, pressure, coefficients, floor):
        """``max dg/dp = max k m p^(m-1)`` over the pixels given, 1/m (m/Pa per m of sliding).

        Parameters
        ----------
        pressure : ndarray, Pa
            Pressures of the pixels (unused for ``m = 1``).
        coefficients : ndarray, 1/Pa
            Their ``k``, the same shape.
        floor : float, Pa
            Least pressure taken (``m < 1``).
        """
        if self.linear:
            return float(coefficients.max())
        m = self.exponent
        p = np.maximum(pressure, floor)
        return float(np.max(coefficients * m * p ** (m - 1.0)))

    def rate_constant(self, k, mean_pressure):
        """``dg/dp`` of a phase of coefficient ``k`` at the mean pressure: ``k m pbar^(m-1)``, 1/Pa.

        The rate at which a pressure difference wears the face flat; with
        ``E*`` and a length it sets the natural sliding distances
        (``s* = L / (k m pbar^(m-1) E*)``).
        """
        m = self.exponent
        return k * m * mean_pressure ** (m - 1.0)


@WEAR_LAWS.register("archard", (
    Key("coefficients", "numbers", unit="1/Pa", low=0.0, required=True, per_phase=True,
        doc="k_i = k_wear,i / sigma_0,i, one per phase"),),
    doc="dw/ds = k_i p: Archard's law, the power law with m = 1")
@dataclasses.dataclass(frozen=True)
class ArchardLaw(PowerLaw):
    """Archard's law ``dw/ds = k_i p`` (paper eq. 1-2): the power law with ``m = 1``.

    Parameters
    ----------
    coefficients : sequence of float, shape (P,), 1/Pa
        ``k_i`` of each phase, positive and finite.

    Examples
    --------
    >>> ArchardLaw((1e-13, 1e-12)).linear
    True
    """

    exponent: float = dataclasses.field(default=1.0, init=False)

    @classmethod
    def from_values(cls, values, context):
        """From the checked ``[wear]`` keys; their count must be the phase map's."""
        return cls(PowerLaw.from_values(dict(values, exponent=1.0), context).coefficients)

    def scene_values(self):
        """``coefficients``."""
        return {"coefficients": list(self.coefficients)}


def _phase_keys(labels):
    """The per-pixel field of a law with phase-wise parameters: phase + 1, 0 off the face."""
    labels = np.asarray(labels)
    return np.where(labels >= 0, labels + 1.0, 0.0)


def _phase_of(field):
    """Phase index + 1 of every entry of a :func:`_phase_keys` field (0 off the face)."""
    return np.rint(np.asarray(field, dtype=float)).astype(np.intp)


#: The threshold law's own key; a law built in Python checks its thresholds through it.
_THRESHOLDS = Key("thresholds", "numbers", unit="Pa", low=0.0, low_open=False, required=True,
                  per_phase=True, doc="p_th,i >= 0, one per phase: no wear at or below it")


@WEAR_LAWS.register("threshold", (
    dataclasses.replace(_COEFFICIENTS, doc="k_i, one per phase (Pa^-m for an exponent m != 1)"),
    _THRESHOLDS,
    dataclasses.replace(_EXPONENT, doc="m in dw/ds = k max(p - p_th, 0)^m (default 1)")),
    doc="dw/ds = k_i max(p - p_th,i, 0)^m: no wear up to a threshold pressure")
@dataclasses.dataclass(frozen=True)
class ThresholdLaw(WearLaw):
    """The threshold law ``dw/ds = k_i max(p - p_th,i, 0)^m`` of each phase.

    No wear at or below the threshold pressure ``p_th,i`` of phase ``i``;
    above it the power law of the excess pressure.  With every threshold 0
    it is the power law (its steady pressures bit for bit, see
    :meth:`phase_pressures`).

    Parameters
    ----------
    coefficients : sequence of float, shape (P,), 1/Pa (Pa^-m)
        ``k_i``, positive and finite.
    thresholds : sequence of float, shape (P,), Pa
        ``p_th,i``, finite and >= 0.
    exponent : float, optional
        ``m``, positive and finite (default 1).

    Raises
    ------
    ValueError
        A bad coefficient, threshold or exponent, or counts that differ.

    Examples
    --------
    >>> law = ThresholdLaw((1e-13, 1e-12), (0.0, 0.1))
    >>> law.phase_pressures([50, 50], 11.0, 1.0)    # p_th + eq. 7 for F - sum A p_th
    array([0.10909091, 0.11090909])
    """

    coefficients: tuple
    thresholds: tuple
    exponent: float = 1.0
    rate_constant_words = "dg/dp at p_th + pbar = k m pbar^(m-1)"

    def __post_init__(self):
        """Check the values (through :class:`PowerLaw`) and the thresholds."""
        power = PowerLaw(self.coefficients, self.exponent)
        p_th = _per_phase(self.thresholds, _THRESHOLDS)
        if len(p_th) != power.n_phases:
            raise ValueError(f"wear thresholds {shorten(list(p_th))} must be one per phase: "
                             f"{power.n_phases} coefficients {shorten(list(power.coefficients))}")
        object.__setattr__(self, "coefficients", power.coefficients)
        object.__setattr__(self, "thresholds", p_th)
        object.__setattr__(self, "exponent", power.exponent)

    @classmethod
    def from_values(cls, values, context):
        """From the checked ``[wear]`` keys; their count must be the phase map's."""
        k = PowerLaw.from_values(values, context).coefficients
        return cls(k, values["thresholds"], values["exponent"])

    @property
    def n_phases(self):
        """Number of phases ``P``."""
        return len(self.coefficients)

    def describe(self):
        """The law in words."""
        k = ", ".join(f"{v:.4g}" for v in self.coefficients)
        p = ", ".join(f"{v:.4g}" for v in self.thresholds)
        return (f"threshold law dw/ds = k max(p - p_th, 0)^{self.exponent:g}, k = [{k}] "
                f"Pa^-{self.exponent:g}, p_th = [{p}] Pa")

    def scene_values(self):
        """``coefficients``, ``thresholds`` and ``exponent``."""
        return {"coefficients": list(self.coefficients), "thresholds": list(self.thresholds),
                "exponent": self.exponent}

    def file_attributes(self):
        """The power law's (``wear_coefficients``, ``exponent``) and ``wear_thresholds`` (Pa)."""
        return {**PowerLaw(self.coefficients, self.exponent).file_attributes(),
                "wear_thresholds": (np.asarray(self.thresholds, dtype=float), "Pa")}

    @classmethod
    def from_file_attributes(cls, attrs):
        """The law of :meth:`file_attributes`."""
        power = PowerLaw.from_file_attributes(attrs)
        if "wear_thresholds" not in attrs:
            raise ValueError(f"the {cls.kind} wear law lacks the attribute 'wear_thresholds'")
        p_th = tuple(float(v) for v in np.atleast_1d(attrs["wear_thresholds"]))
        return cls(power.coefficients, p_th, power.exponent)

    def phase_pressures(self, counts, normal_force, pixel_area):
        """Steady pressures ``p_i = p_th,i + (eq. 7 for F_N - sum_j A_j p_th,j)``, Pa.

        ``k_i (p_i - p_th,i)^m = C`` with ``sum_i A_i p_i = F_N``: the
        excess pressures ``p_i - p_th,i`` are the power law's under the load
        the thresholds leave.

        Parameters
        ----------
        counts : array_like, shape (P,)
            Face pixels of each phase.
        normal_force : float, N
        pixel_area : float, m^2

        Returns
        -------
        ndarray, shape (P,), Pa

        Raises
        ------
        ValueError
            ``sum_i A_i p_th,i >= F_N``: no steady state in which every
            phase wears; the message gives the thresholds and the load.
        """
        counts = np.asarray(counts)
        p_th = np.asarray(self.thresholds)
        held = pixel_area * np.dot(counts, p_th)
        excess = normal_force - held
        if not excess > 0:
            raise ValueError(f"wear thresholds p_th = {shorten(list(self.thresholds))} Pa hold "
                             f"sum_i A_i p_th,i = {held:.6g} N at or above the load F_N = "
                             f"{normal_force:.6g} N: no steady state with every phase wearing "
                             f"(lower the thresholds or raise the load)")
        return p_th + phase_pressures(counts, self.coefficients, excess, pixel_area,
                                      exponent=self.exponent)

    def wear_field(self, labels):
        """The per-pixel key of the law: phase + 1, 0 off the face (``labels < 0``).

        Parameters
        ----------
        labels : ndarray of int, shape (nx, ny)

        Returns
        -------
        ndarray, shape (nx, ny)
        """
        return _phase_keys(labels)

    def _fields(self, field):
        """``k`` and ``p_th`` of the pixels of a :meth:`wear_field` (k = 0 off the face)."""
        phase = _phase_of(field)
        k = np.append(0.0, self.coefficients)[phase]
        return k, np.append(0.0, self.thresholds)[phase]

    def rate(self, pressure, wear_field):
        """Wear rate ``k max(p - p_th, 0)^m`` of every pixel, m/m; zero off the face."""
        k, p_th = self._fields(wear_field)
        q = np.maximum(np.asarray(pressure, dtype=float) - p_th, 0.0)
        return k * q if self.exponent == 1.0 else k * q ** self.exponent

    def linearisation(self, recession, c, pressure, wear_field, face_mask, floor):
        """The implicit stage linearised about ``pressure`` (see :meth:`PowerLaw.linearisation`).

        Below its threshold (``p0 < p_th``) a pixel's rate and slope are 0: no
        shift and the recession unchanged.  At or above it
        ``g ~ k q^m + k m q^(m-1) (p - p_th - q)`` with ``q = p0 - p_th``,
        floored at ``floor`` for ``m < 1``; for ``m < 1`` and a threshold
        the chord ``g ~ k q^(m-1) (p - p_th)`` instead.  With every threshold
        0 this is the power law's linearisation bit for bit.

        Returns
        -------
        shift : ndarray, shape (nx, ny), m/Pa
        recession : ndarray, shape (nx, ny), m
        """
        m = self.exponent
        floor = floor if m < 1.0 else 0.0
        k, p_th = self._fields(wear_field)
        above = face_mask & (pressure >= p_th)
        # Off the face and below the threshold k is taken as 0; 1 keeps q^(m-1) finite.
        k = np.where(above, k, 0.0)
        q = np.where(above, np.maximum(pressure - p_th, floor), 1.0)
        if m < 1.0 and any(self.thresholds):
            # The chord through (p_th, 0) and (p0, g(p0)): its slope k q^(m-1)
            # does not follow the tangent's towards the infinite slope at the
            # threshold, which pressures crossing it make Newton's iterates
            # jump across (a Kachanov-type iteration: slower, but it holds).
            shift = c * k * q ** (m - 1.0)
            return shift, recession - shift * p_th
        shift = c * k * m * q ** (m - 1.0)
        h_lin = recession + c * k * (1.0 - m) * q ** m - shift * p_th
        return shift, h_lin

    def largest_rate_slope(self, pressure, coefficients, floor):
        """``max dg/dp`` over the pixels given, 1/Pa: ``k m max(p - p_th, floor)^(m-1)``.

        For ``m = 1`` the largest ``k`` (the slope once above the threshold);
        below the threshold the pressure is taken at ``p_th + floor``.
        """
        k, p_th = self._fields(coefficients)
        m = self.exponent
        if m == 1.0:
            return float(k.max())
        q = np.maximum(np.asarray(pressure, dtype=float) - p_th, floor)
        return float(np.max(k * m * q ** (m - 1.0)))

    def rate_constant(self, field, mean_pressure):
        """``k m pbar^(m-1)``, 1/Pa: ``dg/dp`` at ``pbar`` above the phase's threshold.

        The slope of the rate at the mean pressure in excess of the
        threshold: the power law's rate constant, which sets the natural
        distances (the steady excess pressures are of order ``pbar``).
        """
        k, _ = self._fields(field)
        m = self.exponent
        return k * m * mean_pressure ** (m - 1.0)


def _check_table(i, pressures, rates):
    """One phase's table as float arrays; ``ValueError`` naming the phase and the bad values."""
    p, g = np.asarray(pressures, dtype=float), np.asarray(rates, dtype=float)
    name = f"wear table of phase {i}"
    if p.ndim != 1 or g.ndim != 1 or p.size != g.size:
        raise ValueError(f"{name}: pressures {shorten(list(pressures))} and rates "
                         f"{shorten(list(rates))} must be lists of the same length")
    if p.size < 2:
        raise ValueError(f"{name} needs at least 2 points, got {p.size}")
    if not (np.all(np.isfinite(p)) and np.all(np.isfinite(g))):
        raise ValueError(f"{name}: pressures and rates must be finite, got "
                         f"{shorten(p.tolist())} Pa and {shorten(g.tolist())}")
    if p[0] != 0.0 or g[0] != 0.0:
        raise ValueError(f"{name} must start at p = 0 Pa with rate 0 (no wear without "
                         f"pressure), got ({p[0]!r} Pa, {g[0]!r})")
    if not np.all(np.diff(p) > 0):
        raise ValueError(f"{name}: pressures must increase, got {shorten(p.tolist())} Pa")
    if not np.all(np.diff(g) >= 0):
        raise ValueError(f"{name}: rates must not decrease, got {shorten(g.tolist())}")
    if not g[-1] > 0:
        raise ValueError(f"{name}: the rate is 0 at every point {shorten(p.tolist())} Pa; "
                         f"the phase never wears")
    return p, g


def _as_tables(values, name):
    """A tuple of tuples of floats from lists of lists; ``ValueError`` naming ``name``."""
    try:
        return tuple(tuple(float(v) for v in row) for row in values)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be one list of numbers per phase, got "
                         f"{shorten(values)}") from None


@WEAR_LAWS.register("table", (
    Key("pressures", "number_lists", unit="Pa", required=True, per_phase=True,
        doc="one list per phase: increasing pressures p_i,j, the first 0"),
    Key("rates", "number_lists", unit="1", required=True, per_phase=True,
        doc="one list per phase: non-decreasing rates g_i(p_i,j) (m/m), the first 0")),
    doc="dw/ds = g_i(p): a monotone (PCHIP) interpolation of points per phase")
@dataclasses.dataclass(frozen=True)
class TableLaw(WearLaw):
    """A tabulated rate ``dw/ds = g_i(p)`` of each phase, interpolated monotonically.

    Between the points ``g_i`` is the monotone cubic (PCHIP,
    :class:`scipy.interpolate.PchipInterpolator`) through them; beyond the
    last point it continues linearly with the interpolant's slope there;
    the first point must be ``(0 Pa, 0)`` (no wear without pressure) and a
    negative pressure wears nothing.

    Parameters
    ----------
    pressures : sequence of sequence of float, shape (P, n_i), Pa
        Increasing pressures of each phase's points, the first 0.
    rates : sequence of sequence of float, shape (P, n_i), 1 (m/m)
        The rates there: non-decreasing, the first 0, the last positive.

    Raises
    ------
    ValueError
        A table that is not one of increasing pressures and non-decreasing
        rates of the same length, at least 2 points, starting at (0, 0);
        tables not one per phase.

    Examples
    --------
    >>> law = TableLaw(((0, 1e5, 2e5), (0, 1e5)), ((0, 1e-9, 4e-9), (0, 1e-8)))
    >>> law.rate(np.array([1e5, 3e5, 2e5]), law.wear_field(np.array([0, 0, 1])))
    array([1.e-09, 8.e-09, 2.e-08])
    """

    pressures: tuple
    rates: tuple
    rate_constant_words = "the secant g_i(z_i + pbar) / pbar above the last zero rate z_i"

    def __post_init__(self):
        """Check the tables; build the interpolants and their extrapolation slopes."""
        from scipy.interpolate import PchipInterpolator

        pressures = _as_tables(self.pressures, "wear table pressures")
        rates = _as_tables(self.rates, "wear table rates")
        if len(pressures) != len(rates) or not pressures:
            raise ValueError(f"wear tables need one list of pressures and one of rates per "
                             f"phase, got {len(pressures)} and {len(rates)}")
        splines, ends, zeros = [], [], []
        for i, (p, g) in enumerate(zip(pressures, rates, strict=True)):
            p, g = _check_table(i, p, g)
            spline = PchipInterpolator(p, g, extrapolate=False)
            splines.append((spline, spline.derivative()))
            ends.append((p[-1], g[-1], float(spline.derivative()(p[-1]))))
            zeros.append(float(p[np.flatnonzero(g > 0)[0] - 1]))
        object.__setattr__(self, "pressures", pressures)
        object.__setattr__(self, "rates", rates)
        object.__setattr__(self, "_splines", tuple(splines))
        object.__setattr__(self, "_ends", tuple(ends))
        #: Largest tabulated pressure of zero rate of each phase, Pa.
        object.__setattr__(self, "_zeros", tuple(zeros))

    @classmethod
    def from_values(cls, values, context):
        """From the checked ``[wear]`` keys; one table per phase of the phase map."""
        law = cls(values["pressures"], values["rates"])
        if context.n_phases is not None:
            law.check_phase_count(context.n_phases)
        return law

    # -- what every law says -------------------------------------------
    @property
    def n_phases(self):
        """Number of phases ``P``."""
        return len(self.pressures)

    def scene_values(self):
        """``pressures`` and ``rates``, one list per phase."""
        return {"pressures": [list(p) for p in self.pressures],
                "rates": [list(g) for g in self.rates]}

    def describe(self):
        """The law in words."""
        points = ", ".join(str(len(p)) for p in self.pressures)
        top = ", ".join(f"{p:.4g}" for p, _, _ in self._ends)
        return (f"tabulated law dw/ds = g_i(p) (PCHIP through [{points}] points up to "
                f"[{top}] Pa, linear beyond)")

    # -- one phase -------------------------------------------------------
    def phase_rate(self, i, pressure):
        """``g_i(p)`` of phase ``i``, m/m: PCHIP, linear beyond the last point, 0 for p <= 0."""
        spline, _ = self._splines[i]
        p_end, g_end, slope = self._ends[i]
        p = np.maximum(np.asarray(pressure, dtype=float), 0.0)
        inside = np.minimum(p, p_end)
        return np.where(p > p_end, g_end + slope * (p - p_end), spline(inside))

    def phase_slope(self, i, pressure):
        """``g_i'(p)``, 1/Pa (0 below 0, the end slope beyond the last point)."""
        _, derivative = self._splines[i]
        p_end, _, slope = self._ends[i]
        p = np.asarray(pressure, dtype=float)
        inside = np.clip(p, 0.0, p_end)
        return np.where(p > p_end, slope, np.where(p < 0, 0.0, derivative(inside)))

    def phase_pressure(self, i, rate):
        """``g_i^-1(C)`` for a rate ``C > 0``, Pa: the least pressure of that rate."""
        from scipy.optimize import brentq

        p, g = self.pressures[i], self.rates[i]
        p_end, g_end, slope = self._ends[i]
        if rate > g_end:
            return p_end + (rate - g_end) / slope if slope > 0 else math.inf
        j = int(np.searchsorted(g, rate))  # g[j-1] < rate <= g[j]
        if g[j] == rate:
            return p[j]
        spline, _ = self._splines[i]
        return brentq(lambda x: float(spline(x)) - rate, p[j - 1], p[j], xtol=1e-300,
                      rtol=4 * np.finfo(float).eps)

    # -- the steady state ----------------------------------------------
    def phase_pressures(self, counts, normal_force, pixel_area):
        """Steady pressures: ``g_i(p_i) = C`` with ``sum_i A_i p_i = F_N``, Pa, shape (P,).

        ``sum_i A_i g_i^-1(C)`` increases with ``C``: bracketed and solved by
        Brent's method in ``log C``.

        Raises
        ------
        ValueError
            A phase that cannot wear under the load (its rate is 0 up to the
            pressure it would carry alone), or tables whose zero-rate
            pressures hold the load; the load on a flat part of a table.
        """
        from scipy.optimize import brentq

        areas = np.asarray(counts, dtype=float) * pixel_area
        F = float(normal_force)
        zero = float(np.dot(areas, self._zeros))
        if not zero < F:
            raise ValueError(f"the wear tables give no wear up to p = {shorten(list(self._zeros))}"
                             f" Pa, which holds sum_i A_i p_i = {zero:.6g} N at or above the "
                             f"load F_N = {F:.6g} N: no steady state with every phase wearing")
        # A phase without area (a section missing it) carries nothing and bounds nothing.
        top = min(float(self.phase_rate(i, F / a)) for i, a in enumerate(areas) if a > 0)

        def excess(log_rate):
            C = math.exp(log_rate)
            return sum(a * self.phase_pressure(i, C) for i, a in enumerate(areas) if a > 0) - F

        hi = math.log(top)
        while excess(hi) < 0:  # rounding at a phase alone carrying the load at its rate
            hi += 1e-9 * max(1.0, abs(hi))
        lo = hi - 1.0
        while excess(lo) > 0:
            lo -= 1.0 + (hi - lo)
        log_rate = brentq(excess, lo, hi, xtol=1e-15, rtol=4 * np.finfo(float).eps)
        p = np.array([self.phase_pressure(i, math.exp(log_rate)) for i in range(len(areas))])
        balance = float(np.dot(areas[areas > 0], p[areas > 0]))
        if not abs(balance - F) <= 1e-9 * F:
            raise ValueError(self._flat_words(areas, math.exp(log_rate), F, balance))
        return p

    def _flat_words(self, areas, rate, force, balance):
        """Why the load falls on a flat part of a table: the phase, its table and the part."""
        flat = [(i, part) for i, a in enumerate(areas) if a > 0
                for part in [self._flat_part(i, rate)] if part is not None]
        if not flat:
            return (f"the load F_N = {force:.6g} N falls on a flat part of a wear table (the "
                    f"phases carry {balance:.6g} N at the rate {rate:.6g}): the steady pressures "
                    f"are not unique")
        i, (level, low, high) = flat[0]
        span = f"from {low:.6g} Pa on" if math.isinf(high) else f"from {low:.6g} to {high:.6g} Pa"
        return (f"the load F_N = {force:.6g} N falls on a flat part of the wear table of phase "
                f"{i} (pressures {shorten(list(self.pressures[i]))} Pa, rates "
                f"{shorten(list(self.rates[i]))}): its rate is {level:.6g} at every pressure "
                f"{span}, so the steady pressures are not unique (the least of that rate carry "
                f"{balance:.6g} N); a table that rises there, or another load")

    def _flat_part(self, i, rate):
        """``(level, low, high)``: the flat part of phase ``i``'s rate at ``rate``, or None.

        ``g_i = level`` (the tabulated rate within 1e-9 of ``rate``) on
        ``[low, high]`` Pa: between tabulated points of that rate (PCHIP is
        constant between equal rates), ``high`` inf when the rate stays
        there beyond the last point (an end slope of 0).
        """
        p, g = np.asarray(self.pressures[i]), np.asarray(self.rates[i])
        same = np.flatnonzero(np.isclose(g, rate, rtol=1e-9, atol=0))
        if not same.size:
            return None
        first, last = int(same[0]), int(same[-1])
        beyond = last == p.size - 1 and self._ends[i][2] == 0
        if first == last and not beyond:
            return None
        return float(g[first]), float(p[first]), math.inf if beyond else float(p[last])

    # -- the run-in, pixel by pixel ------------------------------------
    def wear_field(self, labels):
        """The per-pixel key of the law: phase + 1, 0 off the face (``labels < 0``)."""
        return _phase_keys(labels)

    def _by_phase(self, method, pressure, field):
        """``method(i, p)`` on the pixels of each phase, 0 off the face."""
        phase = _phase_of(field)
        p = np.broadcast_to(np.asarray(pressure, dtype=float), phase.shape)
        out = np.zeros(phase.shape)
        for i in range(self.n_phases):
            mine = phase == i + 1
            if mine.any():
                out[mine] = method(i, p[mine])
        return out

    def rate(self, pressure, wear_field):
        """Wear rate ``g_i(p)`` of every pixel, m/m; zero off the face."""
        return self._by_phase(self.phase_rate, pressure, wear_field)

    def linearisation(self, recession, c, pressure, wear_field, face_mask, floor):
        """The implicit stage linearised about ``pressure``: shift ``c g'(p0)``.

        The recession is ``recession + c (g(p0) - g'(p0) p0)``; ``floor`` is not
        used (the interpolant's slopes are finite).
        """
        field = np.where(face_mask, wear_field, 0.0)
        slope = self._by_phase(self.phase_slope, pressure, field)
        g = self._by_phase(self.phase_rate, pressure, field)
        return c * slope, recession + c * (g - slope * np.where(face_mask, pressure, 0.0))

    def largest_rate_slope(self, pressure, coefficients, floor):
        """``max g'(p)`` over the pixels given, 1/Pa."""
        return float(np.max(self._by_phase(self.phase_slope, pressure, coefficients)))

    def rate_constant(self, field, mean_pressure):
        """The secant ``g_i(z_i + pbar) / pbar``, 1/Pa, ``z_i`` the last zero-rate pressure.

        The table's mean slope over ``pbar`` above the pressure where the
        phase starts to wear: positive for every table (its rate rises
        above ``z_i``), where a tangent would vanish on a flat part; a
        linear table's slope.
        """
        phase = _phase_of(field)
        shifted = np.append(0.0, self._zeros)[phase] + mean_pressure
        return self._by_phase(self.phase_rate, shifted, field) / mean_pressure


def as_wear_law(wear):
    """A wear law: ``wear`` itself, or Archard's law of a sequence of coefficients (1/Pa).

    Examples
    --------
    >>> as_wear_law([1e-13, 1e-12])
    PowerLaw(coefficients=(1e-13, 1e-12), exponent=1.0)
    """
    if isinstance(wear, WearLaw):
        return wear
    return PowerLaw(wear)


def wear_law_from_table(table, base_dir=".", n_phases=None):
    """The wear law of a scene's ``[wear]`` table.

    Parameters
    ----------
    table : dict
        ``law`` (default ``"power"``) and the keys of that law.
    base_dir : path-like, optional
        Directory of the scene file.
    n_phases : int, optional
        Phases of the scene's phase map: the law must have as many.

    Returns
    -------
    wear law object

    Raises
    ------
    ValueError
        An unknown law, an unknown or missing key, a bad value, or a law for
        another number of phases; the message names them.

    Examples
    --------
    >>> wear_law_from_table({"coefficients": [1e-13, 1.7e-13], "exponent": 2})
    PowerLaw(coefficients=(1e-13, 1.7e-13), exponent=2.0)
    """
    import pathlib

    context = Context(base_dir=pathlib.Path(base_dir), n_phases=n_phases, where="[wear]")
    try:
        return WEAR_LAWS.build(table, context)
    except ValueError as err:
        message = str(err)
        raise ValueError(message if "[wear]" in message else f"[wear] {message}") \
            from None


def wear_file_attributes(wear):
    """What a result or run file records of a wear law: ``name -> (value, unit)``.

    ``wear_law_kind`` (its ``[wear] law``), ``wear_law`` (in words) and the
    law's own :meth:`WearLaw.file_attributes`; :func:`wear_law_from_file`
    reads them back.
    """
    return {"wear_law_kind": (wear.kind, None), "wear_law": (wear.describe(), None),
            **wear.file_attributes()}


def same_wear_law(a, b):
    """Whether two wear laws are the same law: the same file attributes, value for value.

    Archard's law and the power law of exponent 1 with the same
    coefficients are the same law; a threshold law is not the power law of
    its coefficients.  None (a law unknown) is the same as nothing.
    """
    if a is None or b is None:
        return False
    fa, fb = a.file_attributes(), b.file_attributes()
    return fa.keys() == fb.keys() and all(
        np.array_equal(np.asarray(fa[name][0]), np.asarray(fb[name][0])) for name in fa)


def wear_law_from_file(attrs):
    """The wear law a file recorded (:func:`wear_file_attributes`), or None if unknown.

    Parameters
    ----------
    attrs : mapping
        The file's attributes (``h5py`` attributes, or a dict of them).  A
        file written before ``wear_law_kind`` was recorded holds the power
        law's ``wear_coefficients`` and ``exponent``.

    Returns
    -------
    WearLaw or None
        None when the file names a law that is not registered (a law
        defined and registered by another program) or holds none.

    Raises
    ------
    ValueError
        A registered law whose attributes are missing or bad.
    """
    kind = attrs.get("wear_law_kind", "power")
    if isinstance(kind, bytes):
        kind = kind.decode()
    kind = str(kind)
    if kind not in WEAR_LAWS:
        return None
    if kind == "power" and "wear_coefficients" not in attrs:
        return None
    return WEAR_LAWS[kind].from_file_attributes(attrs)


def pressure_field(labels, wear, normal_force, pixel_area, *, face_mask=None):
    """Steady pressure at every pixel of a phase map (eq. 7 for the power law).

    Parameters
    ----------
    labels : ndarray, shape (nx, ny), int
        Phase index ``0..P-1`` on the face, -1 off it; every phase present
        (checked, :func:`steady.labels.validate_labels`).
    wear : wear law or sequence of float
        The law of the ``P`` phases (:func:`as_wear_law`: coefficients
        stand for Archard's law).
    normal_force : float, N
    pixel_area : float, m^2
        ``h^2``.
    face_mask : ndarray of bool, shape (nx, ny), optional
        The face's pixels, to check the labels against (default
        ``labels >= 0``).

    Returns
    -------
    pressure : ndarray, shape (nx, ny), Pa
        ``p_i`` on the pixels of phase ``i``, zero off the face.
    phase_pressures : ndarray, shape (P,), Pa
        The law's :meth:`~PowerLaw.phase_pressures`.
    counts : ndarray, shape (P,), int
        Face pixels of each phase.

    Raises
    ------
    ValueError
        Labels that do not fit the law's ``P`` phases.
    """
    wear = as_wear_law(wear)
    labels = np.asarray(labels)
    counts = validate_labels(labels, wear.n_phases, face_mask=face_mask)
    p = wear.phase_pressures(counts, normal_force, pixel_area)
    # Label -1 (off the face) picks the trailing zero.
    return np.append(p, 0.0)[labels], p, counts
