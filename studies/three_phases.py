"""Three phases: matrix, hard grains and soft grains on a Voronoi map (eq. 7, 9 for P = 3).

The paper's theory covers any number of phases (eq. 7, 9) but it shows only
two.  Here every seed of a Voronoi map (40^2 seeds, as the paper's sample 2)
is labelled matrix (phase 0, ``k_0``), hard (phase 1, ``k_0 / R``) or soft
(phase 2, ``k_0 R``), over a grid of hard and soft fill factors
``rho_h, rho_s = 0.05 .. 0.45`` and for two wear contrasts ``R = 10`` and
``R = 100``.  For every map: the energy-corrected normalised rms slope with
its discretisation error (grids ``n/4, n/2, n``), the mean relief of each
phase (the face minus the homogeneous face of the same load, averaged over
the phase, in units of ``grad_f0 d`` with ``d = 2a / sqrt(N)`` the mean seed
spacing), and the fine-grain closed form
(:func:`steady.reference.fine_grain_rms_slope` with three phases).

Reduction check: with the soft grains given the matrix's coefficient
(``k = (1, 1/R, 1)``) the three-phase map must be the two-phase map of
hard grains in the matrix.  :func:`reduction` compares the three-phase
value with the two-phase solve of the merged labels (the same pixels:
equal to round-off) and with the two-phase Voronoi map of Fig. 4b with the
same seed points and ``rho_2 = rho_h`` (other labels: equal within the
realisation scatter).

Run::

    python studies/three_phases.py            # n = 512, 250 maps, about 3 min on one core
    python studies/three_phases.py --quick    # about 2 s
    python studies/three_phases.py --plot-only

Writes ``OUT/three_phases.h5`` and ``OUT/three_phases.png``.
"""

import sys

import numpy as np
import study_io
from matplotlib.colors import ListedColormap

from steady.basis import PhaseBasis
from steady.outline import UNIT_DISK
from steady.phases import Voronoi
from steady.problem import FacePhases
from steady.reference import fine_grain_rms_slope
from steady.rms_slope import grid_ladder, ladder_error

NAME = "three_phases"
PHASES = ("matrix", "hard", "soft")
PARAMS = {"n": 512, "n_seeds": 1600, "contrasts": [10.0, 100.0],
          "hard_fill": [0.05, 0.15, 0.25, 0.35, 0.45], "soft_fill": [0.05, 0.15, 0.25, 0.35, 0.45],
          "seeds": list(range(4000, 4010)), "picture": [0.25, 0.25]}
QUICK = {"n": 64, "n_seeds": 100, "contrasts": [10.0, 100.0], "hard_fill": [0.1, 0.3],
         "soft_fill": [0.1, 0.3], "seeds": [4001, 4002], "picture": [0.3, 0.3]}


def _coefficients(contrasts):
    """Wear-coefficient rows: ``(1, 1/R, R)`` for each contrast, then ``(1, 1/R, 1)``."""
    full = [(1.0, 1.0 / r, r) for r in contrasts]
    reduced = [(1.0, 1.0 / r, 1.0) for r in contrasts]
    return np.array(full + reduced)


def reduction(geometry, n, contrasts):
    """Three-phase rms slopes with ``k_soft = k_matrix`` against two-phase maps.

    Parameters
    ----------
    geometry : steady.phases.Voronoi
        Three phases: matrix, hard, soft.
    n : int
        Grid.
    contrasts : sequence of float, shape (C,)
        ``R``: hard grains wear ``1/R`` as fast as the matrix.

    Returns
    -------
    three : ndarray, shape (C,)
        Normalised rms slope of the three-phase map with ``k = (1, 1/R, 1)``.
    merged : ndarray, shape (C,)
        Two-phase map of the same pixels (soft merged into the matrix),
        ``k = (1, 1/R)``.
    voronoi : ndarray, shape (C,)
        Two-phase Voronoi map with the same seed points and
        ``rho_2 = rho_hard`` (Fig. 4b's map), ``k = (1, 1/R)``.
    """
    grid = UNIT_DISK.grid(n)
    labels = geometry.labels(grid)
    k3 = np.array([(1.0, 1.0 / r, 1.0) for r in contrasts])
    k2 = k3[:, :2]
    three = PhaseBasis(FacePhases(grid, labels, 3), 1.0,
                       faces=False).rms_slopes(k3, np.pi).normalised
    merged_labels = np.where(labels < 0, -1, (labels == 1).astype(labels.dtype))
    merged = PhaseBasis(FacePhases(grid, merged_labels, 2), 1.0,
                        faces=False).rms_slopes(k2, np.pi).normalised
    rho_h = geometry.fill_factors[1]
    two = Voronoi(geometry.n_seeds, (1.0 - rho_h, rho_h), geometry.seed)
    voronoi = PhaseBasis(FacePhases(grid, two.labels(grid), 2), 1.0,
                         faces=False).rms_slopes(k2, np.pi).normalised
    return three, merged, voronoi


def map_values(geometry, n, contrasts):
    """Rms slopes (with error), phase reliefs and fill factors of one three-phase map.

    Returns
    -------
    dict
        ``rms`` (K,) normalised rms slope on grid ``n`` for the rows of
        :func:`_coefficients`; ``error`` (K,) its ladder error; ``relief``
        (K, 3) mean of ``f - f_homogeneous`` over each phase in units of
        ``grad_f0 d``; ``fill`` (3,) realised fill factors.
    """
    k = _coefficients(contrasts)
    grids = grid_ladder(geometry, n)
    values = []
    for m in grids:
        grid = UNIT_DISK.grid(m)
        phases = FacePhases(grid, geometry.labels(grid), geometry.n_phases)
        basis = PhaseBasis(phases, 1.0, faces=m == n)
        values.append(basis.rms_slopes(k, np.pi).normalised)  # pbar = 1 Pa, E* = 1 Pa
        if m == n:
            labels = basis.labels
            flat = basis.face(np.ones(3), np.pi)
            grad_f0 = 4.0 / np.pi
            spacing = 2.0 / np.sqrt(geometry.n_seeds)
            relief = np.array([[np.mean((basis.face(row, np.pi) - flat)[labels == i])
                                for i in range(3)] for row in k]) / (grad_f0 * spacing)
            fill = basis.fill_factors
    values = np.asarray(values)
    return {"rms": values[-1], "error": ladder_error(grids, values), "relief": relief,
            "fill": fill}


def compute(path, params):
    """Every (hard fill, soft fill, realisation) map; write HDF5."""
    n, contrasts = params["n"], params["contrasts"]
    hard, soft, seeds = params["hard_fill"], params["soft_fill"], params["seeds"]
    k = _coefficients(contrasts)
    shape = (len(hard), len(soft), len(seeds))
    rms = np.full(shape + (len(k),), np.nan)
    error = np.full_like(rms, np.nan)
    relief = np.full(shape + (len(k), 3), np.nan)
    fill = np.full(shape + (3,), np.nan)
    red = np.full(shape + (3, len(contrasts)), np.nan)
    for i, rh in enumerate(hard):
        for j, rs in enumerate(soft):
            for s, seed in enumerate(seeds):
                geometry = Voronoi(params["n_seeds"], (1.0 - rh - rs, rh, rs), seed)
                v = map_values(geometry, n, contrasts)
                rms[i, j, s], error[i, j, s] = v["rms"], v["error"]
                relief[i, j, s], fill[i, j, s] = v["relief"], v["fill"]
                red[i, j, s] = reduction(geometry, n, contrasts)
    closed = fine_grain_rms_slope(fill[:, :, :, None, :], k)  # at the realised fill factors
    nominal = np.array([[fine_grain_rms_slope((1 - rh - rs, rh, rs), k) for rs in soft]
                        for rh in hard])
    mean, sd = rms.mean(axis=2), rms.std(axis=2, ddof=1)
    exact = np.abs(red[..., 0, :] / red[..., 1, :] - 1)
    # The two-phase map does not depend on rho_s: average the three-phase values over
    # rho_s first, so that each two-phase map enters once (independent differences).
    two_diff = red[..., 0, :].mean(axis=1) - red[:, 0, :, 2, :]  # (hard, seed, contrast)
    two_diff = two_diff.reshape(-1, len(contrasts))
    nc = len(contrasts)
    picture = Voronoi(params["n_seeds"], (1.0 - sum(params["picture"]), *params["picture"]),
                      seeds[0])
    return study_io.write_study(path, NAME, params, {
        "hard_fill": (np.asarray(hard), "1"),
        "soft_fill": (np.asarray(soft), "1"),
        "contrasts": (np.asarray(contrasts), "1"),
        "wear_coefficients": (k, "k_matrix"),
        "rms_slope": (rms, "grad_f0"),
        "rms_slope_error": (error, "grad_f0"),
        "mean": (mean, "grad_f0"),
        "scatter": (sd, "grad_f0"),
        "closed_form_realised": (closed, "grad_f0"),
        "closed_form": (nominal, "grad_f0"),
        "relief": (relief, "grad_f0 d"),
        "realised_fill": (fill, "1"),
        "reduction_three": (red[..., 0, :], "grad_f0"),
        "reduction_merged": (red[..., 1, :], "grad_f0"),
        "reduction_voronoi": (red[..., 2, :], "grad_f0"),
        "picture_labels": (picture.labels(n).astype(np.int8), "1"),
    }, {
        "realisations": (len(seeds), "1"),
        "reduction_max_relative_difference": (float(exact.max()), "1"),
        "reduction_voronoi_mean_difference": (two_diff.mean(axis=0), "grad_f0"),
        "reduction_voronoi_sem": (two_diff.std(axis=0, ddof=1) / np.sqrt(len(two_diff)),
                                  "grad_f0"),
        "max_error": (float(error[..., :nc].max()), "grad_f0"),
        "max_error_over_scatter": (float(np.max(error.mean(axis=2)[..., :nc]
                                                / sd[..., :nc])), "1"),
        "max_deviation_closed_form": (
            float(np.max(np.abs(rms[..., :nc] / closed[..., :nc] - 1))), "1"),
        "mean_deviation_closed_form": (
            float(np.mean(rms[..., :nc] / closed[..., :nc] - 1)), "1"),
    })


def plot(path, png):
    """Rms-slope maps, phase reliefs and the reduction check, from the HDF5 file."""
    d, a = study_io.read_study(path, NAME)
    p = a["params"]
    contrasts = d["contrasts"]
    nc = contrasts.size
    fig = study_io.figure(13.0, 8.0)
    axes = fig.subplots(2, 3)
    hard, soft = d["hard_fill"], d["soft_fill"]
    sem = d["scatter"] / np.sqrt(a["realisations"])
    for c in range(nc):
        ax = axes[0, c]
        mean = d["mean"][..., c]
        im = ax.pcolormesh(soft, hard, mean, shading="nearest", cmap="magma")
        fig.colorbar(im, ax=ax, shrink=0.85).set_label(r"rms slope / $\nabla f^0_\infty$")
        for i, rh in enumerate(hard):
            for j, rs in enumerate(soft):
                dev = (mean[i, j] - d["closed_form"][i, j, c]) / max(sem[i, j, c], 1e-12)
                ax.text(rs, rh, f"{mean[i, j]:.2f}\n{dev:+.1f}σ", ha="center", va="center",
                        fontsize=6.5, color="w" if mean[i, j] < 0.6 * mean.max() else "k")
        ax.set_xlabel(r"soft fill factor $\rho_s$ ($k = R\,k_0$)")
        ax.set_ylabel(r"hard fill factor $\rho_h$ ($k = k_0/R$)")
        ax.set_title(f"R = {contrasts[c]:g}: mean of {a['realisations']} maps; "
                     f"second line: minus\nthe 3-phase fine-grain form, in standard errors",
                     fontsize=8.5)
    ax = axes[0, 2]
    labels = d["picture_labels"].astype(float)
    cmap = ListedColormap(["#bdbdbd", "#252525", "#e6a03c"])
    ax.imshow(np.ma.masked_less(labels, 0).T, origin="lower", extent=(-1, 1, -1, 1), cmap=cmap,
              interpolation="nearest")
    ax.set_title(f"matrix (grey), hard (black), soft (orange)\n"
                 f"$\\rho_h$ = $\\rho_s$ = {p['picture'][0]:g}, seed {p['seeds'][0]}",
                 fontsize=8.5)
    ax.set_xticks([])
    ax.set_yticks([])
    mid = len(soft) // 2
    colours = {"matrix": "0.45", "hard": "k", "soft": "C1"}
    for c in range(nc):
        ax = axes[1, c]
        rel = d["relief"][:, mid, :, c, :]  # (hard, realisation, phase)
        for q, name in enumerate(PHASES):
            ax.errorbar(hard, rel[..., q].mean(axis=1), yerr=rel[..., q].std(axis=1, ddof=1),
                        color=colours[name], marker="o", ms=3, capsize=2, lw=1,
                        label=f"{name} grains" if name != "matrix" else "matrix")
        ax.axhline(0, color="0.7", lw=0.6)
        ax.set_xlabel(r"hard fill factor $\rho_h$")
        ax.set_ylabel(r"mean relief of the phase / ($\nabla f^0_\infty\,d$)")
        ax.set_title(f"R = {contrasts[c]:g}, $\\rho_s$ = {soft[mid]:g}: face minus the "
                     f"homogeneous face\n(d = 2a/√N, mean seed spacing; bars: scatter)",
                     fontsize=8.5)
        ax.legend(fontsize=7)
    ax = axes[1, 2]
    three, merged, vor = (d[f"reduction_{k}"] for k in ("three", "merged", "voronoi"))
    for c in range(nc):
        ax.plot(vor[..., c].ravel(), three[..., c].ravel(), ".", ms=3, color=f"C{c}",
                label=f"R = {contrasts[c]:g}: 2-phase Voronoi map, same seeds")
    lim = [min(three.min(), vor.min()), max(three.max(), vor.max())]
    ax.plot(lim, lim, color="0.5", lw=0.7)
    ax.set_xlabel(r"two-phase map, $\rho_2 = \rho_h$: rms slope / $\nabla f^0_\infty$")
    ax.set_ylabel(r"three phases, $k_s = k_0$: rms slope / $\nabla f^0_\infty$")
    diffs = ", ".join(f"{m:+.3f} ± {e:.3f}" for m, e in
                      zip(a["reduction_voronoi_mean_difference"], a["reduction_voronoi_sem"],
                          strict=True))
    ax.set_title(f"reduction: same pixels merged, max rel. diff. "
                 f"{a['reduction_max_relative_difference']:.1e};\nnew Voronoi labels, mean "
                 f"diff. (R = {', '.join(f'{c:g}' for c in contrasts)}):\n{diffs}",
                 fontsize=8)
    ax.legend(fontsize=7)
    study_io.save_figure(fig, png, dpi=75)


def main(argv=None):
    """Run the study from the command line (``--help`` lists the options); exit status."""
    return study_io.run_study(NAME, __doc__, compute, plot, PARAMS, QUICK, argv)


if __name__ == "__main__":
    sys.exit(main())
