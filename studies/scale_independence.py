"""Scale independence: whether the rms slope depends on the grain size at converged resolution.

Tests the paper's main claim (Fig. 4-5: "the rms slope is not influenced by
the characteristic linear size of inclusions") at ``rho_2 = 0.5`` for the four
coarseness levels (20^2 .. 160^2 seeds) with 50 realisations each, at grid
``n = 512`` with the energy-corrected rms slope (discretisation error from
grids ``n, n/2, n/4``), beside the plain pixel rms slope, which carries a
spurious grain-size dependence at a fixed grid.

Each value is compared with the fine-grain closed form
(:func:`steady.reference.fine_grain_rms_slope`) evaluated at the realisation's
own realised fill factor; the residual against the mean seed spacing
``d = 2 a / sqrt(N)`` is fitted with a straight line (weighted by the standard
errors), which measures a finite-size (rim) effect of order ``d / a``.

Run::

    python studies/scale_independence.py            # 200 maps at n = 512, ~7 min on 2 cores
                                                    # (12 s once they are in the sweep file)
    python studies/scale_independence.py --quick    # a few seconds
    python studies/scale_independence.py --plot-only

The sweep points go to (or are reused from) ``OUT/voronoi_sweep_n<n>.h5``
(:mod:`voronoi_study`).  Writes ``OUT/scale_independence.h5`` and
``OUT/scale_independence.png``.
"""

import sys

import numpy as np
import study_io
import voronoi_study

from steady.phases import Voronoi
from steady.reference import fine_grain_rms_slope
from steady.rms_slope import SlopeEnergy
from steady.wear import pressure_field

NAME = "scale_independence"
PARAMS = dict(voronoi_study.FULL, fill=0.5, seeds=list(range(1000, 1050)),
              ratios_shown=[1e-3, 1e-1, 1e1, 1e3], leak_ratio=10.0, leak_realisations=5)
QUICK = dict(voronoi_study.QUICK, fill=0.5, seeds=[3001, 3002, 3003, 3004],
             ratios_shown=[1e-1, 1e1], leak_ratio=10.0, leak_realisations=2)


def _line_fit(x, y, sigma):
    """Weighted least squares ``y = c0 + c1 x``: coefficients and their standard errors."""
    w = 1.0 / sigma**2
    A = np.column_stack([np.ones_like(x), x])
    cov = np.linalg.inv(A.T @ (A * w[:, None]))
    coef = cov @ (A.T @ (w * y))
    return coef, np.sqrt(np.diag(cov))


def rim_leak(n_seeds, fill, seed, n, ratio):
    """Split of the mean-square slope into the mean-pressure part and the fluctuation part.

    The steady pressure is ``pbar`` plus a fluctuation ``dp`` (zero mean on the
    face).  Over the plane, the fluctuation's field carries ``(4/E*^2) int dp^2``;
    returns the fraction of it that falls outside the face (``leak``) and the
    face integral of the cross term ``2 grad u_mean . grad u_dp`` per face area,
    in units of ``grad_f0^2``.
    """
    h = 2.0 / n
    labels = Voronoi(n_seeds, (1 - fill, fill), seed).labels(n)
    on_face = labels >= 0
    pressure, _, _ = pressure_field(labels, [1.0, ratio], np.pi, h * h)
    pbar = pressure[on_face].mean()
    mean = np.where(on_face, pbar, 0.0)
    gram = SlopeEnergy(n, h, 1.0).gram([mean, pressure - mean], on_face)
    inside = gram.total - gram.exterior
    g0 = 4 * pbar / np.pi
    return gram.exterior[1, 1] / gram.total[1, 1], 2 * inside[0, 1] / gram.face_area / g0**2


def compute(path, params, *, workers=None, scheduler=None, progress=False):
    """Sweep 50 realisations per level at one fill factor; fit the residuals; write HDF5."""
    data = voronoi_study.sweep_data(params, path, levels=params["levels"],
                                    fill_factors=[params["fill"]], seeds=params["seeds"],
                                    workers=workers, scheduler=scheduler, progress=progress)
    cols = [voronoi_study.index_of(data.ratios, r) for r in params["ratios_shown"]]
    s = data.rms_slope[:, 0][:, :, cols]            # (C, M, J)
    plain = data.rms_slope_plain[:, 0][:, :, cols]
    err = data.error[:, 0][:, :, cols]
    rho = data.realised[:, 0]                      # (C, M)
    ratios = np.asarray(params["ratios_shown"])
    fine = fine_grain_rms_slope(np.stack([1 - rho, rho], axis=-1)[:, :, None, :],
                                np.stack([np.ones_like(ratios), ratios], axis=-1)[None, None])
    fine_nominal = fine_grain_rms_slope(np.stack([np.full_like(ratios, 1 - params["fill"]),
                                                  np.full_like(ratios, params["fill"])], -1),
                                        np.stack([np.ones_like(ratios), ratios], axis=-1))
    m = data.seeds.size
    resid = s - fine
    spacing = 2.0 / np.sqrt(np.asarray(params["levels"], dtype=float))
    fits, fit_errors = [], []
    for j in range(len(cols)):
        coef, se = _line_fit(spacing, resid[:, :, j].mean(axis=1),
                             resid[:, :, j].std(axis=1, ddof=1) / np.sqrt(m))
        fits.append(coef)
        fit_errors.append(se)
    first10 = s[:, :10].mean(axis=1)
    leak = np.array([[rim_leak(c, params["fill"], seed, data.n, params["leak_ratio"])
                      for seed in params["seeds"][:params["leak_realisations"]]]
                     for c in params["levels"]])   # (C, L, 2)
    return study_io.write_study(path, NAME, params, {
        "levels": (np.asarray(params["levels"]), "1"),
        "spacing": (spacing, "a"),
        "ratios": (ratios, "1"),
        "rms_slope": (s, "grad_f0"),
        "rms_slope_plain": (plain, "grad_f0"),
        "error": (err, "grad_f0"),
        "realised_fill": (rho, "1"),
        "fine_grain": (fine, "grad_f0"),
        "fine_grain_nominal": (fine_nominal, "grad_f0"),
        "mean": (s.mean(axis=1), "grad_f0"),
        "scatter": (s.std(axis=1, ddof=1), "grad_f0"),
        "sem": (s.std(axis=1, ddof=1) / np.sqrt(m), "grad_f0"),
        "mean_error": (err.mean(axis=1), "grad_f0"),
        "plain_mean": (plain.mean(axis=1), "grad_f0"),
        "mean_first10": (first10, "grad_f0"),
        "residual_mean": (resid.mean(axis=1), "grad_f0"),
        "residual_sem": (resid.std(axis=1, ddof=1) / np.sqrt(m), "grad_f0"),
        "fit": (np.asarray(fits), "grad_f0, grad_f0 per a"),
        "fit_error": (np.asarray(fit_errors), "grad_f0, grad_f0 per a"),
        "realised_fill_sd": (rho.std(axis=1, ddof=1), "1"),
        "leak": (leak[..., 0], "1"),
        "cross": (leak[..., 1], "grad_f0^2"),
    }, {"n": (data.n, "1"), "realisations": (int(m), "1")})


def plot(path, png):
    """Mean rms slope and residuals against grain size, from the HDF5 file."""
    d, a = study_io.read_study(path, NAME)
    fig = study_io.figure(14.0, 4.0)
    ax, ax_r, ax_l = fig.subplots(1, 3)
    x = d["spacing"]
    xs = np.linspace(0, x.max() * 1.05, 50)
    for j, r in enumerate(d["ratios"]):
        c = f"C{j}"
        ax.errorbar(x, d["mean"][:, j], yerr=d["sem"][:, j], fmt="o-", color=c, ms=4,
                    capsize=2, lw=0.9, label=f"$k_2/k_1$ = {r:g}, corrected")
        ax.plot(x, d["plain_mean"][:, j], "s:", color=c, ms=3, lw=0.8,
                label="plain pixel" if j == 0 else None)
        ax.axhline(d["fine_grain_nominal"][j], color=c, lw=0.6, ls="--")
        ax_r.errorbar(x, d["residual_mean"][:, j], yerr=d["residual_sem"][:, j], fmt="o",
                      color=c, ms=4, capsize=2, label=f"$k_2/k_1$ = {r:g}")
        c0, c1 = d["fit"][j]
        ax_r.plot(xs, c0 + c1 * xs, color=c, lw=0.8)
    ax.set_xscale("log")
    ax.set_xticks(x, [f"{int(round(np.sqrt(v)))}$^2$" for v in d["levels"]])
    ax.minorticks_off()
    ax.set_xlabel("seeds (mean spacing 2a/sqrt(N))")
    ax.set_ylabel(r"rms slope / $\nabla f^0_\infty$")
    ax.set_title(f"$\\rho_2$ = {a['params']['fill']:g}, n = {a['n']}, mean $\\pm$ standard "
                 f"error of {a['realisations']} realisations;\n"
                 "dashed: fine-grain closed form", fontsize=8)
    ax.legend(fontsize=7, ncol=2)
    ax_r.axhline(0, color="0.6", lw=0.6)
    ax_r.set_xlabel("mean seed spacing d / a")
    ax_r.set_ylabel("corrected - closed form at the realised fill factor")
    ax_r.set_title("residual: straight-line fits in d / a", fontsize=8)
    # Residual that the energy leaking off the face predicts for the leak's ratio:
    # S^2 loses leak * (S_fine^2 - 1) (the fluctuation part, module notes).
    leak = d["leak"]
    j = int(np.argmin(np.abs(np.log(d["ratios"] / a["params"]["leak_ratio"]))))
    s_fine = d["fine_grain_nominal"][j]
    ax_r.plot(x, -leak.mean(axis=1) * (s_fine**2 - 1) / (2 * s_fine), "kx", ms=6,
              label=f"from the rim leak, $k_2/k_1$ = {d['ratios'][j]:g}")
    ax_r.legend(fontsize=7)
    ax_l.errorbar(x, leak.mean(axis=1), yerr=leak.std(axis=1, ddof=1) / np.sqrt(leak.shape[1]),
                  fmt="o", color="k", ms=4, capsize=2,
                  label="fraction of the fluctuation energy off the face")
    slope = np.sum(leak.mean(axis=1) * x) / np.sum(x * x)
    ax_l.plot(xs, slope * xs, "k-", lw=0.7, label=f"{slope:.2f} d / a")
    ax_l.axhline(0, color="0.6", lw=0.6)
    ax_l.set_xlabel("mean seed spacing d / a")
    ax_l.set_title(f"rim layer, $k_2/k_1$ = {a['params']['leak_ratio']:g}, "
                   f"{leak.shape[1]} realisations", fontsize=8)
    ax_l.legend(fontsize=7)
    study_io.save_figure(fig, png)


def main(argv=None):
    """Run the study from the command line (``--help`` lists the options); exit status."""
    return study_io.run_study(NAME, __doc__, compute, plot, PARAMS, QUICK, argv, parallel=True,
                              default_sweep=voronoi_study.SWEEP)


if __name__ == "__main__":
    sys.exit(main())
