"""Any local wear law dw/ds = k_i p^m: the Fig. 4b map and the Fig. 5a collapse for m = 0.5 .. 3.

The paper says its results "will be similar for any local wear law".  For the
power law ``dw/ds = k_i p^m`` the steady state has ``k_i p_i^m = C``, so
``p_i ~ k_i^(-1/m)`` (eq. 7 generalised): the face of wear ratio ``k_2/k_1``
at exponent ``m`` should be the Archard face (``m = 1``) of the effective
ratio ``(k_2/k_1)^(1/m)``.  This study computes, independently for each
exponent (:meth:`steady.basis.PhaseBasis.rms_slopes` with ``exponent=m``):

- the Fig. 4b map: realisation mean of the normalised rms slope over
  ``rho_2 = 0.05 .. 0.95`` and ``k_2/k_1 = 10^-3 .. 10^3`` (40^2 seeds),
  for m = 0.5, 1, 2, 3, and the difference from the ``m = 1`` value at
  ``(k_2/k_1)^(1/m)`` on the same maps;
- the Fig. 5a collapse: the four coarseness levels (20^2 .. 160^2 seeds)
  against ``rho_2`` for ``k_2/k_1 = 10^-3, 10^-1, 10, 10^3`` per exponent,
  with the fine-grain closed form
  (:func:`steady.reference.fine_grain_rms_slope` with ``exponent=m``).

Every value is energy-corrected with its discretisation error (grids
``n/4, n/2, n``, or ``320, 512`` for 160^2 seeds).

Run::

    python studies/wear_exponent.py            # n = 512: 390 maps, about 5 min on one core
    python studies/wear_exponent.py --quick    # about 2 s
    python studies/wear_exponent.py --plot-only

Writes ``OUT/wear_exponent.h5`` and ``OUT/wear_exponent.png``.
"""

import sys

import numpy as np
import study_io

from steady.basis import PhaseBasis
from steady.outline import UNIT_DISK
from steady.phases import Voronoi
from steady.problem import FacePhases
from steady.reference import fine_grain_rms_slope
from steady.rms_slope import grid_ladder, ladder_error

NAME = "wear_exponent"
PARAMS = {"n": 512, "exponents": [0.5, 1.0, 2.0, 3.0],
          "ratios": np.logspace(-3, 3, 25).tolist(), "map_level": 1600,
          "map_fill": np.round(np.arange(1, 20) * 0.05, 10).tolist(),
          "map_seeds": list(range(1000, 1010)),
          "levels": [400, 1600, 6400, 25600], "collapse_ratios": [1e-3, 1e-1, 1e1, 1e3],
          "collapse_fill": np.round(np.arange(0.05, 1.0, 0.1), 10).tolist(),
          "collapse_seeds": list(range(1000, 1005))}
QUICK = {"n": 64, "exponents": [0.5, 1.0, 2.0, 3.0], "ratios": np.logspace(-3, 3, 7).tolist(),
         "map_level": 100, "map_fill": [0.1, 0.5, 0.9], "map_seeds": [3001, 3002],
         "levels": [25, 100], "collapse_ratios": [1e-3, 1e3], "collapse_fill": [0.1, 0.5, 0.9],
         "collapse_seeds": [3001, 3002]}


def exponent_slopes(geometry, n, ratios, exponents):
    """Normalised rms slopes of one biphasic map for every exponent and wear ratio.

    Parameters
    ----------
    geometry : steady.phases.Voronoi
        Two phases; ``k = (1, r)``.
    n : int
        Grid of the values.
    ratios : sequence of float, shape (K,)
        ``k_2 / k_1``.
    exponents : sequence of float, shape (E,)
        ``m``.

    Returns
    -------
    rms : ndarray, shape (E, K)
        Energy-corrected ``rms / grad_f0`` on grid ``n`` at exponent ``m``.
    error : ndarray, shape (E, K)
        Its ladder error (:func:`steady.rms_slope.ladder_error`).
    archard : ndarray, shape (E, K)
        ``m = 1`` value at the effective ratio ``r^(1/m)``, grid ``n``.
    fill : float
        Realised ``rho_2`` on grid ``n``.
    """
    ratios = np.asarray(ratios, dtype=float)
    k = np.column_stack([np.ones_like(ratios), ratios])
    grids = grid_ladder(geometry, n)
    values = []
    for m in grids:
        grid = UNIT_DISK.grid(m)
        phases = FacePhases(grid, geometry.labels(grid), geometry.n_phases)
        basis = PhaseBasis(phases, 1.0, faces=False)
        values.append([basis.rms_slopes(k, np.pi, exponent=e).normalised for e in exponents])
    archard = np.array([basis.rms_slopes(np.column_stack([np.ones_like(ratios),
                                                          ratios ** (1.0 / e)]),
                                         np.pi).normalised for e in exponents])
    values = np.asarray(values)
    return values[-1], ladder_error(grids, values), archard, float(basis.fill_factors[1])


def _sweep(level, fills, seeds, params):
    shape = (len(fills), len(seeds), len(params["exponents"]), len(params["ratios"]))
    rms, err, arch = np.empty(shape), np.empty(shape), np.empty(shape)
    fill = np.empty(shape[:2])
    for i, rho in enumerate(fills):
        for s, seed in enumerate(seeds):
            geometry = Voronoi(level, (1.0 - rho, rho), seed)
            rms[i, s], err[i, s], arch[i, s], fill[i, s] = exponent_slopes(
                geometry, params["n"], params["ratios"], params["exponents"])
    return rms, err, arch, fill


def compute(path, params):
    """The map level and the collapse levels for every exponent; write HDF5."""
    ratios = np.asarray(params["ratios"])
    exps = np.asarray(params["exponents"])
    datasets, attrs = {}, {}
    rms, err, arch, fill = _sweep(params["map_level"], params["map_fill"], params["map_seeds"],
                                  params)
    varied = np.abs(np.log(ratios)) > 1e-9
    sd = rms.std(axis=1, ddof=1)
    datasets.update({
        "ratios": (ratios, "1"), "exponents": (exps, "1"),
        "map/fill_factors": (np.asarray(params["map_fill"]), "1"),
        "map/rms_slope": (rms, "grad_f0"), "map/error": (err, "grad_f0"),
        "map/mean": (rms.mean(axis=1), "grad_f0"), "map/scatter": (sd, "grad_f0"),
        "map/archard_effective": (arch, "grad_f0"), "map/realised": (fill, "1"),
    })
    attrs["map_max_difference_from_effective_ratio"] = (float(np.max(np.abs(rms - arch))),
                                                        "grad_f0")
    attrs["map_max_error"] = (float(err.max()), "grad_f0")
    attrs["map_max_error_over_scatter"] = (
        float(np.max(err.mean(axis=1)[..., varied] / sd[..., varied])), "1")
    attrs["map_max_mean"] = (rms.mean(axis=1).max(axis=(0, 2)), "grad_f0")
    attrs["realisations"] = (len(params["map_seeds"]), "1")

    keep = [int(np.argmin(np.abs(np.log(ratios / r)))) for r in params["collapse_ratios"]]
    worst = []
    for level in params["levels"]:
        rms, err, arch, fill = _sweep(level, params["collapse_fill"], params["collapse_seeds"],
                                      params)
        g = f"collapse/{level}"
        datasets[f"{g}/mean"] = (rms.mean(axis=1)[..., keep], "grad_f0")
        datasets[f"{g}/scatter"] = (rms.std(axis=1, ddof=1)[..., keep], "grad_f0")
        datasets[f"{g}/error"] = (err.mean(axis=1)[..., keep], "grad_f0")
        datasets[f"{g}/realised"] = (fill, "1")
        closed = fine_grain_rms_slope(
            np.stack([1 - fill, fill], axis=-1)[:, :, None, None, :],
            np.column_stack([np.ones(len(keep)), ratios[keep]])[None, None, None],
            exponent=exps[None, None, :, None])
        rel = rms[..., keep] / closed - 1
        datasets[f"{g}/relative_to_closed_form"] = (rel.mean(axis=1), "1")
        worst.append(float(np.max(np.abs(rms - arch))))
    attrs["collapse_max_difference_from_effective_ratio"] = (max(worst), "grad_f0")
    fills = np.linspace(0.01, 0.99, 197)
    datasets["collapse/closed_form_fill"] = (fills, "1")
    datasets["collapse/closed_form"] = (fine_grain_rms_slope(
        np.stack([1 - fills, fills], axis=-1)[None, None, :, :],
        np.column_stack([np.ones(len(keep)), ratios[keep]])[None, :, None, :],
        exponent=exps[:, None, None]), "grad_f0")
    datasets["collapse/ratios"] = (ratios[keep], "1")
    datasets["collapse/fill_factors"] = (np.asarray(params["collapse_fill"]), "1")
    datasets["collapse/levels"] = (np.asarray(params["levels"]), "1")
    return study_io.write_study(path, NAME, params, datasets, attrs)


def plot(path, png):
    """Four maps and four collapse panels, from the HDF5 file."""
    d, a = study_io.read_study(path, NAME)
    p = a["params"]
    exps = d["exponents"]
    fig = study_io.figure(14.0, 7.6)
    axes = fig.subplots(2, len(exps))
    x = np.log10(d["ratios"])
    y = d["map/fill_factors"]
    mean = d["map/mean"]  # (fill, exponent, ratio)
    vmax = float(mean.max())
    for e, m in enumerate(exps):
        ax = axes[0, e]
        im = ax.pcolormesh(x, y, mean[:, e], shading="nearest", cmap="magma", vmin=1,
                           vmax=vmax)
        cs = ax.contour(x, y, mean[:, e], levels=[1.2, 1.5, 2, 3, 5], colors="w",
                        linewidths=0.7)
        ax.clabel(cs, fontsize=7)
        diff = np.max(np.abs(d["map/rms_slope"][:, :, e] - d["map/archard_effective"][:, :, e]))
        ax.set_title(f"m = {m:g}: max {mean[:, e].max():.2f}; minus m = 1 at "
                     f"$(k_2/k_1)^{{1/m}}$:\n{diff:.1e} (every map of the sweep)", fontsize=8.5)
        ax.set_xlabel(r"$\log_{10}(k_2/k_1)$")
        ax.set_ylabel(r"$\rho_2$")
    fig.colorbar(im, ax=axes[0, :].tolist(), shrink=0.85).set_label(
        r"rms slope / $\nabla f^0_\infty$" f" (mean of {a['realisations']}, "
        f"{int(round(np.sqrt(p['map_level'])))}$^2$ seeds)")
    markers = "o^sv"
    ratios = d["collapse/ratios"]
    for e, m in enumerate(exps):
        ax = axes[1, e]
        for c, r in enumerate(ratios):
            ax.plot(d["collapse/closed_form_fill"], d["collapse/closed_form"][e, c],
                    color=f"C{c}", lw=0.9, label=f"$k_2/k_1$ = {r:g}")
            for li, level in enumerate(d["collapse/levels"]):
                g = f"collapse/{level}"
                ax.errorbar(d["collapse/fill_factors"], d[f"{g}/mean"][:, e, c],
                            yerr=d[f"{g}/scatter"][:, e, c], fmt=markers[li % 4], ms=3,
                            color=f"C{c}", mfc="none", lw=0.6, capsize=1.5)
        dev = max(np.max(np.abs(d[f"collapse/{lv}/relative_to_closed_form"][:, e]))
                  for lv in d["collapse/levels"])
        ax.set_yscale("log")
        study_io.plain_log_ticks(ax)
        ax.set_xlabel(r"$\rho_2$")
        ax.set_ylabel(r"rms slope / $\nabla f^0_\infty$")
        sides = ", ".join(f"{int(round(np.sqrt(lv)))}$^2$ {markers[i % 4]}"
                          for i, lv in enumerate(d["collapse/levels"]))
        ax.set_title(f"m = {m:g}: levels {sides};\nlines: fine-grain form, level means "
                     f"within {100 * dev:.1f} %", fontsize=8)
        if e == 0:
            ax.legend(fontsize=7)
    study_io.save_figure(fig, png, dpi=75)


def main(argv=None):
    """Run the study from the command line (``--help`` lists the options); exit status."""
    return study_io.run_study(NAME, __doc__, compute, plot, PARAMS, QUICK, argv)


if __name__ == "__main__":
    sys.exit(main())
