"""Fig. 4: four coarseness levels at rho_2 = 0.5, and the map of the normalised rms slope.

Reproduces the paper's Fig. 4: (a) biphasic Voronoi maps with 20^2, 40^2,
80^2 and 160^2 seeds at ``rho_2 = 0.5``; (b) the realisation mean of the
normalised rms slope ``rms / grad_f0`` (energy-corrected, grid ``n``) over
``rho_2 = 0.05 .. 0.95`` and ``k_2 / k_1 = 10^-3 .. 10^3`` for 40^2 seeds
(the paper's sample 2), 10 realisations.  The file also holds, for every map
point, the realisation scatter (standard deviation), the discretisation error
of the mean (grids ``n, n/2, n/4``) and the plain pixel value.

Run::

    python studies/fig4_coarseness.py            # n = 512: 190 maps, ~7 min on 2 cores
                                                 # (seconds once they are in the sweep file)
    python studies/fig4_coarseness.py --n 256    # 31 s on 2 cores
    python studies/fig4_coarseness.py --quick    # a few seconds
    python studies/fig4_coarseness.py --plot-only
    python studies/fig4_coarseness.py --scheduler tcp://host:8786   # on a Dask cluster

The sweep points go to (or are reused from) ``OUT/voronoi_sweep_n<n>.h5``
(:mod:`voronoi_study`).  Writes ``OUT/fig4_coarseness.h5`` and
``OUT/fig4_coarseness.png``.
"""

import sys

import numpy as np
import study_io
import voronoi_study
from matplotlib.colors import ListedColormap

from steady.phases import Voronoi

NAME = "fig4_coarseness"
PARAMS = dict(voronoi_study.FULL, map_level=1600, picture_fill=0.5, picture_n=512,
              ratio_range=[1e-3, 1e3])
QUICK = dict(voronoi_study.QUICK, map_level=100, picture_fill=0.5, picture_n=64,
             ratio_range=[1e-3, 1e3])


def compute(path, params, *, workers=None, scheduler=None, progress=False):
    """Sweep the map level (reusing finished points); write the map and the pictures."""
    data = voronoi_study.sweep_data(params, path, levels=[params["map_level"]],
                                    fill_factors=params["fill_factors"], seeds=params["seeds"],
                                    workers=workers, scheduler=scheduler, progress=progress)
    lo, hi = params["ratio_range"]
    keep = (data.ratios >= lo * (1 - 1e-9)) & (data.ratios <= hi * (1 + 1e-9))
    mean, sd, err = data.mean[0][:, keep], data.scatter[0][:, keep], data.mean_error[0][:, keep]
    sem = sd / np.sqrt(data.seeds.size)
    # At k_2 = k_1 every map gives the homogeneous face: no scatter, left out.
    varied = np.broadcast_to(np.abs(np.log(data.ratios[keep])) > 1e-9, mean.shape)
    err_v, sd_v, sem_v = err[varied], sd[varied], sem[varied]
    pictures = [Voronoi(c, (1 - params["picture_fill"], params["picture_fill"]),
                        params["seeds"][0]).labels(params["picture_n"]).astype(np.int8)
                for c in params["levels"]]
    return study_io.write_study(path, NAME, params, {
        "fill_factors": (data.fill_factors, "1"),
        "ratios": (data.ratios[keep], "1"),
        "mean": (mean, "grad_f0"),
        "scatter": (sd, "grad_f0"),
        "error": (err, "grad_f0"),
        "plain_mean": (data.rms_slope_plain[0].mean(axis=1)[:, keep], "grad_f0"),
        "realised_fill_factors": (data.realised[0], "1"),
        "pictures": (np.asarray(pictures), "1"),
        "levels": (np.asarray(params["levels"]), "1"),
    }, {
        "n": (data.n, "1"),
        "realisations": (int(data.seeds.size), "1"),
        "max_error": (float(err.max()), "grad_f0"),
        "max_error_over_scatter": (float(np.max(err_v / sd_v)), "1"),
        "max_error_over_sem": (float(np.max(err_v / sem_v)), "1"),
        "fraction_error_below_sem": (float(np.mean(err_v < sem_v)), "1"),
        "max_relative_scatter": (float(np.max(sd / mean)), "1"),
    })


def plot(path, png):
    """Four maps and the rms-slope map, from the HDF5 file."""
    d, a = study_io.read_study(path, NAME)
    p = a["params"]
    fig = study_io.figure(10.0, 6.4)
    top, bottom = fig.subfigures(2, 1, height_ratios=[1, 1.55])
    cmap = ListedColormap(["#bdbdbd", "#252525"])
    axes = top.subplots(1, len(d["levels"]))
    for ax, pic, level in zip(axes, d["pictures"], d["levels"], strict=True):
        ax.imshow(np.ma.masked_less(pic, 0).T, origin="lower", extent=(-1, 1, -1, 1),
                  cmap=cmap, interpolation="nearest")
        side = int(round(np.sqrt(level)))
        ax.set_title(f"{side}$^2$ seeds", fontsize=9)
        ax.set_xticks([])
        ax.set_yticks([])
    top.suptitle(f"(a) $\\rho_2$ = {p['picture_fill']:g}, seed {p['seeds'][0]}", fontsize=10)
    ax, ax_err = bottom.subplots(1, 2, width_ratios=[1.35, 1])
    x = np.log10(d["ratios"])
    y = d["fill_factors"]
    im = ax.pcolormesh(x, y, d["mean"], shading="nearest", cmap="magma")
    cs = ax.contour(x, y, d["mean"], levels=[1.2, 1.5, 2, 3, 5], colors="w", linewidths=0.7)
    ax.clabel(cs, fontsize=7)
    cb = bottom.colorbar(im, ax=ax)
    cb.set_label(r"rms slope / $\nabla f^0_\infty$")
    ax.set_xlabel(r"$\log_{10}(k_2/k_1)$")
    ax.set_ylabel(r"$\rho_2$")
    side = int(round(np.sqrt(p["map_level"])))
    ax.set_title(f"(b) mean of {a['realisations']} realisations, {side}$^2$ seeds, "
                 f"n = {a['n']}", fontsize=9)
    sem = d["scatter"] / np.sqrt(a["realisations"])
    ratio = np.full_like(sem, np.nan)
    # k_2 = k_1 gives the homogeneous face for every map: no scatter, left blank.
    np.divide(d["error"], sem, out=ratio, where=sem > 1e-9 * d["mean"])
    im2 = ax_err.pcolormesh(x, y, ratio, shading="nearest", cmap="viridis", vmin=0,
                            vmax=max(1.0, float(np.nanmax(ratio))))
    cb2 = bottom.colorbar(im2, ax=ax_err)
    cb2.set_label("discretisation error / standard error of the mean")
    ax_err.set_xlabel(r"$\log_{10}(k_2/k_1)$")
    ax_err.set_ylabel(r"$\rho_2$")
    ax_err.set_title(f"error of the mean below its standard error at "
                     f"{100 * a['fraction_error_below_sem']:.0f} % of the points\n"
                     f"(max error {a['max_error']:.1e}, max error/scatter "
                     f"{a['max_error_over_scatter']:.2f})", fontsize=8)
    study_io.save_figure(fig, png)


def main(argv=None):
    """Run the study from the command line (``--help`` lists the options); exit status."""
    return study_io.run_study(NAME, __doc__, compute, plot, PARAMS, QUICK, argv, parallel=True,
                              default_sweep=voronoi_study.SWEEP)


if __name__ == "__main__":
    sys.exit(main())
