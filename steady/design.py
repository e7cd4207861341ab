"""Design rule: the fill factor that gives a target rms slope, and back.

The steady rms slope of a biphasic punch is ``grad_f0`` times a normalised
value that depends only on the fill factor ``rho_1`` and the wear ratio
``k_1 / k_0`` (eq. 15; ``grad_f0 = 4 pbar / (pi E*)``, eq. 12).  This module

- tabulates its realisation mean and scatter over random Voronoi maps
  (:class:`DesignTable`, an HDF5 file built from the sweep of
  :mod:`steady.voronoi_sweep`) and interpolates it monotonically (PCHIP in
  the fill factor and in ``log10`` of the wear ratio);
- inverts it: given ``pbar / E*``, the wear ratio and a target rms slope,
  the fill factor ``rho_1`` with its realisation scatter
  (:meth:`DesignTable.fill_factor_for`), and the reverse
  (:meth:`DesignTable.rms_slope`);
- answers both from the command line with the table shipped in the package
  (:data:`DEFAULT_TABLE`).

Phases are numbered from 0, as everywhere in runin: ``rho_1`` is the fill
factor of phase 1 and ``k_1 / k_0`` its wear coefficient over phase 0's (the
paper, which numbers from 1, writes ``rho_2`` and ``k_2 / k_1``).

The table is computed with Archard's law (``m = 1``) and takes no wear law:
it does not apply to the power law of another exponent, the threshold law
or a tabulated rate (:mod:`steady.wear`).

The fine-grain limit in closed form,
:func:`steady.reference.fine_grain_rms_slope`, is the check of the table.

Command line (``runin-design``, or ``python -m steady.cli.design``;
:mod:`steady.cli.design`)::

    runin-design --pbar-over-estar 0.08 --wear-ratio 1e-2 --target-slope 1.0
    runin-design --pbar-over-estar 0.08 --wear-ratio 1e-2 --fill-factor 0.1
"""

from __future__ import annotations

import dataclasses
import importlib.resources
import math
import os
import pathlib

import h5py
import numpy as np
from scipy import interpolate, optimize

from .array_files import input_file_size
from .safe_files import atomic_h5
from .schema import Key
from .text import one_line, shorten
from .validity import check_rms_slope

__all__ = [
    "DEFAULT_TABLE",
    "DesignResult",
    "DesignTable",
    "TABLE_FORMAT",
    "TABLE_VERSION",
]

TABLE_FORMAT = "runin.design_table"
TABLE_VERSION = 1

#: The table shipped as package data (``python studies/design_table.py``
#: builds it): a :class:`pathlib.Path` in an installed package.
DEFAULT_TABLE = importlib.resources.files("steady") / "data" / "design_table.h5"

#: A design's load, ``pbar / E*``, and its target steady rms slope.
_PBAR_OVER_ESTAR = Key("pbar_over_estar", "number", unit="1", low=0.0)
_TARGET_SLOPE = Key("target_slope", "number", unit="1", low=0.0)


@dataclasses.dataclass(frozen=True)
class DesignResult:
    """Fill factor for a target rms slope.

    Attributes
    ----------
    fill_factor : float
        ``rho_1`` at which the realisation-mean rms slope equals the target
        (the largest such ``rho_1`` if there are several).
    fill_factor_range : (float, float)
        The fill factors around it within which the target lies inside
        the realisation scatter (mean +- one standard deviation).
    solutions : tuple of float
        Every ``rho_1`` in the table's range that reaches the target.
    normalised_target : float
        ``target / grad_f0``.
    reachable : (float, float)
        Smallest and largest rms slope (not normalised) over the table's
        fill factors at this wear ratio and ``pbar / E*``.
    """

    fill_factor: float
    fill_factor_range: tuple
    solutions: tuple
    normalised_target: float
    reachable: tuple


class DesignTable:
    """Tabulated normalised rms slope ``S(rho_1, k_1/k_0)`` with its scatter.

    Parameters
    ----------
    fill_factors : array_like, shape (R,)
        Increasing ``rho_1`` nodes.
    ratios : array_like, shape (K,)
        Increasing wear ratios ``k_1 / k_0``.
    mean, scatter, error : array_like, shape (R, K), grad_f0
        Realisation mean, realisation standard deviation and
        discretisation error of the normalised rms slope.
    attrs : mapping, optional
        Provenance (grid, coarseness, realisations), stored with the table.

    Examples
    --------
    With the table shipped in the package (:data:`DEFAULT_TABLE`): the fill
    factor of a hard phase wearing a thousand times slower that gives an rms
    slope of 0.3 at ``pbar / E* = 0.08``, and the rms slope of a 30 % fill
    factor.  (The paper's tyre rule, an rms slope of 1, lies beyond the small
    slopes of the model, :mod:`steady.validity`: that query warns.)

    >>> table = DesignTable.read()
    >>> design = table.fill_factor_for(0.08, 1e-3, 0.3)
    >>> print(f"rho_1 = {design.fill_factor:.4f}")
    rho_1 = 0.2405
    >>> value, scatter = table.rms_slope(0.08, 1e-3, 0.3)
    >>> print(f"rms slope {value:.3f} +- {scatter:.3f}")
    rms slope 0.263 +- 0.002
    """

    def __init__(self, fill_factors, ratios, mean, scatter, error, attrs=None):
        self.fill_factors = np.asarray(fill_factors, dtype=float)
        self.ratios = np.asarray(ratios, dtype=float)
        self.mean = np.asarray(mean, dtype=float)
        self.scatter = np.asarray(scatter, dtype=float)
        self.error = np.asarray(error, dtype=float)
        self.attrs = dict(attrs or {})
        shape = (self.fill_factors.size, self.ratios.size)
        for name in ("mean", "scatter", "error"):
            if getattr(self, name).shape != shape:
                raise ValueError(f"{name} must have shape {shape}, got "
                                 f"{getattr(self, name).shape}")
        if np.any(np.diff(self.fill_factors) <= 0) or np.any(np.diff(self.ratios) <= 0):
            raise ValueError("table fill factors and ratios must be increasing")
        log_r = np.log10(self.ratios)
        self._along_ratio = {name: interpolate.PchipInterpolator(log_r, getattr(self, name),
                                                                  axis=1)
                             for name in ("mean", "scatter", "error")}

    @classmethod
    def from_voronoi(cls, data, level=0, attrs=None):
        """Table of one coarseness level of a :class:`steady.voronoi_sweep.VoronoiData`."""
        attrs = dict(attrs or {})
        attrs.update(n=data.n, n_seeds=int(data.n_seeds[level]),
                     realisations=int(data.seeds.size))
        return cls(data.fill_factors, data.ratios, data.mean[level], data.scatter[level],
                   data.mean_error[level], attrs)

    def write(self, path, *, force=False):
        """Write the table to HDF5 (layout ``runin.design_table``, version 1).

        Parameters
        ----------
        path : str or path-like
        force : bool, optional
            Replace an existing file (default False).

        Returns
        -------
        pathlib.Path

        Raises
        ------
        ValueError
            ``path`` exists and ``force`` is False, or is a directory
            (:func:`steady.safe_files.atomic_h5`).
        """
        path = pathlib.Path(path)
        with atomic_h5(path, format=TABLE_FORMAT, version=TABLE_VERSION, force=force) as f:
            for k, v in self.attrs.items():
                f.attrs[k] = v
            for name, unit in (("fill_factors", "1"), ("ratios", "1"), ("mean", "grad_f0"),
                               ("scatter", "grad_f0"), ("error", "grad_f0")):
                ds = f.create_dataset(name, data=getattr(self, name))
                ds.attrs["units"] = unit
        return path

    @classmethod
    def read(cls, path=None):
        """Read a table.

        Parameters
        ----------
        path : str or path-like, optional
            Default: the table shipped with the package,
            :data:`DEFAULT_TABLE`.

        Returns
        -------
        DesignTable

        Raises
        ------
        FileNotFoundError
            The file does not exist.
        ValueError
            A foreign, damaged or incomplete file.
        """
        if path is None:
            with importlib.resources.as_file(DEFAULT_TABLE) as shipped:
                return cls._read(pathlib.Path(shipped))
        return cls._read(pathlib.Path(path))

    @classmethod
    def _read(cls, path):
        if not os.path.lexists(path):
            raise FileNotFoundError(f"design table {str(path)!r} does not exist; build it "
                                    f"with 'python studies/design_table.py'")
        input_file_size(path, "design table")  # a directory, a device, a loop of links...
        try:
            if not h5py.is_hdf5(path):
                raise ValueError(f"design table {str(path)!r} is not an HDF5 file")
            with h5py.File(path, "r") as f:
                if f.attrs.get("format") != TABLE_FORMAT:
                    raise ValueError(f"{str(path)!r} is not a design table "
                                     f"(format {shorten(f.attrs.get('format'))})")
                version = int(f.attrs["format_version"])
                if version != TABLE_VERSION:
                    raise ValueError(f"design table {str(path)!r} has version {version}, "
                                     f"expected {TABLE_VERSION}")
                attrs = {k: v for k, v in f.attrs.items()
                         if k not in ("format", "format_version")}
                arrays = [f[name][()] for name in ("fill_factors", "ratios", "mean",
                                                   "scatter", "error")]
        except (OSError, KeyError, TypeError, RuntimeError) as err:
            raise ValueError(f"design table {str(path)!r} is damaged or incomplete: "
                             f"{str(err)[:200]}") from None
        try:
            return cls(*arrays, attrs)
        except (ValueError, TypeError, IndexError) as err:
            raise ValueError(f"design table {str(path)!r} is inconsistent: "
                             f"{one_line(err, 200)}") from None

    def _check_ratio(self, ratio):
        lo, hi = self.ratios[0], self.ratios[-1]
        if not (np.isfinite(ratio) and lo * (1 - 1e-9) <= ratio <= hi * (1 + 1e-9)):
            raise ValueError(f"wear ratio {ratio!r} is outside the table's range "
                             f"{lo:.3g}..{hi:.3g}")

    def _column(self, ratio):
        """PCHIP interpolants in ``rho_1`` of mean, scatter and error at one ratio."""
        self._check_ratio(ratio)
        x = math.log10(ratio)
        return {name: interpolate.PchipInterpolator(self.fill_factors, f(x))
                for name, f in self._along_ratio.items()}

    def normalised(self, fill_factor, ratio):
        """Normalised rms slope at ``(rho_1, k_1/k_0)``.

        Returns
        -------
        mean, scatter, error : float, grad_f0
        """
        lo, hi = self.fill_factors[0], self.fill_factors[-1]
        if not (lo - 1e-12 <= fill_factor <= hi + 1e-12):
            raise ValueError(f"fill factor {fill_factor!r} is outside the table's range "
                             f"{lo:.3g}..{hi:.3g}")
        col = self._column(ratio)
        return tuple(float(col[name](fill_factor)) for name in ("mean", "scatter", "error"))

    def curve(self, ratio, fill_factors=None):
        """Normalised rms slope along ``rho_1`` at one wear ratio.

        Parameters
        ----------
        ratio : float
            ``k_1 / k_0``.
        fill_factors : array_like, optional
            ``rho_1`` values inside the table's range (default: its nodes).

        Returns
        -------
        mean, scatter, error : ndarray, grad_f0
        """
        x = self.fill_factors if fill_factors is None else np.asarray(fill_factors, float)
        lo, hi = self.fill_factors[0], self.fill_factors[-1]
        if np.any(x < lo - 1e-12) or np.any(x > hi + 1e-12):
            raise ValueError(f"fill factors must lie in the table's range {lo:.3g}..{hi:.3g}")
        col = self._column(ratio)
        return tuple(col[name](x) for name in ("mean", "scatter", "error"))

    def rms_slope(self, pbar_over_estar, ratio, fill_factor):
        """Steady rms slope (friction proxy) of a design.

        Parameters
        ----------
        pbar_over_estar : float
            ``pbar / E*``, positive.
        ratio : float
            Wear ratio ``k_1 / k_0``.
        fill_factor : float
            ``rho_1``.

        Returns
        -------
        value, scatter : float, dimensionless
            ``grad_f0`` times the table's mean and realisation scatter.

        Warns
        -----
        steady.validity.ValidityWarning
            An rms slope beyond :data:`steady.validity.SLOPE_LIMIT`: a
            design outside the range of the linear half-space.
        """
        g0 = _reference(pbar_over_estar)
        mean, scatter, _ = self.normalised(fill_factor, ratio)
        check_rms_slope(float(np.max(g0 * mean)),
                        f"the design pbar/E* = {pbar_over_estar:.4g}, k_1/k_0 = {ratio:.4g}, "
                        f"rho_1 = {shorten(fill_factor)}")
        return g0 * mean, g0 * scatter

    def fill_factor_for(self, pbar_over_estar, ratio, target_slope):
        """Fill factor ``rho_1`` that gives a target steady rms slope.

        Parameters
        ----------
        pbar_over_estar : float
            ``pbar / E*``, positive.
        ratio : float
            Wear ratio ``k_1 / k_0``.  Below 1, phase 1 is the hard
            (low-wear) phase.
        target_slope : float
            Target rms slope (dimensionless), positive.

        Returns
        -------
        DesignResult

        Raises
        ------
        ValueError
            Target outside the reachable range (named in the message), or
            inputs outside the table.

        Warns
        -----
        steady.validity.ValidityWarning
            A target beyond :data:`steady.validity.SLOPE_LIMIT`: a design
            outside the range of the linear half-space.
        """
        g0 = _reference(pbar_over_estar)
        target_slope = _TARGET_SLOPE.parse(target_slope, "")
        t = target_slope / g0
        col = self._column(ratio)
        rho = np.linspace(self.fill_factors[0], self.fill_factors[-1], 4001)
        mean = col["mean"](rho)
        sd = col["scatter"](rho)
        low, high = float(mean.min()), float(mean.max())
        if not low <= t <= high:
            raise ValueError(
                f"target rms slope {target_slope:.4g} ({t:.4g} grad_f0) is not reachable at "
                f"pbar/E* = {pbar_over_estar:.4g} and wear ratio {ratio:.4g}: fill factors "
                f"{rho[0]:.3g}..{rho[-1]:.3g} give rms slopes {g0 * low:.4g}..{g0 * high:.4g} "
                f"({low:.4g}..{high:.4g} grad_f0)")
        f = mean - t
        roots = []
        for i in np.flatnonzero(np.sign(f[:-1]) != np.sign(f[1:])):
            if f[i] == 0.0:
                roots.append(float(rho[i]))
            else:
                roots.append(float(optimize.brentq(lambda x: col["mean"](x) - t,
                                                   rho[i], rho[i + 1], xtol=1e-12)))
        if f[-1] == 0.0:
            roots.append(float(rho[-1]))
        roots = sorted(set(roots))
        best = roots[-1]
        inside = np.abs(f) <= sd
        j = int(np.argmin(np.abs(rho - best)))
        lo_j = hi_j = j
        while lo_j > 0 and inside[lo_j - 1]:
            lo_j -= 1
        while hi_j < rho.size - 1 and inside[hi_j + 1]:
            hi_j += 1
        check_rms_slope(target_slope, f"the design target at pbar/E* = {pbar_over_estar:.4g}, "
                                      f"k_1/k_0 = {ratio:.4g}")
        return DesignResult(fill_factor=best,
                            fill_factor_range=(float(min(rho[lo_j], best)),
                                               float(max(rho[hi_j], best))),
                            solutions=tuple(roots), normalised_target=t,
                            reachable=(g0 * low, g0 * high))


def _reference(pbar_over_estar):
    """The reference slope ``4 pbar / (pi E*)`` of a checked ``pbar / E*``."""
    return 4.0 * _PBAR_OVER_ESTAR.parse(pbar_over_estar, "") / np.pi
