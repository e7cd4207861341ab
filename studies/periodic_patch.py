"""A periodic patch against the paper's punch: the scale-independence claim without the rim.

The biphasic Voronoi microstructure of the paper's Fig. 3 (fill factor 0.5,
``k_2 / k_1 = 10``, seed spacing ``d = 0.2 mm``) on a periodic cell of side
``m d`` (``m`` grains across, ``m^2`` seeds; the tessellation repeats with the
cell), for growing ``m``, beside the same microstructure on the paper's punch
(a disk of radius 4 mm, 40 grains across) under the same mean pressure.  Rms
slopes in units of the disk's ``grad_f0 = 4 pbar / (pi E*)`` (eq. 12), the
cell's unit too.

The cell's rms slope is Parseval's, exactly (docs/model.md, "The periodic
cell"): ``2 std(p) / E*``, i.e. ``sqrt(pi^2 / 4 sum_i rho_i (p_i / pbar - 1)^2)
grad_f0`` at the realised fill factors -- the fluctuation part of the
fine-grain closed form (:func:`steady.reference.fine_grain_rms_slope`), whose
remaining 1 is the homogeneous punch's rim.  The study measures how the
patch's value and its scatter between realisations depend on its size.

Further cases enter through :func:`patch_estimate`, which takes the cell's
problem as every solve does (:func:`steady.scene.problem_of` of a scene, or a
:class:`steady.problem.Problem`): its operator is the problem's.  One is
built in: a road's aggregate under a tyre -- the same microstructure with
grains of 10 mm on a patch of 8 x 8 grains, ``pbar / E* = 0.08``, on the
half-space and on a tread of 8 mm (incompressible) on a rigid belt.

Run::

    python studies/periodic_patch.py            # about 20 s
    python studies/periodic_patch.py --quick    # a few s
    python studies/periodic_patch.py --plot-only

Writes ``OUT/periodic_patch.h5`` and ``OUT/periodic_patch.png``.
"""

import math
import sys
import time

import numpy as np
import study_io
from matplotlib.colors import ListedColormap

from steady.outline import Circle, PeriodicCell
from steady.phases import Voronoi
from steady.problem import FacePhases, Problem
from steady.reference import fine_grain_rms_slope
from steady.solution import solve

NAME = "periodic_patch"
PARAMS = {"spacing": 2e-4, "pixels_per_spacing": 8, "fill_factor": 0.5, "ratio": 10.0,
          "grains": [2, 4, 8, 16, 32, 64], "seeds": [4101, 4102, 4103, 4104, 4105, 4106],
          "punch_radius": 4e-3, "pbar": 198943.68, "E_star": 1.3e6, "shown": 16,
          "road_spacing": 1e-2, "road_grains": 8, "road_pbar_over_E_star": 0.08, "tread": 8e-3}
QUICK = {"spacing": 8e-4, "pixels_per_spacing": 8, "fill_factor": 0.5, "ratio": 10.0,
         "grains": [2, 4, 8], "seeds": [4101, 4102], "punch_radius": 4e-3,
         "pbar": 198943.68, "E_star": 1.3e6, "shown": 4,
         "road_spacing": 1e-2, "road_grains": 4, "road_pbar_over_E_star": 0.08, "tread": 8e-3}


def patch_estimate(problem, geometry):
    """The corrected rms slope of a problem's steady face and its error bar, Pa / Pa.

    The hook of every case of the study: the problem carries the face, the
    load, the wear law and the counter-body (its operator: on a layer the
    cell's slope integrals are the layer's), the geometry the map's ladder.

    Parameters
    ----------
    problem : steady.problem.Problem
    geometry : phase geometry
        The map of ``problem`` (rasterised again on the ladder's grids).

    Returns
    -------
    tuple of float
        ``(rms_slope, rms_slope_error)``, dimensionless.
    """
    result = solve(problem, geometry=geometry)
    return result.rms_slope, result.rms_slope_error


def _problem(outline, geometry, n, params, *, pbar=None, thickness=None, poisson=None):
    grid = outline.grid(n)
    k = [1.0e-13, 1.0e-13 * params["ratio"]]
    phases = FacePhases(grid, geometry.labels(grid), geometry.n_phases)
    force = (params["pbar"] if pbar is None else pbar) * outline.area
    return Problem(phases, k, force, params["E_star"], thickness=thickness, poisson=poisson)


def _cases(outline, n_seeds, n, params):
    """Normalised rms slope, error and realised fill factor of each realisation."""
    rho = params["fill_factor"]
    unit = 4.0 * params["pbar"] / (math.pi * params["E_star"])
    out = []
    for seed in params["seeds"]:
        geometry = Voronoi(n_seeds, (1.0 - rho, rho), seed)
        problem = _problem(outline, geometry, n, params)
        rms_slope, error = patch_estimate(problem, geometry)
        fill = float(problem.phases.counts[1] / problem.phases.counts.sum())
        out.append((rms_slope / unit, error / unit, fill))
    return np.array(out)


def _road(params):
    """A road's aggregate under a tyre: the patch on the half-space and on the tread.

    ``(seeds, 2, 2)``: rms slope and error bar over ``grad_f0`` of each map, on the
    half-space and on the tread (a layer of ``tread`` m, incompressible, on a rigid belt).
    """
    d, m = params["road_spacing"], params["road_grains"]
    pbar = params["road_pbar_over_E_star"] * params["E_star"]
    unit = 4.0 * pbar / (math.pi * params["E_star"])
    rho = params["fill_factor"]
    out = []
    for seed in params["seeds"]:
        geometry = Voronoi(m * m, (1.0 - rho, rho), seed)
        row = []
        for thickness, poisson in ((None, None), (params["tread"], 0.5)):
            problem = _problem(PeriodicCell(m * d, m * d), geometry,
                               m * params["pixels_per_spacing"], params, pbar=pbar,
                               thickness=thickness, poisson=poisson)
            rms_slope, error = patch_estimate(problem, geometry)
            row.append((rms_slope / unit, error / unit))
        out.append(row)
    return np.array(out)


def compute(path, params):
    """Patches of every size and the punch, each over the realisations; write HDF5."""
    start = time.perf_counter()
    rho, d, per = params["fill_factor"], params["spacing"], params["pixels_per_spacing"]
    k_ratio = [1.0, params["ratio"]]
    datasets, attrs = {}, {}
    rows = []
    for m in params["grains"]:
        rows.append(_cases(PeriodicCell(m * d, m * d), m * m, m * per, params))
    rows = np.array(rows)  # (sizes, seeds, 3)
    datasets["grains"] = (np.asarray(params["grains"]), "1")
    datasets["patch/rms_slope"] = (rows[..., 0], "grad_f0")
    datasets["patch/rms_slope_error"] = (rows[..., 1], "grad_f0")
    datasets["patch/fill_factor"] = (rows[..., 2], "1")
    # The closed form at each realised fill factor: the fine-grain form without its 1.
    fills = rows[..., 2]
    full = fine_grain_rms_slope(np.stack([1 - fills, fills], axis=-1), k_ratio)
    datasets["patch/closed_form"] = (np.sqrt(full**2 - 1.0), "grad_f0")
    radius = params["punch_radius"]
    across = round(2 * radius / d)
    punch = _cases(Circle(radius), across * across, across * per, params)
    datasets["punch/rms_slope"] = (punch[:, 0], "grad_f0")
    datasets["punch/rms_slope_error"] = (punch[:, 1], "grad_f0")
    datasets["punch/fill_factor"] = (punch[:, 2], "1")
    nominal = float(fine_grain_rms_slope([1 - rho, rho], k_ratio))
    attrs["fine_grain_punch"] = (nominal, "grad_f0")
    attrs["fine_grain_patch"] = (math.sqrt(nominal**2 - 1.0), "grad_f0")
    attrs["punch_grains"] = (across, "1")
    road = _road(params)
    datasets["road/rms_slope"] = (road[..., 0], "grad_f0")
    datasets["road/rms_slope_error"] = (road[..., 1], "grad_f0")
    # One patch's map and face for the figure.
    m = params["shown"]
    geometry = Voronoi(m * m, (1.0 - rho, rho), params["seeds"][0])
    result = solve(_problem(PeriodicCell(m * d, m * d), geometry, m * per, params),
                   face_only=True)
    unit = 4.0 * params["pbar"] / (math.pi * params["E_star"])
    datasets["shown/labels"] = (result.labels.astype(np.int8), "1")
    datasets["shown/face"] = (result.face / (unit * d), "grad_f0 d")
    attrs["run_time"] = (time.perf_counter() - start, "s")
    return study_io.write_study(path, NAME, params, datasets, attrs)


def plot(path, png):
    """Rms slope against the patch side, beside the punch; one patch's map and face."""
    d, a = study_io.read_study(path, NAME)
    p = a["params"]
    fig = study_io.figure(10.0, 4.6)
    ax, ax_map, ax_face = fig.subplots(1, 3, gridspec_kw={"width_ratios": [1.6, 1, 1.25]})
    grains = d["grains"]
    values = d["patch/rms_slope"]
    mean, scatter = values.mean(axis=1), values.std(axis=1, ddof=1)
    ax.errorbar(grains, mean, yerr=scatter, fmt="o-", color="C0", capsize=3,
                label="periodic patch (mean $\\pm$ scatter)")
    ax.plot(grains, d["patch/closed_form"].mean(axis=1), "x", color="C0", ms=8,
            label="$2\\,\\mathrm{std}(p)/E^*$ at the realised fill")
    ax.axhline(a["fine_grain_patch"], color="C0", ls=":", lw=1,
               label="fine-grain form without the rim")
    punch = d["punch/rms_slope"]
    pm, ps = punch.mean(), punch.std(ddof=1)
    ax.axhspan(pm - ps, pm + ps, color="C1", alpha=0.25)
    ax.axhline(pm, color="C1", label=f"punch, {a['punch_grains']} grains across")
    ax.axhline(a["fine_grain_punch"], color="C1", ls=":", lw=1, label="fine-grain form (punch)")
    road = d["road/rms_slope"].mean(axis=0)
    ax.plot([p["road_grains"]] * 2, road, "s", color="C2", mfc="none")
    ax.annotate(f"road, {p['road_spacing'] * 1e3:g} mm grains: half-space",
                (p["road_grains"], road[0]), xytext=(6, 4), textcoords="offset points",
                fontsize=7, color="C2")
    ax.annotate(f"on a {p['tread'] * 1e3:g} mm tread", (p["road_grains"], road[1]),
                xytext=(6, -4), textcoords="offset points", fontsize=7, color="C2")
    ax.set_xscale("log", base=2)
    ax.set_xlabel("patch side (grains)")
    ax.set_ylabel(r"rms slope / $\nabla f^0_\infty$")
    ax.set_title(f"$\\rho_2$ = {p['fill_factor']:g}, $k_2/k_1$ = {p['ratio']:g}, "
                 f"{len(p['seeds'])} maps each", fontsize=9)
    ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.62, -0.2), ncol=2)
    labels = np.ma.masked_less(d["shown/labels"], 0)
    side = p["shown"]
    extent = (0, side, 0, side)
    ax_map.imshow(labels.T, origin="lower", extent=extent, interpolation="nearest",
                  cmap=ListedColormap(["#bdbdbd", "#252525"]))
    ax_map.set_title(f"patch of {side} x {side} grains", fontsize=9)
    face = d["shown/face"]
    image = ax_face.imshow((face - np.nanmean(face)).T, origin="lower", extent=extent,
                           cmap="viridis", interpolation="nearest")
    ax_face.set_title("its steady face (mean removed)", fontsize=9)
    fig.colorbar(image, ax=ax_face, shrink=0.85).set_label(r"$f_\infty / (\nabla f^0_\infty d)$")
    for axis in (ax_map, ax_face):
        axis.set_xlabel("x (grains)")
        axis.set_ylabel("y (grains)")
    study_io.save_figure(fig, png)


def main(argv=None):
    """Run the study from the command line (``--help`` lists the options); exit status."""
    return study_io.run_study(NAME, __doc__, compute, plot, PARAMS, QUICK, argv)


if __name__ == "__main__":
    sys.exit(main())
