"""Design rule: the fill factor that gives a target rms slope, and back.

The steady rms slope of a biphasic punch is ``grad_f0`` times a normalised
value that depends only on the fill factor ``rho_2`` and the wear ratio
``k_2 / k_1`` (eq. 15; ``grad_f0 = 4 pbar / (pi E*)``, eq. 12).  This module

- computes that normalised value over random Voronoi maps, all wear ratios
  of one map at once (:class:`steady.basis.PhaseBasis`), as a resumable
  sweep (:mod:`steady.sweep`): :func:`voronoi_slopes`,
  :func:`voronoi_sweep`, :func:`collect_voronoi`;
- tabulates its realisation mean and scatter (:class:`DesignTable`, an
  HDF5 file) and interpolates it monotonically (PCHIP in the fill factor
  and in ``log10`` of the wear ratio);
- inverts it: given ``pbar / E*``, the wear ratio and a target rms slope,
  the fill factor ``rho_2`` with its realisation scatter
  (:meth:`DesignTable.fill_factor_for`), and the reverse
  (:meth:`DesignTable.rms_slope`);
- gives the fine-grain limit in closed form
  (:func:`fine_grain_rms_slope`), against which the table is checked.

Fine-grain limit
----------------
Over the whole plane ``int |grad u|^2 dA = (4 / E*^2) int p^2 dA``
(Parseval; :mod:`steady.accuracy`).  Split the steady pressure into its
mean ``pbar`` and the fluctuation ``p - pbar``.  The mean gives the
homogeneous face (normalised rms slope 1, of which the fraction
``4 / pi^2`` of the plane integral falls on the face).  When the grains are
much smaller than the punch, the fluctuation's field stays on the face
(up to a rim layer about one grain wide) and does not correlate with the
smooth mean field, so that

    (rms / grad_f0)^2 = 1 + (pi^2 / 4) sum_i rho_i (p_i / pbar - 1)^2.

For two phases with ``r = k_2 / k_1`` and Archard's law this is
``1 + (pi^2 / 4) rho_1 rho_2 (r - 1)^2 / (rho_1 r + rho_2)^2``: symmetric
under ``(rho_2, r) -> (1 - rho_2, 1 / r)``, and in the pillars limit
``r -> 0`` it tends to ``sqrt(1 + (pi^2 / 4) (1 / rho_2 - 1))``, not to the
``1 / rho_2`` of eq. 18, which would exceed the Parseval bound
``(pi / 2) / sqrt(rho_2)``.

Command line (``python -m steady.design``)::

    python -m steady.design --pbar-over-estar 0.08 --wear-ratio 1e-2 --target-slope 1.0
    python -m steady.design --pbar-over-estar 0.08 --wear-ratio 1e-2 --fill-factor 0.1
"""

from __future__ import annotations

import argparse
import dataclasses
import functools
import logging
import math
import pathlib
import sys

import h5py
import numpy as np
from scipy import interpolate, optimize

from .accuracy import grid_ladder, ladder_error
from .basis import PhaseBasis
from .reference import fine_grain_rms_slope
from .phases import Voronoi
from .sweep import run_sweep

__all__ = [
    "DEFAULT_TABLE",
    "DesignResult",
    "DesignTable",
    "TABLE_FORMAT",
    "TABLE_VERSION",
    "VORONOI_SWEEP_VERSION",
    "VoronoiData",
    "collect_voronoi",
    "main",
    "voronoi_points",
    "voronoi_slopes",
    "voronoi_sweep",
]

logger = logging.getLogger(__name__)

TABLE_FORMAT = "runin.design_table"
TABLE_VERSION = 1

#: The table shipped with the studies (``python studies/design_table.py`` builds it).
DEFAULT_TABLE = pathlib.Path(__file__).resolve().parent.parent / "studies" / "data" / \
    "design_table.h5"

#: Layout version of the Voronoi sweep points (part of the sweep settings).
VORONOI_SWEEP_VERSION = 1


def voronoi_slopes(point, *, n, ratios):
    """Normalised rms slopes of one biphasic Voronoi map for many wear ratios.

    The sweep task of :func:`voronoi_sweep` (module level, picklable).

    Parameters
    ----------
    point : mapping
        ``n_seeds`` (int), ``fill_factor`` (``rho_2``, float), ``seed`` (int):
        the map ``Voronoi(n_seeds, (1 - rho_2, rho_2), seed)``; phase 1 of
        the paper is index 0, phase 2 is index 1.
    n : int
        Grid of the values.
    ratios : sequence of float, shape (K,)
        Wear ratios ``k_2 / k_1``.

    Returns
    -------
    dict
        ``grids`` (G,) the ladder of :func:`grid_ladder`;
        ``rms_slope`` (G, K) energy-corrected ``rms / grad_f0`` on each grid;
        ``rms_slope_plain`` (K,) plain pixel value on grid ``n``;
        ``error`` (K,) :func:`ladder_error` of the value on grid ``n`` (for the
        ladder ``n, 2n``: ``2 |S_2n - S_n|``, its first-order error);
        ``fill_factor`` realised ``rho_2`` on grid ``n``.
    """
    rho = float(point["fill_factor"])
    geometry = Voronoi(int(point["n_seeds"]), (1.0 - rho, rho), int(point["seed"]))
    grids = grid_ladder(geometry, n)
    k = np.column_stack([np.ones(len(ratios)), np.asarray(ratios, dtype=float)])
    values, plain, fill = [], None, None
    for m in grids:
        basis = PhaseBasis(geometry.labels(m), 1.0, 1.0, faces=False)
        sweep = basis.rms_slopes(k, np.pi)  # pbar = 1 Pa, E* = 1 Pa
        values.append(sweep.normalised)
        if m == n:
            plain = sweep.rms_slope_plain / sweep.reference_slope
            fill = float(basis.fill_factors[1])
    values = np.asarray(values)
    if grids[-1] == n:
        error = ladder_error(grids, values)
    else:  # ladder n, 2n: first-order error of the coarser value S_n
        error = np.abs(values[1] - values[0]) * grids[1] / (grids[1] - grids[0])
    return {"grids": np.asarray(grids), "rms_slope": values, "rms_slope_plain": plain,
            "error": error, "fill_factor": fill}


_VORONOI_UNITS = {"grids": "1", "rms_slope": "grad_f0", "rms_slope_plain": "grad_f0",
                  "error": "grad_f0", "fill_factor": "1"}


def voronoi_points(n_seeds, fill_factors, seeds):
    """Sweep points for every (coarseness, fill factor, realisation)."""
    return [{"n_seeds": int(c), "fill_factor": round(float(r), 10), "seed": int(s)}
            for c in n_seeds for r in fill_factors for s in seeds]


def voronoi_sweep(path, *, n, ratios, n_seeds, fill_factors, seeds, executor=None,
                  workers=None, scheduler=None, progress=False):
    """Run (or resume) the Voronoi sweep into a sweep file.

    Parameters
    ----------
    path : str or path-like
        Sweep file (:mod:`steady.sweep`); its settings are ``n`` and
        ``ratios``, so that sweeps over other coarseness levels, fill
        factors or realisations with the same grid and ratios share it.
    n : int
        Grid of the values (:func:`grid_ladder` adds coarser ones).
    ratios : sequence of float
        Wear ratios ``k_2 / k_1``.
    n_seeds, fill_factors, seeds : sequences
        Coarseness levels, fill factors ``rho_2`` and realisation seeds.
    executor, workers, scheduler, progress
        As :func:`steady.sweep.run_sweep`.

    Returns
    -------
    SweepFile
    """
    ratios = [float(r) for r in ratios]
    settings = {"task": "steady.design.voronoi_slopes", "version": VORONOI_SWEEP_VERSION,
                "n": int(n), "ratios": ratios}
    task = functools.partial(voronoi_slopes, n=int(n), ratios=ratios)
    return run_sweep(task, voronoi_points(n_seeds, fill_factors, seeds), path,
                     settings=settings, units=_VORONOI_UNITS, executor=executor,
                     workers=workers, scheduler=scheduler, progress=progress,
                     description=f"Voronoi sweep n={n}")


@dataclasses.dataclass(frozen=True, eq=False)
class VoronoiData:
    """Values of a Voronoi sweep on a regular (level, fill factor, realisation) grid.

    Attributes
    ----------
    n_seeds : ndarray, shape (C,)
    fill_factors : ndarray, shape (R,)
        Nominal ``rho_2``.
    seeds : ndarray, shape (M,)
    ratios : ndarray, shape (K,)
        ``k_2 / k_1``.
    rms_slope : ndarray, shape (C, R, M, K), grad_f0
        Energy-corrected normalised rms slope on grid ``n``.
    rms_slope_plain : ndarray, shape (C, R, M, K), grad_f0
    error : ndarray, shape (C, R, M, K), grad_f0
        Discretisation error estimate of each value.
    realised : ndarray, shape (C, R, M)
        Realised ``rho_2`` on grid ``n``.
    n : int
    """

    n_seeds: np.ndarray
    fill_factors: np.ndarray
    seeds: np.ndarray
    ratios: np.ndarray
    rms_slope: np.ndarray
    rms_slope_plain: np.ndarray
    error: np.ndarray
    realised: np.ndarray
    n: int

    @property
    def mean(self):
        """Realisation mean, shape (C, R, K)."""
        return self.rms_slope.mean(axis=2)

    @property
    def scatter(self):
        """Realisation standard deviation (ddof 1), shape (C, R, K)."""
        return self.rms_slope.std(axis=2, ddof=1) if self.seeds.size > 1 else \
            np.zeros_like(self.mean)

    @property
    def mean_error(self):
        """Discretisation error of the mean (mean of the errors), shape (C, R, K)."""
        return self.error.mean(axis=2)


def collect_voronoi(sweep_file, n_seeds, fill_factors, seeds):
    """Gather the points of a Voronoi sweep file into arrays.

    Parameters
    ----------
    sweep_file : SweepFile
    n_seeds, fill_factors, seeds : sequences
        The grid of points wanted; every one must be in the file.

    Returns
    -------
    VoronoiData

    Raises
    ------
    ValueError
        A point is missing (the message names it).
    """
    settings = sweep_file.settings
    ratios = np.asarray(settings["ratios"])
    index = {}
    for point in sweep_file.read():
        p = point.params
        index[(p["n_seeds"], round(p["fill_factor"], 10), p["seed"])] = point.values
    shape = (len(n_seeds), len(fill_factors), len(seeds))
    out = {name: np.empty(shape + (ratios.size,)) for name in
           ("rms_slope", "rms_slope_plain", "error")}
    realised = np.empty(shape)
    for ci, c in enumerate(n_seeds):
        for ri, r in enumerate(fill_factors):
            for si, s in enumerate(seeds):
                key = (int(c), round(float(r), 10), int(s))
                if key not in index:
                    raise ValueError(f"sweep file {str(sweep_file.path)!r} has no point "
                                     f"n_seeds={key[0]}, fill_factor={key[1]}, seed={key[2]}")
                v = index[key]
                grids = list(v["grids"])
                top = grids.index(settings["n"])
                out["rms_slope"][ci, ri, si] = v["rms_slope"][top]
                out["rms_slope_plain"][ci, ri, si] = v["rms_slope_plain"]
                out["error"][ci, ri, si] = v["error"]
                realised[ci, ri, si] = v["fill_factor"]
    return VoronoiData(n_seeds=np.asarray(n_seeds), fill_factors=np.asarray(fill_factors),
                       seeds=np.asarray(seeds), ratios=ratios, realised=realised,
                       n=int(settings["n"]), **out)


@dataclasses.dataclass(frozen=True)
class DesignResult:
    """Fill factor for a target rms slope.

    Attributes
    ----------
    fill_factor : float
        ``rho_2`` at which the realisation-mean rms slope equals the target
        (the largest such ``rho_2`` if there are several).
    fill_factor_range : (float, float)
        The fill factors around it within which the target lies inside
        the realisation scatter (mean +- one standard deviation).
    solutions : tuple of float
        Every ``rho_2`` in the table's range that reaches the target.
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
    """Tabulated normalised rms slope ``S(rho_2, k_2/k_1)`` with its scatter.

    Parameters
    ----------
    fill_factors : array_like, shape (R,)
        Increasing ``rho_2`` nodes.
    ratios : array_like, shape (K,)
        Increasing wear ratios ``k_2 / k_1``.
    mean, scatter, error : array_like, shape (R, K), grad_f0
        Realisation mean, realisation standard deviation and
        discretisation error of the normalised rms slope.
    attrs : mapping, optional
        Provenance (grid, coarseness, realisations), stored with the table.
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
        """Table of one coarseness level of a :class:`VoronoiData`."""
        attrs = dict(attrs or {})
        attrs.update(n=data.n, n_seeds=int(data.n_seeds[level]),
                     realisations=int(data.seeds.size))
        return cls(data.fill_factors, data.ratios, data.mean[level], data.scatter[level],
                   data.mean_error[level], attrs)

    def write(self, path):
        """Write the table to HDF5 (layout ``runin.design_table``, version 1)."""
        path = pathlib.Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        with h5py.File(path, "w") as f:
            f.attrs["format"] = TABLE_FORMAT
            f.attrs["format_version"] = TABLE_VERSION
            for k, v in self.attrs.items():
                f.attrs[k] = v
            for name, unit in (("fill_factors", "1"), ("ratios", "1"), ("mean", "grad_f0"),
                               ("scatter", "grad_f0"), ("error", "grad_f0")):
                ds = f.create_dataset(name, data=getattr(self, name))
                ds.attrs["units"] = unit
        return path

    @classmethod
    def read(cls, path=None):
        """Read a table (default :data:`DEFAULT_TABLE`).

        Raises
        ------
        ValueError
            Missing or foreign file.
        """
        path = pathlib.Path(DEFAULT_TABLE if path is None else path)
        if not path.is_file():
            raise ValueError(f"design table {str(path)!r} does not exist; build it with "
                             f"'python studies/design_table.py'")
        with h5py.File(path, "r") as f:
            if f.attrs.get("format") != TABLE_FORMAT:
                raise ValueError(f"{str(path)!r} is not a design table "
                                 f"(format {f.attrs.get('format')!r})")
            version = int(f.attrs["format_version"])
            if version != TABLE_VERSION:
                raise ValueError(f"design table {str(path)!r} has version {version}, "
                                 f"expected {TABLE_VERSION}")
            attrs = {k: v for k, v in f.attrs.items() if k not in ("format", "format_version")}
            return cls(f["fill_factors"][()], f["ratios"][()], f["mean"][()],
                       f["scatter"][()], f["error"][()], attrs)

    def _check_ratio(self, ratio):
        lo, hi = self.ratios[0], self.ratios[-1]
        if not (np.isfinite(ratio) and lo * (1 - 1e-9) <= ratio <= hi * (1 + 1e-9)):
            raise ValueError(f"wear ratio {ratio!r} is outside the table's range "
                             f"{lo:.3g}..{hi:.3g}")

    def _column(self, ratio):
        """PCHIP interpolants in ``rho_2`` of mean, scatter and error at one ratio."""
        self._check_ratio(ratio)
        x = math.log10(ratio)
        return {name: interpolate.PchipInterpolator(self.fill_factors, f(x))
                for name, f in self._along_ratio.items()}

    def normalised(self, fill_factor, ratio):
        """Normalised rms slope at ``(rho_2, k_2/k_1)``.

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
        """Normalised rms slope along ``rho_2`` at one wear ratio.

        Parameters
        ----------
        ratio : float
            ``k_2 / k_1``.
        fill_factors : array_like, optional
            ``rho_2`` values inside the table's range (default: its nodes).

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
            Wear ratio ``k_2 / k_1``.
        fill_factor : float
            ``rho_2``.

        Returns
        -------
        value, scatter : float, dimensionless
            ``grad_f0`` times the table's mean and realisation scatter.
        """
        g0 = _reference(pbar_over_estar)
        mean, scatter, _ = self.normalised(fill_factor, ratio)
        return g0 * mean, g0 * scatter

    def fill_factor_for(self, pbar_over_estar, ratio, target_slope):
        """Fill factor ``rho_2`` that gives a target steady rms slope.

        Parameters
        ----------
        pbar_over_estar : float
            ``pbar / E*``, positive.
        ratio : float
            Wear ratio ``k_2 / k_1``.  Below 1, phase 2 is the hard
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
        """
        g0 = _reference(pbar_over_estar)
        if not (np.isfinite(target_slope) and target_slope > 0):
            raise ValueError(f"target rms slope must be positive, got {target_slope!r}")
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
        return DesignResult(fill_factor=best,
                            fill_factor_range=(float(min(rho[lo_j], best)),
                                               float(max(rho[hi_j], best))),
                            solutions=tuple(roots), normalised_target=t,
                            reachable=(g0 * low, g0 * high))


def _reference(pbar_over_estar):
    if not (np.isfinite(pbar_over_estar) and pbar_over_estar > 0):
        raise ValueError(f"pbar/E* must be positive, got {pbar_over_estar!r}")
    return 4.0 * pbar_over_estar / np.pi


def main(argv=None):
    """Command line: fill factor for a target rms slope, or rms slope for a fill factor."""
    parser = argparse.ArgumentParser(
        prog="python -m steady.design",
        description="Steady rms slope (friction proxy) of a biphasic punch: the fill factor "
                    "rho_2 of phase 2 that gives a target rms slope, or the rms slope of a "
                    "fill factor.  Phase 2 is the hard phase when the wear ratio is below 1.")
    parser.add_argument("--pbar-over-estar", type=float, required=True,
                        help="mean pressure over the effective modulus, pbar/E*")
    parser.add_argument("--wear-ratio", type=float, required=True,
                        help="k_2/k_1 (below 1: phase 2 wears less)")
    what = parser.add_mutually_exclusive_group(required=True)
    what.add_argument("--target-slope", type=float, help="target steady rms slope")
    what.add_argument("--fill-factor", type=float, help="fill factor rho_2 of phase 2")
    parser.add_argument("--table", default=None,
                        help=f"design table (default {DEFAULT_TABLE})")
    args = parser.parse_args(argv)
    try:
        table = DesignTable.read(args.table)
        g0 = _reference(args.pbar_over_estar)
        source = (f"table: {table.attrs.get('n_seeds', '?')} Voronoi seeds, "
                  f"{table.attrs.get('realisations', '?')} realisations, "
                  f"n = {table.attrs.get('n', '?')}")
        if args.target_slope is not None:
            res = table.fill_factor_for(args.pbar_over_estar, args.wear_ratio,
                                        args.target_slope)
            lo, hi = res.fill_factor_range
            print(f"fill factor rho_2 = {res.fill_factor:.4g} "
                  f"(realisation scatter: {lo:.4g}..{hi:.4g})")
            if len(res.solutions) > 1:
                print("other fill factors reaching the target: "
                      + ", ".join(f"{r:.4g}" for r in res.solutions[:-1]))
            print(f"target {args.target_slope:.4g} = {res.normalised_target:.4g} grad_f0, "
                  f"grad_f0 = 4 pbar/(pi E*) = {g0:.4g}; reachable "
                  f"{res.reachable[0]:.4g}..{res.reachable[1]:.4g}")
        else:
            value, sd = table.rms_slope(args.pbar_over_estar, args.wear_ratio,
                                        args.fill_factor)
            fine = fine_grain_rms_slope([1 - args.fill_factor, args.fill_factor],
                                        [1.0, args.wear_ratio])
            print(f"rms slope = {value:.4g} +- {sd:.2g} (realisation scatter); "
                  f"{value / g0:.4g} grad_f0, grad_f0 = {g0:.4g}")
            print(f"fine-grain closed form: {g0 * fine:.4g} ({fine:.4g} grad_f0)")
        print(source)
    except ValueError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
