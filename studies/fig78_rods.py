"""Fig. 7-8: five rods in a cylinder, both ways round: worn faces and differential profiles.

Reproduces the theoretical parts of the paper's Fig. 7 and 8: five rods of
radius 2.5 mm in a cylinder of radius 10 mm, ``F_N = 35 N``, ``E* = 1.3 MPa``,
``k_steel / k_brass = 1.7`` as printed in the paper, steel rods in brass and
brass rods in steel (``steady/examples/rods_steel_in_brass.toml`` and
``rods_brass_in_steel.toml``: one rod on the axis, four with centres 6 mm
from it at 0, 90, 180 and 270 degrees).  For each: the limiting face and the
differential profiles (cross section minus the ring average at the same
radius, :func:`steady.profiles.differential_profile`) of four chords parallel
to x at y = 0, 2, 4 and 6 mm.  The paper's measured profiles are not
reproduced (no data).

Run::

    python studies/fig78_rods.py            # about 10 s
    python studies/fig78_rods.py --quick    # about 1 s
    python studies/fig78_rods.py --plot-only

Writes ``OUT/fig78_rods.h5`` and ``OUT/fig78_rods.png``.
"""

import sys

import numpy as np
import study_io
from matplotlib.patches import Circle

from steady.phases import Rods
from steady.profiles import differential_profile
from steady.scene import load_scene
from steady.solution import solve_scene

NAME = "fig78_rods"
SCENES = {"steel_in_brass": "rods_steel_in_brass.toml",
          "brass_in_steel": "rods_brass_in_steel.toml"}
TITLES = {"steel_in_brass": "steel rods in brass", "brass_in_steel": "brass rods in steel"}
PARAMS = {"n": 512, "chords_y_mm": [0.0, 2.0, 4.0, 6.0], "points": 801}
QUICK = {"n": 48, "chords_y_mm": [0.0, 6.0], "points": 81}


def compute(path, params):
    """Solve both scenes and sample their differential profiles; write HDF5."""
    datasets, attrs = {}, {}
    for key, file in SCENES.items():
        scene = load_scene(study_io.ROOT / "steady" / "examples" / file)
        if not isinstance(scene.geometry, Rods):
            raise ValueError(f"scene {file} is not a rods scene")
        res = solve_scene(scene, n=params["n"])
        a = scene.outline.radius
        r = scene.grid(res.n).radii
        rim = np.mean(res.face[(res.labels >= 0) & (r > a - 1.5 * res.pixel_size)])
        profiles, positions = [], []
        for y_mm in params["chords_y_mm"]:
            y = y_mm * 1e-3
            half = np.sqrt(a * a - y * y)
            s, v = differential_profile(res.face, a, (-half, y), (half, y), params["points"])
            positions.append(s - half)
            profiles.append(v)
        datasets[f"{key}/face"] = (res.face - rim, "m")
        datasets[f"{key}/labels"] = (res.labels.astype(np.int8), "1")
        datasets[f"{key}/x"] = (np.asarray(positions), "m")
        datasets[f"{key}/differential"] = (np.asarray(profiles), "m")
        datasets[f"{key}/phase_pressures"] = (res.phase_pressures, "Pa")
        datasets[f"{key}/wear_coefficients"] = (np.asarray(scene.wear.coefficients), "1/Pa")
        datasets[f"{key}/rod_centres"] = (np.asarray(scene.geometry.centres), "m")
        datasets[f"{key}/rod_radii"] = (np.asarray(scene.geometry.radii), "m")
        # Differential profile at the side rods on the y = 0 chord (rods minus the
        # ring average at 6 mm, where rods hold about half the ring).
        x, dp = positions[0], profiles[0]
        near = np.zeros_like(x, dtype=bool)
        for cx, cy in scene.geometry.centres:
            if abs(cy) < 1e-12 and abs(cx) > 0:
                near |= np.abs(x - cx) < 0.5 * scene.geometry.radii[0]
        attrs[f"{key}_side_rods"] = (float(np.nanmean(dp[near])), "m")
        # solve_scene: energy-corrected value with its error (grids n, n/2, n/4).
        attrs[f"{key}_rms_slope"] = (res.rms_slope, "1")
        attrs[f"{key}_rms_slope_error"] = (res.rms_slope_error, "1")
        attrs[f"{key}_rms_slope_plain"] = (res.rms_slope_plain, "1")
        attrs[f"{key}_reference_slope"] = (res.reference_slope, "1")
    attrs["radius"] = (a, "m")
    return study_io.write_study(path, NAME, params, datasets, attrs)


def plot(path, png):
    """Faces with the chords, and differential profiles, from the HDF5 file."""
    d, a = study_io.read_study(path, NAME)
    p = a["params"]
    r_mm = a["radius"] * 1e3
    fig = study_io.figure(10.0, 7.2)
    axes = fig.subplots(2, 2, width_ratios=[1, 1.5])
    for row, key in enumerate(SCENES):
        ax_face, ax_prof = axes[row]
        face = d[f"{key}/face"] * 1e6
        im = ax_face.imshow(face.T, origin="lower", extent=(-r_mm, r_mm, -r_mm, r_mm),
                            cmap="viridis", interpolation="nearest")
        cb = fig.colorbar(im, ax=ax_face, shrink=0.85)
        cb.set_label(r"$f_\infty$ above the rim (µm)")
        for (cx, cy), rr in zip(d[f"{key}/rod_centres"], d[f"{key}/rod_radii"],
                                strict=True):
            ax_face.add_patch(Circle((cx * 1e3, cy * 1e3), rr * 1e3, fill=False, lw=0.6,
                                     color="w", ls=":"))
        for i, y in enumerate(p["chords_y_mm"]):
            half = np.sqrt(r_mm**2 - y**2)
            ax_face.plot([-half, half], [y, y], color=f"C{i}", lw=1.0)
            ax_prof.plot(d[f"{key}/x"][i] * 1e3, d[f"{key}/differential"][i] * 1e6,
                         color=f"C{i}", lw=1.0, label=f"y = {y:g} mm")
        k = d[f"{key}/wear_coefficients"]
        ax_face.set_title(f"{TITLES[key]}\nk_matrix : k_rod = {k[0] / k.min():.2g} : "
                          f"{k[1] / k.min():.2g}", fontsize=9)
        ax_face.set_xlabel("x (mm)")
        ax_face.set_ylabel("y (mm)")
        ax_prof.axhline(0, color="0.6", lw=0.6)
        ax_prof.set_xlabel("x (mm)")
        ax_prof.set_ylabel("differential profile (µm)")
        ax_prof.set_title(f"{TITLES[key]}: side rods on y = 0 at "
                          f"{a[f'{key}_side_rods'] * 1e6:+.1f} µm from their ring average",
                          fontsize=9)
        ax_prof.legend(fontsize=8, ncol=2)
    study_io.save_figure(fig, png, dpi=75)


def main(argv=None):
    """Run the study from the command line (``--help`` lists the options); exit status."""
    return study_io.run_study(NAME, __doc__, compute, plot, PARAMS, QUICK, argv)


if __name__ == "__main__":
    sys.exit(main())
