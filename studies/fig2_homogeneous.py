"""Fig. 2: limiting worn face of a homogeneous cylinder against eq. 10, and its rms slope.

Reproduces the paper's Fig. 2 (dimensionless face ``f_bar = f pi E* / (4 pbar a)``
against ``r_bar = r / a``) from the steady solver on an ``n x n`` grid, with the
closed form ``f_bar = E(r_bar)`` (eq. 10), and checks eq. 12: the rms slope of
the face under grid refinement, plain pixel value and energy-corrected value
(:mod:`steady.rms_slope`), against the continuum value
(:func:`steady.reference.disk_normalised_rms_slope`, 1 to quadrature accuracy) and the
paper's 1.0109.

Run::

    python studies/fig2_homogeneous.py            # about 20 s
    python studies/fig2_homogeneous.py --quick    # about 1 s
    python studies/fig2_homogeneous.py --plot-only

Writes ``OUT/fig2_homogeneous.h5`` and ``OUT/fig2_homogeneous.png``.
"""

import sys

import numpy as np
import study_io

from steady import reference
from steady.basis import PhaseBasis
from steady.outline import UNIT_DISK
from steady.phases import Homogeneous
from steady.problem import FacePhases

NAME = "fig2_homogeneous"
PARAMS = {"n": 512, "refinement": [32, 64, 128, 256, 512, 1024]}
QUICK = {"n": 64, "refinement": [32, 64]}


def compute(path, params):
    """Solve the homogeneous face and the rms slope ladder; write HDF5."""
    n = params["n"]
    grid = UNIT_DISK.grid(n)
    labels = Homogeneous().labels(grid)
    basis = PhaseBasis(FacePhases(grid, labels, 1), 1.0)
    force = np.pi  # pbar = 1 Pa on a unit disk, E* = 1 Pa: grad_f0 = 4 / pi
    g0 = 4.0 / np.pi
    face = basis.face([1.0], force) / g0  # f / (grad_f0 a) = f pi E* / (4 pbar a)
    r = grid.radii
    on = labels >= 0
    exact = reference.disk_face(r, 1.0, 1.0, 1.0) / g0
    corrected, plain = [], []
    for m in params["refinement"]:
        if m == n:
            b = basis
        else:
            g = UNIT_DISK.grid(m)
            b = PhaseBasis(FacePhases(g, Homogeneous().labels(g), 1), 1.0, faces=False)
        s = b.rms_slopes([[1.0]], force)
        corrected.append(s.normalised[0])
        plain.append(s.rms_slope_plain[0] / s.reference_slope)
    error = np.abs(face[on] - exact[on])
    return study_io.write_study(path, NAME, params, {
        "r_bar": (r[on], "1"),
        "f_bar": (face[on], "1"),
        "grids": (np.asarray(params["refinement"]), "1"),
        "rms_slope": (np.asarray(corrected), "grad_f0"),
        "rms_slope_plain": (np.asarray(plain), "grad_f0"),
    }, {
        "n": (n, "1"),
        "max_face_error": (float(error.max()), "1"),
        "rms_face_error": (float(np.sqrt(np.mean(error**2))), "1"),
        "continuum_rms_slope": (reference.disk_normalised_rms_slope(), "grad_f0"),
        "paper_rms_slope": (1.0109, "grad_f0"),
    })


def plot(path, png):
    """Face against eq. 10 and rms slope against the grid, from the HDF5 file."""
    d, a = study_io.read_study(path, NAME)
    fig = study_io.figure(9.0, 3.6)
    ax, ax2 = fig.subplots(1, 2)
    rb = np.linspace(0, 1, 400)
    # Every 7th pixel is plenty to show the scatter about the curve.
    ax.plot(d["r_bar"][::7], d["f_bar"][::7], ".", ms=1.5, color="0.55",
            label=f"solver, pixels (n = {a['n']})")
    ax.plot(rb, reference.disk_face(rb, 1.0, 1.0, 1.0) * np.pi / 4, "C0", lw=1.5,
            label=r"eq. 10: $E(\bar r)$")
    ax.set_xlabel(r"$\bar r = r / a$")
    ax.set_ylabel(r"$\bar f_\infty = f_\infty \pi E^* / (4 \bar p a)$")
    ax.set_title(f"face: max |error| {a['max_face_error']:.1e}")
    ax.legend(fontsize=8)
    g = d["grids"]
    ax2.semilogx(g, d["rms_slope_plain"], "s-", color="C3", ms=4, label="plain pixel rms")
    ax2.semilogx(g, d["rms_slope"], "o-", color="C0", ms=4, label="energy-corrected")
    ax2.axhline(a["continuum_rms_slope"], color="k", lw=0.8,
                label=f"continuum {a['continuum_rms_slope']:.6f}")
    ax2.axhline(a["paper_rms_slope"], color="C1", ls="--", lw=0.8, label="paper 1.0109")
    ax2.set_xticks(g, [str(int(x)) for x in g])
    ax2.set_xlabel("grid n")
    ax2.set_ylabel(r"rms slope / $\nabla f^0_\infty$")
    ax2.set_title("eq. 12 under refinement")
    ax2.legend(fontsize=8)
    study_io.save_figure(fig, png)


def main(argv=None):
    """Run the study from the command line (``--help`` lists the options); exit status."""
    return study_io.run_study(NAME, __doc__, compute, plot, PARAMS, QUICK, argv)


if __name__ == "__main__":
    sys.exit(main())
