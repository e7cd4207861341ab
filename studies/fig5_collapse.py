"""Fig. 5: normalised rms slope against the fill factor and against the wear ratio.

Reproduces the paper's Fig. 5: (a) the realisation mean of ``rms / grad_f0``
(energy-corrected, grid ``n``, 10 realisations) against ``rho_2`` for five wear
ratios ``k_2 / k_1`` and all four coarseness levels (20^2 .. 160^2 seeds): the
collapse onto one curve per wear ratio; (b) against ``k_2 / k_1`` for several
``rho_2`` (40^2 seeds), with the two insert topographies at ``rho_2 = 0.3``
(``k_2 / k_1 = 0.1`` and ``10``).  Error bars are the realisation scatter
(standard deviation); the file holds the discretisation errors too.  Lines:
the fine-grain closed form of :func:`steady.reference.fine_grain_rms_slope`;
dashed in (a): the pillars asymptote ``1 / rho_2`` of eq. 18.

Run::

    python studies/fig5_collapse.py            # n = 512: 760 maps, ~27 min on 2 cores
                                               # (15 s once they are in the sweep file)
    python studies/fig5_collapse.py --quick    # a few seconds
    python studies/fig5_collapse.py --plot-only

The sweep points go to (or are reused from) ``OUT/voronoi_sweep_n<n>.h5``
(:mod:`voronoi_study`; Fig. 4 shares them).  Writes ``OUT/fig5_collapse.h5``
and ``OUT/fig5_collapse.png``.
"""

import sys

import numpy as np
import study_io
import voronoi_study

from steady.basis import PhaseBasis
from steady.outline import UNIT_DISK
from steady.phases import Voronoi
from steady.problem import FacePhases
from steady.reference import fine_grain_rms_slope

NAME = "fig5_collapse"
PARAMS = dict(voronoi_study.FULL, curve_ratios=[1e-3, 1e-2, 1e-1, 1e1, 1e3],
              curve_fills=[0.1, 0.3, 0.5, 0.7, 0.9], map_level=1600, ratio_range=[1e-3, 1e3],
              insert_fill=0.3, insert_ratios=[0.1, 10.0], insert_n=256)
QUICK = dict(voronoi_study.QUICK, curve_ratios=[1e-3, 1e-1, 1e1], curve_fills=[0.3, 0.7],
             map_level=100, ratio_range=[1e-3, 1e3], insert_fill=0.3,
             insert_ratios=[0.1, 10.0], insert_n=32)


def compute(path, params, *, workers=None, scheduler=None, progress=False):
    """Sweep all levels (reusing finished points), pick the curves; write HDF5."""
    data = voronoi_study.sweep_data(params, path, levels=params["levels"],
                                    fill_factors=params["fill_factors"], seeds=params["seeds"],
                                    workers=workers, scheduler=scheduler, progress=progress)
    cols = [voronoi_study.index_of(data.ratios, r) for r in params["curve_ratios"]]
    rows = [voronoi_study.index_of(data.fill_factors, f) for f in params["curve_fills"]]
    level = list(params["levels"]).index(params["map_level"])
    lo, hi = params["ratio_range"]
    keep = np.flatnonzero((data.ratios >= lo * (1 - 1e-9)) & (data.ratios <= hi * (1 + 1e-9)))
    rho = data.fill_factors
    fine_a = np.array([[fine_grain_rms_slope([1 - f, f], [1, r]) for f in rho]
                       for r in params["curve_ratios"]])
    ratios_b = data.ratios[keep]
    fine_b = np.array([[fine_grain_rms_slope([1 - f, f], [1, r]) for r in ratios_b]
                       for f in params["curve_fills"]])
    inserts = []
    geometry = Voronoi(params["map_level"], (1 - params["insert_fill"], params["insert_fill"]),
                       params["seeds"][0])
    grid = UNIT_DISK.grid(params["insert_n"])
    basis = PhaseBasis(FacePhases(grid, geometry.labels(grid), geometry.n_phases), 1.0)
    for r in params["insert_ratios"]:
        face = basis.face([1.0, r], np.pi) / (4 / np.pi)
        inserts.append(face - np.nanmin(face))
    return study_io.write_study(path, NAME, params, {
        "fill_factors": (rho, "1"),
        "levels": (np.asarray(params["levels"]), "1"),
        "a/mean": (data.mean[:, :, cols], "grad_f0"),
        "a/scatter": (data.scatter[:, :, cols], "grad_f0"),
        "a/error": (data.mean_error[:, :, cols], "grad_f0"),
        "a/fine_grain": (fine_a, "grad_f0"),
        "b/ratios": (ratios_b, "1"),
        "b/mean": (data.mean[level][rows][:, keep], "grad_f0"),
        "b/scatter": (data.scatter[level][rows][:, keep], "grad_f0"),
        "b/error": (data.mean_error[level][rows][:, keep], "grad_f0"),
        "b/fine_grain": (fine_b, "grad_f0"),
        "inserts": (np.asarray(inserts), "grad_f0 a"),
        "insert_labels": (basis.labels.astype(np.int8), "1"),
    }, {"n": (data.n, "1"), "realisations": (int(data.seeds.size), "1")})


def plot(path, png):
    """Fig. 5a, 5b and the inserts, from the HDF5 file."""
    d, a = study_io.read_study(path, NAME)
    p = a["params"]
    fig = study_io.figure(12.5, 4.6)
    ax_a, ax_b, ax_i = fig.subplots(1, 3, width_ratios=[1.2, 1.2, 0.55])
    rho = d["fill_factors"]
    markers = "os^D"
    for j, r in enumerate(p["curve_ratios"]):
        c = f"C{j}"
        ax_a.plot(rho, d["a/fine_grain"][j], color=c, lw=0.9, label=f"$k_2/k_1$ = {r:g}")
        for i in range(len(d["levels"])):
            ax_a.errorbar(rho, d["a/mean"][i, :, j], yerr=d["a/scatter"][i, :, j],
                          fmt=markers[i], ms=3.5, mfc="none", color=c, elinewidth=0.6,
                          capsize=1.5)
    for i, level in enumerate(d["levels"]):  # legend entries of the levels, in black
        ax_a.plot([], [], markers[i], mfc="none", color="k",
                  label=f"{int(round(np.sqrt(level)))}$^2$ seeds")
    ax_a.plot(rho, 1 / rho, "k--", lw=0.8, label=r"eq. 18: $1/\rho_2$")
    ax_a.set_yscale("log")
    ax_a.set_ylim(0.9, 25)
    study_io.plain_log_ticks(ax_a)
    ax_a.set_xlabel(r"$\rho_2$")
    ax_a.set_ylabel(r"rms slope / $\nabla f^0_\infty$")
    ax_a.set_title(f"(a) wear ratios (colours), coarseness levels (symbols);\n"
                   f"lines: fine-grain closed form; n = {a['n']}, "
                   f"{a['realisations']} realisations", fontsize=8)
    ax_a.legend(fontsize=6.5, loc="upper center", ncol=2)
    ratios = d["b/ratios"]
    for j, f in enumerate(p["curve_fills"]):
        c = f"C{j}"
        ax_b.errorbar(ratios, d["b/mean"][j], yerr=d["b/scatter"][j], fmt="o", ms=3, color=c,
                      elinewidth=0.6, capsize=1.5, label=f"$\\rho_2$ = {f:g}")
        ax_b.plot(ratios, d["b/fine_grain"][j], color=c, lw=0.9)
    ax_b.set_xscale("log")
    ax_b.set_xlabel(r"$k_2/k_1$")
    ax_b.set_ylabel(r"rms slope / $\nabla f^0_\infty$")
    side = int(round(np.sqrt(p["map_level"])))
    ax_b.set_title(f"(b) {side}$^2$ seeds; lines: fine-grain closed form", fontsize=8)
    ax_b.legend(fontsize=7)
    ax_i.axis("off")
    top, bottom = ax_i.inset_axes([0, 0.52, 1, 0.45]), ax_i.inset_axes([0, 0.0, 1, 0.45])
    vmax = float(np.nanmax(d["inserts"]))
    for ax, face, r in zip((top, bottom), d["inserts"], p["insert_ratios"], strict=False):
        im = ax.imshow(face.T, origin="lower", extent=(-1, 1, -1, 1), cmap="viridis",
                       vmin=0, vmax=vmax, interpolation="nearest")
        ax.set_title(f"$\\rho_2$ = {p['insert_fill']:g}, $k_2/k_1$ = {r:g}", fontsize=8)
        ax.set_xticks([])
        ax.set_yticks([])
    cb = fig.colorbar(im, cax=ax_i.inset_axes([0.05, -0.1, 0.9, 0.04]),
                      orientation="horizontal")
    cb.set_label(r"$(f_\infty - \min f_\infty) / (\nabla f^0_\infty a)$", fontsize=8)
    study_io.save_figure(fig, png)


def main(argv=None):
    """Run the study from the command line (``--help`` lists the options); exit status."""
    return study_io.run_study(NAME, __doc__, compute, plot, PARAMS, QUICK, argv, parallel=True,
                              default_sweep=voronoi_study.SWEEP)


if __name__ == "__main__":
    sys.exit(main())
