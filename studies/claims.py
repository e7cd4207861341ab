"""The paper's three analytical claims: pillars asymptote, symmetry, tyre design rule.

Tests, on the Voronoi sweep (energy-corrected rms slope, grid ``n = 512``,
10 realisations):

- the pillars asymptote (eq. 16-18): for few hard inclusions and
  ``k_2 / k_1 -> 0``, ``rms -> grad_f0 / rho_2``.  Compared with the sweep at
  ``k_2 / k_1 = 10^-4 .. 10^-2`` (80^2 seeds, ``rho_2 = 0.01 .. 0.5``), with the
  fine-grain closed form (:func:`steady.reference.fine_grain_rms_slope`,
  ``sqrt(1 + (pi^2/4)(1/rho_2 - 1))`` in that limit) and with the Parseval
  bound ``(pi/2) / sqrt(rho_2)`` that no map can exceed;
- the symmetry ``S(rho_2, k_2/k_1) = S(1 - rho_2, k_1/k_2)``: exactly, on one
  map with its phases swapped, and statistically, between the realisation
  means of independent maps at the two mirrored points (all four coarseness
  levels, all fill factors and wear ratios);
- the tyre design rule: at ``pbar / E* = 0.08`` an rms slope of order one
  needs a hard-phase fill factor of about 0.1.  Inverted with the design
  table (:class:`steady.design.DesignTable`, 80^2 seeds) for several wear
  ratios.

Run::

    python studies/claims.py            # 35 s once the sweep is in OUT/voronoi_sweep_n512.h5;
                                        # from scratch 840 maps, ~30 min on 2 cores
    python studies/claims.py --quick    # a few seconds
    python studies/claims.py --plot-only

Writes ``OUT/claims.h5`` and ``OUT/claims.png``.
"""

import sys

import numpy as np
import study_io
import voronoi_study

from steady.basis import PhaseBasis
from steady.design import DesignTable
from steady.outline import UNIT_DISK
from steady.phases import Voronoi
from steady.problem import FacePhases
from steady.reference import fine_grain_rms_slope

NAME = "claims"
EXTRA_FILLS = [0.01, 0.02, 0.03, 0.04]
PARAMS = dict(voronoi_study.FULL, table_level=6400,
              extra_fills=EXTRA_FILLS + [0.96, 0.97, 0.98, 0.99],
              pillar_ratios=[1e-4, 1e-3, 1e-2], pillar_max_fill=0.5,
              tyre_pbar_over_estar=0.08, tyre_target=1.0, tyre_ratios=[1e-1, 1e-2, 1e-3, 1e-4],
              tyre_fill=0.1, swap_n=256, swap_level=1600, swap_fill=0.3)
QUICK = dict(voronoi_study.QUICK, table_level=100, extra_fills=[0.05, 0.95],
             pillar_ratios=[1e-3, 1e-2], pillar_max_fill=0.5, tyre_pbar_over_estar=0.08,
             tyre_target=0.2, tyre_ratios=[1e-1, 1e-2, 1e-3], tyre_fill=0.1, swap_n=32,
             swap_level=100, swap_fill=0.3)


def compute(path, params, *, workers=None, scheduler=None, progress=False):
    """Sweep (reusing finished points), evaluate the three claims; write HDF5."""
    common = dict(workers=workers, scheduler=scheduler, progress=progress)
    rho = np.asarray(params["fill_factors"])
    all_levels = voronoi_study.sweep_data(params, path, levels=params["levels"],
                                          fill_factors=rho, seeds=params["seeds"], **common)
    fills = np.unique(np.concatenate([rho, params["extra_fills"]]))
    table_data = voronoi_study.sweep_data(params, path, levels=[params["table_level"]],
                                          fill_factors=fills, seeds=params["seeds"], **common)
    ratios = all_levels.ratios
    m = all_levels.seeds.size
    out, attrs = {}, {"n": (all_levels.n, "1"), "realisations": (int(m), "1")}

    # Pillars: small rho_2, k_2/k_1 -> 0.
    small = fills <= params["pillar_max_fill"] + 1e-12
    cols = [voronoi_study.index_of(ratios, r) for r in params["pillar_ratios"]]
    out["pillars/fill_factors"] = (fills[small], "1")
    out["pillars/ratios"] = (np.asarray(params["pillar_ratios"]), "1")
    out["pillars/mean"] = (table_data.mean[0][small][:, cols], "grad_f0")
    out["pillars/scatter"] = (table_data.scatter[0][small][:, cols], "grad_f0")
    out["pillars/error"] = (table_data.mean_error[0][small][:, cols], "grad_f0")
    f = fills[small]
    out["pillars/eq18"] = (1.0 / f, "grad_f0")
    out["pillars/fine_grain_limit"] = (np.sqrt(1 + np.pi**2 / 4 * (1 / f - 1)), "grad_f0")
    out["pillars/parseval_bound"] = (np.pi / 2 / np.sqrt(f), "grad_f0")
    # The bound for every realisation at its realised fill factor and pressures.
    rr = table_data.realised[0][small]
    bound = np.empty(rr.shape + (len(cols),))
    for j, c in enumerate(cols):
        r = ratios[c]
        p1 = 1.0 / ((1 - rr) + rr / r)
        bound[..., j] = np.pi / 2 * np.sqrt((1 - rr) * p1**2 + rr * (p1 / r) ** 2)
    excess = table_data.rms_slope[0][small][:, :, cols] - bound
    attrs["pillars_max_over_bound"] = (float(excess.max()), "grad_f0")

    # Symmetry: statistically, between mirrored sweep points.
    mean, sem = all_levels.mean, all_levels.scatter / np.sqrt(m)
    mirrored = mean[:, ::-1, ::-1]
    diff = mean - mirrored
    z = diff / np.sqrt(sem**2 + sem[:, ::-1, ::-1] ** 2 + 1e-300)
    varied = np.abs(np.log(ratios)) > 1e-9
    out["symmetry/mean"] = (mean, "grad_f0")
    out["symmetry/mirrored"] = (mirrored, "grad_f0")
    out["symmetry/z"] = (z, "1")
    attrs["symmetry_max_relative_difference"] = (float(np.max(np.abs(diff / mean))), "1")
    zv = z[:, :, varied]
    attrs["symmetry_max_abs_z"] = (float(np.max(np.abs(zv))), "1")
    attrs["symmetry_fraction_abs_z_below_2"] = (float(np.mean(np.abs(zv) < 2)), "1")
    # Exactly: one map and the same map with its phases swapped.
    g = Voronoi(params["swap_level"], (1 - params["swap_fill"], params["swap_fill"]),
                params["seeds"][0])
    grid = UNIT_DISK.grid(params["swap_n"])
    labels = g.labels(grid)
    swapped = np.where(labels >= 0, 1 - labels, -1)
    k = np.column_stack([np.ones(ratios.size), ratios])
    a_ = PhaseBasis(FacePhases(grid, labels, 2), 1.0, faces=False).rms_slopes(k, np.pi).normalised
    b_ = PhaseBasis(FacePhases(grid, swapped, 2), 1.0,
                    faces=False).rms_slopes(k[:, ::-1], np.pi).normalised
    attrs["symmetry_swapped_max_relative_difference"] = (float(np.max(np.abs(a_ / b_ - 1))),
                                                         "1")

    # Tyre rule at pbar/E* = 0.08.
    table = DesignTable.from_voronoi(table_data)
    q = params["tyre_pbar_over_estar"]
    g0 = 4 * q / np.pi
    tyre_fill, tyre_low, tyre_high, reach, at_fill, at_fill_sd = [], [], [], [], [], []
    for r in params["tyre_ratios"]:
        try:
            res = table.fill_factor_for(q, r, params["tyre_target"])
            tyre_fill.append(res.fill_factor)
            tyre_low.append(res.fill_factor_range[0])
            tyre_high.append(res.fill_factor_range[1])
        except ValueError:
            tyre_fill.append(np.nan)
            tyre_low.append(np.nan)
            tyre_high.append(np.nan)
        reach.append(g0 * float(table.curve(r)[0].max()))
        v, sd = table.rms_slope(q, r, params["tyre_fill"])
        at_fill.append(v)
        at_fill_sd.append(sd)
    dense = np.linspace(table.fill_factors[0], table.fill_factors[-1], 300)
    curves = np.array([g0 * table.curve(r, dense)[0] for r in params["tyre_ratios"]])
    fine = np.array([[g0 * fine_grain_rms_slope([1 - x, x], [1, r]) for x in dense]
                     for r in params["tyre_ratios"]])
    out["tyre/ratios"] = (np.asarray(params["tyre_ratios"]), "1")
    out["tyre/fill_factor"] = (np.asarray(tyre_fill), "1")
    out["tyre/fill_factor_low"] = (np.asarray(tyre_low), "1")
    out["tyre/fill_factor_high"] = (np.asarray(tyre_high), "1")
    out["tyre/max_rms_slope"] = (np.asarray(reach), "1")
    out["tyre/rms_slope_at_fill"] = (np.asarray(at_fill), "1")
    out["tyre/rms_slope_at_fill_scatter"] = (np.asarray(at_fill_sd), "1")
    out["tyre/dense_fill"] = (dense, "1")
    out["tyre/curves"] = (curves, "1")
    out["tyre/fine_grain"] = (fine, "1")
    # Fine-grain limit k_2/k_1 -> 0: rho_2 at which the target is reached.
    t = params["tyre_target"] / g0
    attrs["tyre_fine_grain_limit_fill"] = (float(1 / (1 + (t * t - 1) * 4 / np.pi**2)), "1")
    attrs["tyre_reference_slope"] = (g0, "1")
    return study_io.write_study(path, NAME, params, out, attrs)


def plot(path, png):
    """Pillars, symmetry and tyre-rule panels, from the HDF5 file."""
    d, a = study_io.read_study(path, NAME)
    p = a["params"]
    fig = study_io.figure(13.0, 4.3)
    ax_p, ax_s, ax_t = fig.subplots(1, 3)
    f = d["pillars/fill_factors"]
    for j, r in enumerate(d["pillars/ratios"]):
        ax_p.errorbar(f, d["pillars/mean"][:, j], yerr=d["pillars/scatter"][:, j], fmt="o",
                      ms=3.5, capsize=1.5, color=f"C{j}", label=f"sweep, $k_2/k_1$ = {r:g}")
    ax_p.plot(f, d["pillars/eq18"], "k--", lw=0.9, label=r"eq. 18: $1/\rho_2$")
    ax_p.plot(f, d["pillars/fine_grain_limit"], "k-", lw=0.9,
              label=r"fine grain, $k_2/k_1\to 0$")
    ax_p.plot(f, d["pillars/parseval_bound"], ":", color="C3", lw=1.0,
              label=r"bound $(\pi/2)/\sqrt{\rho_2}$")
    ax_p.set_xscale("log")
    ax_p.set_yscale("log")
    study_io.plain_log_ticks(ax_p)
    ax_p.set_xlabel(r"$\rho_2$ (hard phase)")
    ax_p.set_ylabel(r"rms slope / $\nabla f^0_\infty$")
    side = int(round(np.sqrt(p["table_level"])))
    ax_p.set_title(f"(a) pillars: {side}$^2$ seeds, n = {a['n']}", fontsize=9)
    ax_p.legend(fontsize=7)
    mean, mir = d["symmetry/mean"], d["symmetry/mirrored"]
    ax_s.plot(mean.ravel(), mir.ravel(), ".", ms=2, color="C0")
    lim = [0.9, float(max(mean.max(), mir.max())) * 1.05]
    ax_s.plot(lim, lim, "k-", lw=0.6)
    ax_s.set_xscale("log")
    ax_s.set_yscale("log")
    study_io.plain_log_ticks(ax_s)
    ax_s.set_xlabel(r"$S(\rho_2, k_2/k_1)$")
    ax_s.set_ylabel(r"$S(1-\rho_2, k_1/k_2)$")
    ax_s.set_title(f"(b) symmetry, all levels: max |difference| "
                   f"{100 * a['symmetry_max_relative_difference']:.1f} %,\n"
                   f"{100 * a['symmetry_fraction_abs_z_below_2']:.0f} % within 2 standard "
                   f"errors; same map swapped: "
                   f"{a['symmetry_swapped_max_relative_difference']:.0e}", fontsize=8)
    dense = d["tyre/dense_fill"]
    for j, r in enumerate(d["tyre/ratios"]):
        ax_t.plot(dense, d["tyre/curves"][j], color=f"C{j}", lw=1.0,
                  label=f"$k_2/k_1$ = {r:g}")
        ax_t.plot(dense, d["tyre/fine_grain"][j], color=f"C{j}", lw=0.7, ls=":")
    ax_t.axhline(p["tyre_target"], color="k", lw=0.7)
    ax_t.axvline(p["tyre_fill"], color="0.5", lw=0.7, ls="--")
    ax_t.set_xscale("log")
    study_io.plain_log_ticks(ax_t)
    ax_t.set_xlabel(r"$\rho_2$ (hard phase)")
    ax_t.set_ylabel("rms slope")
    ax_t.set_title(f"(c) tyre rule, $\\bar p/E^*$ = {p['tyre_pbar_over_estar']:g}: "
                   f"target {p['tyre_target']:g} (line),\npaper's $\\rho_2$ = "
                   f"{p['tyre_fill']:g} (dashed); dotted: fine-grain closed form", fontsize=8)
    ax_t.legend(fontsize=7)
    study_io.save_figure(fig, png)


def main(argv=None):
    """Run the study from the command line (``--help`` lists the options); exit status."""
    return study_io.run_study(NAME, __doc__, compute, plot, PARAMS, QUICK, argv, parallel=True,
                              default_sweep=voronoi_study.SWEEP)


if __name__ == "__main__":
    sys.exit(main())
