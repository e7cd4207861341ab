"""Local wear laws: how fast each phase wears under a pressure.

A wear law gives the local wear rate ``dw/ds = g_i(p)`` of phase ``i``
(m of depth per m of sliding) at the contact pressure ``p``.  Everything the
model asks of a law goes through one object:

- ``n_phases`` and ``describe()``;
- the steady state (paper eq. 3-7): every point wears at the same rate,
  ``g_i(p_i) = C``, and the phases carry the load, ``sum_i A_i p_i = F``:
  :meth:`~PowerLaw.phase_pressures` inverts it;
- the run-in (:mod:`transient`): the rate of every pixel,
  :meth:`~PowerLaw.rate`, from the per-pixel coefficients of a phase map
  (:meth:`~PowerLaw.coefficient_field`); its linearisation about a
  pressure for an implicit stage (:meth:`~PowerLaw.linearisation`); the
  slope ``dg/dp`` that bounds an explicit step
  (:meth:`~PowerLaw.largest_rate_slope`); and the rate constant that sets
  the natural sliding distances (:meth:`~PowerLaw.rate_constant`).

Laws are registered in :data:`WEAR_LAWS` with their ``[wear]`` keys
(``[wear] law``, default ``"power"``); docs/model.md ("The code") shows
how a law is added, with :class:`ArchardLaw` as the example.  The laws are
the power law ``g_i(p) = k_i p^m`` and Archard's ``k_i p`` (paper eq. 1-2),
the power law with ``m = 1``.

Examples
--------
>>> law = PowerLaw((1e-13, 1e-12))
>>> law.phase_pressures([50, 50], 11.0, 1.0)       # eq. 7: 10 : 1
array([0.2 , 0.02])
>>> law.linear, law.n_phases
(True, 2)
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from .labels import validate_labels
from .pressures import phase_pressures
from .schema import Context, Key, Registry
from .text import shorten

__all__ = ["WEAR_LAWS", "ArchardLaw", "PowerLaw", "as_wear_law", "pressure_field",
           "wear_law_from_table"]

#: Registered wear laws, by ``[wear] law`` (default ``"power"``).
WEAR_LAWS = Registry("wear law", "law", default="power")


@WEAR_LAWS.register("power", (
    Key("coefficients", "numbers", unit="1/Pa", low=0.0, required=True,
        doc="k_i = k_wear,i / sigma_0,i, one per phase (Pa^-m for an exponent m != 1)"),
    Key("exponent", "number", unit="1", low=0.0, default=1.0,
        doc="m in dw/ds = k p^m (default 1: Archard)")),
    doc="dw/ds = k_i p^m: Archard's law for m = 1, the paper's")
@dataclasses.dataclass(frozen=True)
class PowerLaw:
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

    def __post_init__(self):
        """Check the coefficients and the exponent; store them as floats."""
        try:
            k = tuple(float(v) for v in np.atleast_1d(np.asarray(self.coefficients,
                                                                 dtype=float)).ravel())
            shape = np.shape(self.coefficients)
        except (TypeError, ValueError):
            raise ValueError(f"wear coefficients must be numbers (1/Pa), got "
                             f"{shorten(self.coefficients)}") from None
        if len(shape) > 1 or not k:
            raise ValueError(f"wear coefficients must be a list of numbers, one per phase, got "
                             f"{shorten(self.coefficients)}")
        if not all(math.isfinite(v) and v > 0 for v in k):
            raise ValueError(f"wear coefficients must be positive and finite (1/Pa), got "
                             f"{shorten(list(k))}")
        if isinstance(self.exponent, bool):
            raise ValueError(f"wear exponent must be a number, got {self.exponent!r}")
        try:
            m = float(self.exponent)
        except (TypeError, ValueError):
            raise ValueError(f"wear exponent must be a number, got "
                             f"{shorten(self.exponent)}") from None
        if not (math.isfinite(m) and m > 0):
            raise ValueError(f"wear exponent must be positive and finite, got {shorten(m)}")
        object.__setattr__(self, "coefficients", k)
        object.__setattr__(self, "exponent", m)

    @classmethod
    def from_values(cls, values, context):
        """From the checked ``[wear]`` keys; their count must be the phase map's."""
        k = values["coefficients"]
        if context.n_phases is not None and len(k) != context.n_phases:
            raise ValueError(f"[wear] coefficients has {len(k)} values {shorten(list(k))} but "
                             f"the phase map has {context.n_phases} phases")
        return cls(k, values["exponent"])

    # -- what every law says -------------------------------------------
    @property
    def n_phases(self):
        """Number of phases ``P``."""
        return len(self.coefficients)

    @property
    def linear(self):
        """Whether the rate is linear in the pressure (``m = 1``, Archard)."""
        return self.exponent == 1.0

    def describe(self):
        """The law in words."""
        k = ", ".join(f"{v:.4g}" for v in self.coefficients)
        if self.linear:
            return f"Archard's law dw/ds = k p, k = [{k}] 1/Pa"
        return f"power law dw/ds = k p^{self.exponent:g}, k = [{k}] Pa^-{self.exponent:g}"

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
    def coefficient_field(self, labels):
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

    def rate(self, pressure, coefficient_field):
        """Wear rate ``k p^m`` of every pixel, dimensionless (m/m); zero where ``k`` is.

        Parameters
        ----------
        pressure : ndarray, shape (nx, ny), Pa
            Negative values count as 0.
        coefficient_field : ndarray, shape (nx, ny), 1/Pa
            :meth:`coefficient_field`.
        """
        p = np.maximum(pressure, 0.0)
        if self.linear:
            return coefficient_field * p
        return coefficient_field * p ** self.exponent

    def linearisation(self, height, c, pressure, coefficient_field, face_mask, floor):
        """The implicit stage ``w = height + c g(P(w))`` linearised about ``pressure``.

        ``g(p) ~ g(p0) + g'(p0) (p - p0)`` turns the stage into the contact
        problem with the shift ``c g'(p0)`` and the height
        ``height + c (g(p0) - g'(p0) p0)``.

        Parameters
        ----------
        height : ndarray, shape (nx, ny), m
        c : float, m
            Sliding distance multiplying the implicit rate.
        pressure : ndarray, shape (nx, ny), Pa
            The linearisation point ``p0``.
        coefficient_field : ndarray, shape (nx, ny), 1/Pa
        face_mask : ndarray of bool, shape (nx, ny)
        floor : float, Pa
            Least linearisation pressure where ``g'`` is infinite at 0
            (``m < 1``); not used for ``m >= 1``.

        Returns
        -------
        shift : ndarray, shape (nx, ny), m/Pa
        height : ndarray, shape (nx, ny), m
        """
        m = self.exponent
        floor = floor if m < 1.0 else 0.0
        # Off the face the wear coefficient is 0; 1 keeps p^(m-1) finite there.
        pl = np.where(face_mask, np.maximum(pressure, floor), 1.0)
        shift = c * coefficient_field * m * pl ** (m - 1.0)
        h_lin = height + c * coefficient_field * (1.0 - m) * pl ** m
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
    Key("coefficients", "numbers", unit="1/Pa", low=0.0, required=True,
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


def as_wear_law(wear):
    """A wear law: ``wear`` itself, or Archard's law of a sequence of coefficients (1/Pa).

    Examples
    --------
    >>> as_wear_law([1e-13, 1e-12])
    PowerLaw(coefficients=(1e-13, 1e-12), exponent=1.0)
    """
    if isinstance(wear, PowerLaw) or hasattr(wear, "phase_pressures"):
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
