"""Steady faces beyond the cylinder: a tread block and an annular seal with Fig. 3's microstructure.

The biphasic Voronoi microstructure of the paper's Fig. 3 (seed spacing
0.2 mm, fill factor 0.5, ``k_2 / k_1 = 10``) on three faces of the same
load per area: the paper's disk (radius 4 mm), a rectangular tread block
(4 mm x 12 mm, aspect 1:3) and an annular seal (radii 2.5 and 4 mm).  The
seeds are spread uniformly over each face's bounding box at the same
density, so that the three faces carry the same grain size, and every grid
has the same pixel size (``pixels_per_spacing`` pixels per seed spacing).

Each face's rms slope is normalised by its own reference, the rms slope of
the homogeneous face of the same outline under the same load (the disk's
``4 pbar / (pi E*)``; the rectangle's from Love's closed form; the
annulus's from superposed disks), and compared over several realisations
of the map: does the normalisation carry the microstructure's effect from
one outline to another?

Run::

    python studies/face_outlines.py            # about 10 s
    python studies/face_outlines.py --quick    # a few s
    python studies/face_outlines.py --plot-only

Writes ``OUT/face_outlines.h5`` and ``OUT/face_outlines.png``.
"""

import sys

import numpy as np
import study_io
from matplotlib.colors import ListedColormap

from steady.normalisation import reference_slope
from steady.outline import Annulus, Circle, Rectangle
from steady.phases import Voronoi
from steady.problem import FacePhases, Problem
from steady.rms_slope import estimate_rms_slope
from steady.solution import solve

NAME = "face_outlines"
PARAMS = {"spacing": 2e-4, "pixels_per_spacing": 12.8, "fill_factor": 0.5, "ratio": 10.0,
          "seeds": [2718, 2719, 2720, 2721, 2722], "pbar": 198943.68, "E_star": 1.3e6}
QUICK = {"spacing": 8e-4, "pixels_per_spacing": 6.4, "fill_factor": 0.5, "ratio": 10.0,
         "seeds": [2718, 2719], "pbar": 198943.68, "E_star": 1.3e6}

#: The faces of the study: name, outline, title.
FACES = (
    ("disk", Circle(4e-3), "disk, radius 4 mm"),
    ("tread", Rectangle(4e-3, 12e-3), "tread block, 4 x 12 mm"),
    ("seal", Annulus(2.5e-3, 4e-3), "annular seal, radii 2.5 / 4 mm"),
)


def _set_up(outline, params):
    """Seeds in the bounding box at the density of the spacing, and the grid size."""
    lx, ly = outline.half_extent
    n_seeds = round(4 * lx * ly / params["spacing"] ** 2)
    n = 8 * round(2 * outline.scale / params["spacing"] * params["pixels_per_spacing"] / 8)
    return n_seeds, n


def compute(path, params):
    """Corrected rms slopes of every face and realisation, faces of the first; write HDF5."""
    rho, E_star = params["fill_factor"], params["E_star"]
    k = [1.0e-13, 1.0e-13 * params["ratio"]]
    datasets, attrs = {}, {}
    for name, outline, _ in FACES:
        n_seeds, n = _set_up(outline, params)
        force = params["pbar"] * outline.area
        ref = reference_slope(outline, force, E_star)
        values, errors, plains = [], [], []
        for i, seed in enumerate(params["seeds"]):
            geometry = Voronoi(n_seeds, (1.0 - rho, rho), seed)
            estimate = estimate_rms_slope(geometry, k, force, outline, E_star, n)
            values.append(estimate.rms_slope / ref.value)
            errors.append(estimate.error / ref.value)
            plains.append(estimate.rms_slope_plain / ref.value)
            if i == 0:
                grid = outline.grid(n)
                labels = geometry.labels(grid)
                phases = FacePhases(grid, labels, geometry.n_phases)
                result = solve(Problem(phases, k, force, E_star))
                face = np.where(labels >= 0, result.face - result.face[labels >= 0].mean(),
                                np.nan)
                datasets[f"{name}/labels"] = (labels.astype(np.int8), "1")
                datasets[f"{name}/face"] = (face / (ref.value * outline.scale), "grad_f0 L")
                datasets[f"{name}/half_extent"] = (np.asarray(outline.half_extent), "m")
                attrs[f"{name}_grids"] = (",".join(map(str, estimate.grids)), "1")
                attrs[f"{name}_fill_factor"] = (float(result.fill_factors[1]), "1")
        datasets[f"{name}/rms_slope"] = (np.asarray(values), "grad_f0")
        datasets[f"{name}/rms_slope_error"] = (np.asarray(errors), "grad_f0")
        datasets[f"{name}/rms_slope_plain"] = (np.asarray(plains), "grad_f0")
        attrs[f"{name}_n"] = (n, "1")
        attrs[f"{name}_n_seeds"] = (n_seeds, "1")
        attrs[f"{name}_reference_factor"] = (ref.factor, "pbar / E*")
        attrs[f"{name}_reference_source"] = (ref.source, "1")
        attrs[f"{name}_mean"] = (float(np.mean(values)), "grad_f0")
        attrs[f"{name}_scatter"] = (float(np.std(values, ddof=1)) if len(values) > 1 else 0.0,
                                    "grad_f0")
    return study_io.write_study(path, NAME, params, datasets, attrs)


def plot(path, png):
    """Phase maps above the normalised faces, from the HDF5 file."""
    d, a = study_io.read_study(path, NAME)
    widths = [float(d[f"{name}/half_extent"][0] / d[f"{name}/half_extent"][1])
              for name, _, _ in FACES]
    fig = study_io.figure(10.0, 7.4)
    axes = fig.subplots(2, 3, gridspec_kw={"width_ratios": widths})
    cmap = ListedColormap(["#bdbdbd", "#252525"])
    faces = [np.ma.masked_invalid(d[f"{name}/face"]) for name, _, _ in FACES]
    lo = min(float(f.min()) for f in faces)
    hi = max(float(f.max()) for f in faces)
    for col, ((name, _, title), face) in enumerate(zip(FACES, faces, strict=True)):
        lx, ly = (1e3 * v for v in d[f"{name}/half_extent"])
        extent = (-lx, lx, -ly, ly)
        labels = np.ma.masked_less(d[f"{name}/labels"], 0)
        ax_map, ax_face = axes[0, col], axes[1, col]
        # Arrays are [x, y]; imshow wants [row = y, column = x].
        ax_map.imshow(labels.T, origin="lower", extent=extent, cmap=cmap,
                      interpolation="nearest")
        ax_map.set_title(f"{title}\n{a[name + '_n_seeds']} seeds, "
                         f"$\\rho_2$ = {a[name + '_fill_factor']:.3f}", fontsize=9)
        im = ax_face.imshow(face.T, origin="lower", extent=extent, cmap="viridis",
                            vmin=lo, vmax=hi, interpolation="nearest")
        values = d[f"{name}/rms_slope"]
        ax_face.set_title(
            f"rms slope {values[0]:.3f} $\\pm$ {d[name + '/rms_slope_error'][0]:.3f}\n"
            f"{len(values)} maps: {a[name + '_mean']:.3f} $\\pm$ {a[name + '_scatter']:.3f}\n"
            f"(reference {a[name + '_reference_factor']:.4f} $\\bar p / E^*$)", fontsize=9)
        for ax in (ax_map, ax_face):
            ax.set_xlabel("x (mm)")
        ax_map.set_ylabel("y (mm)")
        ax_face.set_ylabel("y (mm)")
    cb = fig.colorbar(im, ax=axes[1, :].tolist(), shrink=0.85)
    cb.set_label(r"$(f_\infty - \langle f_\infty\rangle) / (\nabla f^0_\infty L)$")
    p = a["params"]
    fig.suptitle(f"Fig. 3 microstructure on three faces: $k_2/k_1$ = {p['ratio']:g}, seed "
                 f"spacing {p['spacing'] * 1e3:g} mm; rms slopes in units of each face's "
                 f"homogeneous reference", fontsize=10)
    study_io.save_figure(fig, png)


def main(argv=None):
    """Run the study from the command line (``--help`` lists the options); exit status."""
    return study_io.run_study(NAME, __doc__, compute, plot, PARAMS, QUICK, argv)


if __name__ == "__main__":
    sys.exit(main())
