"""Fig. 6b: cross sections of the worn epoxy cylinder, theory in physical units.

Reproduces the theoretical curve of the paper's Fig. 6b: the homogeneous epoxy
cylinder of ``steady/examples/epoxy_cylinder.toml`` (``a = 4 mm``,
``F_N = 10 N``, ``E* = 1.3 MPa``), its limiting face from the steady solver
sampled along four diameters (0, 45, 90 and 135 degrees), against eq. 10.
Heights are given relative to the rim (``f_inf(r) - f_inf(a)``), in
micrometres, against the position along the section in mm.  The paper's
measured profiles are not reproduced (no data).

Run::

    python studies/fig6_epoxy.py            # about 5 s
    python studies/fig6_epoxy.py --quick    # about 1 s
    python studies/fig6_epoxy.py --plot-only

Writes ``OUT/fig6_epoxy.h5`` and ``OUT/fig6_epoxy.png``.
"""

import sys

import numpy as np
import study_io

from steady import reference
from steady.profiles import cross_section
from steady.scene import load_scene
from steady.solution import solve_scene

NAME = "fig6_epoxy"
SCENE = study_io.ROOT / "steady" / "examples" / "epoxy_cylinder.toml"
PARAMS = {"n": 512, "angles_deg": [0.0, 45.0, 90.0, 135.0], "points": 401}
QUICK = {"n": 64, "angles_deg": [0.0, 90.0], "points": 41}


def compute(path, params):
    """Solve the scene and sample its cross sections; write HDF5."""
    scene = load_scene(SCENE)
    res = solve_scene(scene, n=params["n"])
    a = scene.outline.radius
    pbar = reference.disk_mean_pressure(scene.normal_force, a)
    rim = float(reference.disk_face(a, a, pbar, scene.E_star))
    sections = []
    for deg in params["angles_deg"]:
        t = np.radians(deg)
        d = a * np.array([np.cos(t), np.sin(t)])
        s, f = cross_section(res.face, a, -d, d, params["points"])
        sections.append(f - rim)
    s = s - a  # position along the section, from -a to a
    exact = reference.disk_face(np.abs(s), a, pbar, scene.E_star) - rim
    sections = np.asarray(sections)
    dev = np.nanmax(np.abs(sections - exact[None]))
    # The face's slope is log-singular at the rim, where the last pixel
    # centre sits h/2 inside: most of the deviation is there.
    inner = np.abs(s) <= 0.9 * a
    dev_inner = np.nanmax(np.abs(sections[:, inner] - exact[None, inner]))
    return study_io.write_study(path, NAME, params, {
        "position": (s, "m"),
        "height": (sections, "m"),
        "eq10_height": (exact, "m"),
    }, {
        "radius": (a, "m"), "normal_force": (scene.normal_force, "N"),
        "E_star": (scene.E_star, "Pa"), "n": (params["n"], "1"),
        "max_deviation": (float(dev), "m"),
        "max_deviation_inner": (float(dev_inner), "m"),
        "centre_height": (float(exact[len(exact) // 2]), "m"),
        "rms_slope": (res.rms_slope, "1"),
        "reference_slope": (res.reference_slope, "1"),
    })


def plot(path, png):
    """Cross sections and eq. 10 in mm / micrometres, from the HDF5 file."""
    d, a = study_io.read_study(path, NAME)
    fig = study_io.figure(6.0, 3.6)
    ax = fig.subplots()
    x = d["position"] * 1e3
    for deg, h in zip(a["params"]["angles_deg"], d["height"], strict=True):
        ax.plot(x, h * 1e6, lw=1.0, label=f"solver, section at {deg:g} deg")
    ax.plot(x, d["eq10_height"] * 1e6, "k--", lw=1.0, label="eq. 10")
    ax.set_xlabel("position along the section (mm)")
    ax.set_ylabel(r"$f_\infty - f_\infty(a)$ (µm)")
    ax.set_title(f"epoxy cylinder: a = {a['radius'] * 1e3:g} mm, F = {a['normal_force']:g} N, "
                 f"E* = {a['E_star'] / 1e6:g} MPa\ncentre {a['centre_height'] * 1e6:.0f} µm "
                 f"above the rim; solver - eq. 10: max {a['max_deviation'] * 1e6:.2f} µm "
                 f"({a['max_deviation_inner'] * 1e6:.2f} µm within r < 0.9 a)",
                 fontsize=9)
    ax.legend(fontsize=8)
    study_io.save_figure(fig, png)


def main(argv=None):
    """Run the study from the command line (``--help`` lists the options); exit status."""
    return study_io.run_study(NAME, __doc__, compute, plot, PARAMS, QUICK, argv)


if __name__ == "__main__":
    sys.exit(main())
