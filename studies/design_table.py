"""The design table: normalised rms slope over fill factor and wear ratio, with its scatter.

Builds the table behind ``runin-design`` (:class:`steady.design.DesignTable`):
the realisation mean, the realisation scatter (standard deviation) and the
discretisation error of the normalised rms slope ``rms / grad_f0`` of
biphasic Voronoi maps with 80^2 seeds (fine grains: the finite-size effect is
below the scatter; see ``scale_independence.py``), 10 realisations, grid
``n = 512`` (energy-corrected), over ``rho_2 = 0.01 .. 0.99`` and
``k_2 / k_1 = 10^-4 .. 10^4``.  The figure shows the table with the
fine-grain closed form.

Run::

    python studies/design_table.py            # 20 s once the sweep is in
                                              # OUT/voronoi_sweep_n512.h5; from scratch
                                              # 270 maps, ~10 min on 2 cores
    python studies/design_table.py --quick    # a few seconds
    python studies/design_table.py --plot-only
    python studies/design_table.py --docs-figures   # rebuild the shipped table

Writes ``OUT/design_table.h5`` and ``OUT/design_table.png``; with
``--docs-figures``, the table shipped as package data of ``steady``,
``steady/data/design_table.h5``, and ``docs/figures/design_table.png``.
"""

import sys

import numpy as np
import study_io
import voronoi_study

from steady.design import DesignTable
from steady.reference import fine_grain_rms_slope

NAME = "design_table"
#: The shipped table, in the source tree (package data of ``steady``).
TABLE = study_io.ROOT / "steady" / "data" / "design_table.h5"
PARAMS = dict(voronoi_study.FULL, table_level=6400,
              extra_fills=[0.01, 0.02, 0.03, 0.04, 0.96, 0.97, 0.98, 0.99])
QUICK = dict(voronoi_study.QUICK, table_level=100, extra_fills=[0.05, 0.95])
#: Wear ratios drawn in the figure (those the table holds).
SHOWN_RATIOS = [1e-4, 1e-3, 1e-2, 1e-1, 1e1, 1e2]


def compute(path, params, *, workers=None, scheduler=None, progress=False):
    """Sweep the table's level (reusing finished points); write the table."""
    fills = np.unique(np.concatenate([params["fill_factors"], params["extra_fills"]]))
    data = voronoi_study.sweep_data(params, path, levels=[params["table_level"]],
                                    fill_factors=fills, seeds=params["seeds"], workers=workers,
                                    scheduler=scheduler, progress=progress)
    table = DesignTable.from_voronoi(data, attrs={"source": "studies/design_table.py"})
    return table.write(path, force=True)


def plot(path, png):
    """Table curves with their scatter and the closed form, from the table file."""
    table = DesignTable.read(path)
    fig = study_io.figure(6.5, 4.3)
    ax = fig.subplots()
    rho = table.fill_factors
    shown = [r for r in SHOWN_RATIOS if np.any(np.isclose(table.ratios, r, rtol=1e-6))]
    for j, r in enumerate(shown):
        c = voronoi_study.index_of(table.ratios, r)
        ax.fill_between(rho, table.mean[:, c] - table.scatter[:, c],
                        table.mean[:, c] + table.scatter[:, c], color=f"C{j}", alpha=0.3, lw=0)
        ax.plot(rho, table.mean[:, c], "o-", ms=2.5, lw=0.8, color=f"C{j}",
                label=f"$k_2/k_1$ = {r:g}")
        ax.plot(rho, fine_grain_rms_slope(np.column_stack([1 - rho, rho]), [1, r]), ":",
                color=f"C{j}", lw=1.0)
    ax.set_xscale("log")
    ax.set_yscale("log")
    study_io.plain_log_ticks(ax)
    ax.set_xlabel(r"$\rho_2$")
    ax.set_ylabel(r"rms slope / $\nabla f^0_\infty$")
    side = int(round(np.sqrt(table.attrs.get("n_seeds", 0))))
    ax.set_title(f"design table: {side}$^2$ seeds, {table.attrs.get('realisations')} "
                 f"realisations, n = {table.attrs.get('n')};\nband: realisation scatter, "
                 "dotted: fine-grain closed form", fontsize=9)
    ax.legend(fontsize=7)
    study_io.save_figure(fig, png)


def main(argv=None):
    """Run the study from the command line (``--help`` lists the options); exit status."""
    return study_io.run_study(NAME, __doc__, compute, plot, PARAMS, QUICK, argv, parallel=True,
                              committed_output=TABLE, default_sweep=voronoi_study.SWEEP)


if __name__ == "__main__":
    sys.exit(main())
