"""Fig. 7-8 both ways: the rods with the printed k_steel/k_brass = 1.7 and with its inverse.

The paper prints ``k_steel / k_brass = 1.7`` for its rods (Fig. 7-8) but
describes steel rods that "are less worn and produce visible protrusions"
and brass rods that wear into dimples, which needs ``k_steel < k_brass``.
This study draws both: the two rods scenes
(``steady/examples/rods_steel_in_brass.toml`` and ``rods_brass_in_steel.toml``,
the arrangement of :mod:`fig78_rods`) with the printed ratio and with the
steel and brass coefficients swapped (``k_steel / k_brass = 1/1.7``), side by
side with their differential profiles (cross section minus the ring average,
:func:`steady.profiles.differential_profile`) on the chords ``y = 0`` and
``y = 6 mm``.  For every case: the height of each rod above its ring average
(the sign says protrusion or dimple; the side rods, since the axial rod is its
own ring average), and the energy-corrected rms slope
with its error bar.

Run::

    python studies/rods_both_ways.py            # n = 512, about 5 s
    python studies/rods_both_ways.py --quick    # about 2 s
    python studies/rods_both_ways.py --plot-only

Writes ``OUT/rods_both_ways.h5`` and ``OUT/rods_both_ways.png``.
"""

import dataclasses
import sys

import fig78_rods
import numpy as np
import study_io
from fit_rods import STEEL
from matplotlib.patches import Circle

from steady.outline import as_outline
from steady.profiles import differential_profile, ring_average
from steady.scene import load_scene
from steady.solution import solve_scene

NAME = "rods_both_ways"
#: k_steel / k_brass of the two columns: as printed, and inverted.
RATIOS = {"printed": 1.7, "inverse": 1 / 1.7}
RATIO_LABELS = {"printed": "1.7 (printed)", "inverse": "1/1.7"}
PARAMS = {"n": 512, "chords_y_mm": [0.0, 6.0], "points": 801}
QUICK = {"n": 48, "chords_y_mm": [0.0, 6.0], "points": 81}


def _with_ratio(scene, key, ratio):
    """The scene with ``k_steel / k_brass = ratio`` (brass keeps its coefficient)."""
    k = list(scene.wear.coefficients)
    brass = k[1 - STEEL[key]]
    k[STEEL[key]] = ratio * brass
    return dataclasses.replace(scene, wear=dataclasses.replace(scene.wear, coefficients=tuple(k)))


def _rod_heights(face, geometry, radius):
    """Mean height of each rod's pixels above the ring average at their radius, m."""
    n = face.shape[0]
    grid = as_outline(radius).grid(n)
    r_ring, mean = ring_average(face, radius, n // 2)
    ok = np.isfinite(mean)
    r_px = grid.radii
    relief = face - np.interp(r_px, r_ring[ok], mean[ok])
    x = grid.x
    out = []
    for (cx, cy), rr in zip(geometry.centres, geometry.radii, strict=True):
        inside = ((x[:, None] - cx) ** 2 + (x[None, :] - cy) ** 2 < rr ** 2) & grid.mask
        out.append(float(np.mean(relief[inside])))
    return np.asarray(out)


def compute(path, params):
    """Solve both scenes at both ratios; sample their differential profiles; write HDF5."""
    datasets, attrs = {}, {}
    for key, file in fig78_rods.SCENES.items():
        base = load_scene(study_io.ROOT / "steady" / "examples" / file)
        k = base.wear.coefficients
        if abs(k[STEEL[key]] / k[1 - STEEL[key]] - 1.7) > 1e-12:
            raise ValueError(f"scene {file}: expected k_steel / k_brass = 1.7")
        a = base.outline.radius
        datasets[f"{key}/rod_centres"] = (np.asarray(base.geometry.centres), "m")
        datasets[f"{key}/rod_radii"] = (np.asarray(base.geometry.radii), "m")
        for case, ratio in RATIOS.items():
            scene = _with_ratio(base, key, ratio)
            res = solve_scene(scene, n=params["n"])
            r = scene.grid(res.n).radii
            rim = np.mean(res.face[(res.labels >= 0) & (r > a - 1.5 * res.pixel_size)])
            profiles, positions = [], []
            for y_mm in params["chords_y_mm"]:
                y = y_mm * 1e-3
                half = np.sqrt(a * a - y * y)
                s, v = differential_profile(res.face, a, (-half, y), (half, y),
                                            params["points"])
                positions.append(s - half)
                profiles.append(v)
            g = f"{key}/{case}"
            datasets[f"{g}/face"] = (res.face - rim, "m")
            datasets[f"{g}/x"] = (np.asarray(positions), "m")
            datasets[f"{g}/differential"] = (np.asarray(profiles), "m")
            datasets[f"{g}/phase_pressures"] = (res.phase_pressures, "Pa")
            datasets[f"{g}/wear_coefficients"] = (np.asarray(scene.wear.coefficients), "1/Pa")
            heights = _rod_heights(res.face, scene.geometry, a)
            datasets[f"{g}/rod_heights"] = (heights, "m")
            attrs[f"{key}_{case}_rms_slope"] = (res.rms_slope, "1")
            attrs[f"{key}_{case}_rms_slope_error"] = (res.rms_slope_error, "1")
            attrs[f"{key}_{case}_reference_slope"] = (res.reference_slope, "1")
            attrs[f"{key}_{case}_steel_pressure_over_brass"] = (
                float(res.phase_pressures[STEEL[key]] / res.phase_pressures[1 - STEEL[key]]),
                "1")
            # Sign of the steel relief (+ proud, - recessed) from the four side rods:
            # the axial rod is its own ring average.  Rods of steel: their height;
            # rods of brass: minus their height.
            side = np.hypot(*np.asarray(scene.geometry.centres).T) > 0
            steel_relief = heights[side].mean() * (1 if STEEL[key] == 1 else -1)
            attrs[f"{key}_{case}_steel_relief"] = (float(steel_relief), "m")
    attrs["radius"] = (a, "m")
    return study_io.write_study(path, NAME, params, datasets, attrs)


def plot(path, png):
    """Faces at both ratios and their differential profiles, from the HDF5 file."""
    d, a = study_io.read_study(path, NAME)
    p = a["params"]
    r_mm = a["radius"] * 1e3
    fig = study_io.figure(13.0, 7.4)
    axes = fig.subplots(2, 3, width_ratios=[1, 1, 1.5])
    for row, key in enumerate(fig78_rods.SCENES):
        faces = [d[f"{key}/{case}/face"] * 1e6 for case in RATIOS]
        lo = min(np.nanmin(f) for f in faces)
        hi = max(np.nanmax(f) for f in faces)
        for col, case in enumerate(RATIOS):
            ax = axes[row, col]
            im = ax.imshow(faces[col].T, origin="lower", extent=(-r_mm, r_mm, -r_mm, r_mm),
                           cmap="viridis", interpolation="nearest", vmin=lo, vmax=hi)
            for (cx, cy), rr in zip(d[f"{key}/rod_centres"], d[f"{key}/rod_radii"],
                                    strict=True):
                ax.add_patch(Circle((cx * 1e3, cy * 1e3), rr * 1e3, fill=False, lw=0.6,
                                    color="w", ls=":"))
            for i, y in enumerate(p["chords_y_mm"]):
                half = np.sqrt(r_mm**2 - y**2)
                ax.plot([-half, half], [y, y], color=f"C{i}", lw=1.0)
            relief = a[f"{key}_{case}_steel_relief"] * 1e6
            ax.set_title(f"{fig78_rods.TITLES[key]}, k_steel/k_brass = "
                         f"{RATIO_LABELS[case]}\nsteel {'proud' if relief > 0 else 'recessed'}"
                         f" ({relief:+.1f} µm vs ring average)", fontsize=8.5)
            ax.set_xlabel("x (mm)")
            ax.set_ylabel("y (mm)")
        fig.colorbar(im, ax=axes[row, :2].tolist(), shrink=0.85).set_label(
            r"$f_\infty$ above the rim (µm)")
        ax = axes[row, 2]
        for i, y in enumerate(p["chords_y_mm"]):
            for case, ls in zip(RATIOS, ("-", "--"), strict=True):
                g = f"{key}/{case}"
                ax.plot(d[f"{g}/x"][i] * 1e3, d[f"{g}/differential"][i] * 1e6, color=f"C{i}",
                        ls=ls, lw=1.0, label=f"y = {y:g} mm, {RATIO_LABELS[case]}")
        ax.axhline(0, color="0.6", lw=0.6)
        ax.set_xlabel("x (mm)")
        ax.set_ylabel("differential profile (µm)")
        slopes = ", ".join(
            f"{RATIO_LABELS[c]}: {a[f'{key}_{c}_rms_slope'] / a[f'{key}_{c}_reference_slope']:.4f}"
            for c in RATIOS)
        ax.set_title(f"{fig78_rods.TITLES[key]}: differential profiles\n"
                     f"rms slope / grad_f0: {slopes}", fontsize=8.5)
        lo, hi = ax.get_ylim()
        ax.set_ylim(lo, hi + 0.45 * (hi - lo))  # room for the legend above the curves
        ax.legend(fontsize=7, ncol=2, loc="upper center")
    study_io.save_figure(fig, png, dpi=75)


def main(argv=None):
    """Run the study from the command line (``--help`` lists the options); exit status."""
    return study_io.run_study(NAME, __doc__, compute, plot, PARAMS, QUICK, argv)


if __name__ == "__main__":
    sys.exit(main())
