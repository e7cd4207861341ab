"""Fig. 3: a biphasic Voronoi map and its limiting worn face for k_2/k_1 = 10.

Reproduces the paper's Fig. 3: (a) a biphasic phase map (Voronoi cells of
random seeds, each labelled phase 1 or phase 2 with fill factor ``rho_2``),
(b) the limiting face (eq. 14) for ``k_2 / k_1 = 10``, in the normalised form
of eq. 15 divided by ``a`` (``f / (grad_f0 a)``), with the energy-corrected rms
slope and its discretisation error (grids ``n, n/2, n/4``).

The map is the one of ``steady/examples/voronoi_biphasic.toml`` (40^2 seeds,
``rho_2 = 0.5``, seed 2718).

Run::

    python studies/fig3_biphasic.py            # about 5 s
    python studies/fig3_biphasic.py --quick    # about 1 s
    python studies/fig3_biphasic.py --plot-only

Writes ``OUT/fig3_biphasic.h5`` and ``OUT/fig3_biphasic.png``.
"""

import sys

import numpy as np
import study_io
from matplotlib.colors import ListedColormap

from steady.basis import PhaseBasis
from steady.outline import UNIT_DISK
from steady.phases import Voronoi
from steady.problem import FacePhases
from steady.rms_slope import grid_ladder, ladder_error

NAME = "fig3_biphasic"
PARAMS = {"n": 512, "n_seeds": 1600, "fill_factor": 0.5, "seed": 2718, "ratio": 10.0}
QUICK = {"n": 64, "n_seeds": 100, "fill_factor": 0.5, "seed": 2718, "ratio": 10.0}


def compute(path, params):
    """Face and corrected rms slope of one biphasic map; write HDF5."""
    rho, n = params["fill_factor"], params["n"]
    geometry = Voronoi(params["n_seeds"], (1.0 - rho, rho), params["seed"])
    k = [1.0, params["ratio"]]
    grids = grid_ladder(geometry, n)
    values = []
    for m in grids:
        grid = UNIT_DISK.grid(m)
        phases = FacePhases(grid, geometry.labels(grid), geometry.n_phases)
        basis = PhaseBasis(phases, 1.0, faces=(m == n))
        s = basis.rms_slopes([k], np.pi)
        values.append(s.normalised[0])
        if m == n:
            face = basis.face(k, np.pi) / s.reference_slope
            labels = basis.labels
            plain = s.rms_slope_plain[0] / s.reference_slope
            fill = basis.fill_factors[1]
            pressures = s.phase_pressures[0]
    return study_io.write_study(path, NAME, params, {
        "labels": (labels.astype(np.int8), "1"),
        "face": (face, "grad_f0 a"),
        "grids": (np.asarray(grids), "1"),
        "rms_slope_ladder": (np.asarray(values), "grad_f0"),
        "phase_pressures": (pressures, "pbar"),
    }, {
        "rms_slope": (values[grids.index(n)], "grad_f0"),
        "rms_slope_error": (float(ladder_error(grids, values)), "grad_f0"),
        "rms_slope_plain": (plain, "grad_f0"),
        "realised_fill_factor": (fill, "1"),
    })


def plot(path, png):
    """Phase map beside the normalised face, from the HDF5 file."""
    d, a = study_io.read_study(path, NAME)
    p = a["params"]
    fig = study_io.figure(9.0, 4.0)
    ax_map, ax_face = fig.subplots(1, 2)
    labels = np.ma.masked_less(d["labels"], 0)
    extent = (-1, 1, -1, 1)
    # Arrays are [x, y]; imshow wants [row = y, column = x].
    ax_map.imshow(labels.T, origin="lower", extent=extent,
                  cmap=ListedColormap(["#bdbdbd", "#252525"]), interpolation="nearest")
    ax_map.set_title(f"(a) phase 1 grey, phase 2 black: {p['n_seeds']} seeds,\n"
                     f"$\\rho_2$ = {a['realised_fill_factor']:.3f} (realised)", fontsize=9)
    im = ax_face.imshow(d["face"].T, origin="lower", extent=extent, cmap="viridis",
                        interpolation="nearest")
    cb = fig.colorbar(im, ax=ax_face, shrink=0.85)
    cb.set_label(r"$f_\infty / (\nabla f^0_\infty a)$")
    ax_face.set_title(f"(b) limiting face, $k_2/k_1$ = {p['ratio']:g}: rms slope\n"
                      f"{a['rms_slope']:.4f} $\\pm$ {a['rms_slope_error']:.4f} "
                      f"$\\nabla f^0_\\infty$ (plain pixel {a['rms_slope_plain']:.4f})",
                      fontsize=9)
    for ax in (ax_map, ax_face):
        ax.set_xlabel("x / a")
        ax.set_ylabel("y / a")
    study_io.save_figure(fig, png)


def main(argv=None):
    """Run the study from the command line (``--help`` lists the options); exit status."""
    return study_io.run_study(NAME, __doc__, compute, plot, PARAMS, QUICK, argv)


if __name__ == "__main__":
    sys.exit(main())
