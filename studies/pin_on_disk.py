"""Pin on disk: how the steady face depends on the track radius, and when translation holds.

The paper assumes that the whole face slides at one speed.  A pin on a disk
slides at ``v = omega |x - x_axis|``, faster on its outer side; the steady
pressure is then ``p = (C v_ref / (k_i v))^(1/m)`` (docs/model.md, "Sliding
kinematics") and the face tilts.  For the paper's Voronoi face
(``steady/examples/voronoi_biphasic.toml``: 40^2 seeds, ``rho_2 = 0.5``,
``k_2 / k_1 = 10``) and the homogeneous disk, against ``R / a`` (``R`` the
track radius, ``a`` the face's radius):

- the energy-corrected steady rms slope over the translation's, with the
  error bars of both (grids ``n, n/2, n/4``);
- the face's tilt: the change, from the translation's face, of the slope
  along x of the least-squares plane through the face, in units of
  ``grad_f0 = 4 pbar / (pi E*)``;

and the smallest ``R / a`` beyond which the translation's rms slope is good
to 1 %, and beyond which the tilt stays below 1 % of ``grad_f0``
(log-linear interpolation between the radii computed).

Run::

    python studies/pin_on_disk.py            # about 11 s
    python studies/pin_on_disk.py --quick    # about 3 s
    python studies/pin_on_disk.py --plot-only

Writes ``OUT/pin_on_disk.h5`` and ``OUT/pin_on_disk.png``.
"""

import sys

import numpy as np
import study_io
from matplotlib.ticker import LogFormatterSciNotation, LogLocator

from steady.outline import Circle
from steady.phases import Homogeneous, Voronoi
from steady.problem import FacePhases, Problem
from steady.sliding import PinOnDisk
from steady.solution import solve
from steady.wear import PowerLaw

NAME = "pin_on_disk"
PARAMS = {"n": 256, "n_seeds": 1600, "fill_factor": 0.5, "seed": 2718, "ratio": 10.0,
          "radius": 4e-3, "normal_force": 10.0, "E_star": 1.3e6, "k": 1e-13,
          "track_ratios": [1.1, 1.25, 1.5, 2.0, 3.0, 5.0, 10.0, 20.0, 50.0, 100.0, 1000.0]}
QUICK = dict(PARAMS, n=64, n_seeds=100, track_ratios=[1.5, 5.0, 50.0])

#: The accuracy asked of the translation.
WITHIN = 0.01


def _tilt(face, grid, reference):
    """Slope along x of the least-squares plane through the face, in units of ``reference``."""
    mask = grid.mask
    X, Y = np.meshgrid(grid.x, grid.y, indexing="ij")
    design = np.column_stack([np.ones(mask.sum()), X[mask], Y[mask]])
    coefficients, *_ = np.linalg.lstsq(design, face[mask], rcond=None)
    return float(coefficients[1] / reference)


def _threshold(ratios, values, within):
    """The smallest ratio beyond which ``|values| <= within`` (log-linear), or NaN."""
    ratios, values = np.asarray(ratios), np.abs(np.asarray(values))
    bad = np.flatnonzero(values > within)
    if bad.size == 0:
        return float(ratios[0]) if values[0] <= within else float("nan")
    i = bad[-1]
    if i + 1 >= ratios.size:
        return float("nan")
    lo, hi = np.log(ratios[i]), np.log(ratios[i + 1])
    t = (np.log(values[i]) - np.log(within)) / (np.log(values[i]) - np.log(values[i + 1]))
    return float(np.exp(lo + t * (hi - lo)))


def _curve(geometry, wear, params):
    """Rms slope (with error), its ratio to the translation's and the tilt, per track radius."""
    a = params["radius"]
    grid = Circle(a).grid(params["n"])
    phases = FacePhases(grid, geometry.labels(grid), geometry.n_phases)
    base = Problem(phases, wear, params["normal_force"], params["E_star"])
    flat = solve(base, geometry=geometry)
    # A random map's face has a tilt of its own: the kinematics' is the change.
    flat_tilt = _tilt(flat.face, grid, flat.reference_slope)
    slopes, errors, tilts = [], [], []
    for ratio in params["track_ratios"]:
        tilted = Problem(phases, wear, params["normal_force"], params["E_star"],
                         PinOnDisk(ratio * a))
        result = solve(tilted, geometry=geometry)
        slopes.append(result.rms_slope / result.reference_slope)
        errors.append(result.rms_slope_error / result.reference_slope)
        tilts.append(_tilt(result.face, grid, result.reference_slope) - flat_tilt)
    return {"rms_slope": (np.array(slopes), "grad_f0"),
            "rms_slope_error": (np.array(errors), "grad_f0"),
            "translation_rms_slope": (np.array(flat.rms_slope / flat.reference_slope),
                                      "grad_f0"),
            "translation_rms_slope_error": (np.array(flat.rms_slope_error
                                                     / flat.reference_slope), "grad_f0"),
            "tilt": (np.array(tilts), "grad_f0")}


def compute(path, params):
    """Both faces at every track radius; write HDF5."""
    rho, k = params["fill_factor"], params["k"]
    cases = {"voronoi": (Voronoi(params["n_seeds"], (1.0 - rho, rho), params["seed"]),
                         PowerLaw([k, params["ratio"] * k])),
             "homogeneous": (Homogeneous(), PowerLaw([k]))}
    datasets = {"track_ratio": (np.asarray(params["track_ratios"]), "1")}
    attrs = {}
    for name, (geometry, wear) in cases.items():
        curve = _curve(geometry, wear, params)
        datasets.update({f"{name}/{key}": value for key, value in curve.items()})
        gap = curve["rms_slope"][0] / curve["translation_rms_slope"][0] - 1.0
        attrs[f"{name}_rms_slope_within_1pc"] = (_threshold(params["track_ratios"], gap,
                                                            WITHIN), "R / a")
        attrs[f"{name}_tilt_within_1pc"] = (_threshold(params["track_ratios"],
                                                       curve["tilt"][0], WITHIN), "R / a")
    return study_io.write_study(path, NAME, params, datasets, attrs)


def plot(path, png):
    """Rms slope ratio and tilt against R / a, from the HDF5 file."""
    d, a = study_io.read_study(path, NAME)
    p = a["params"]
    ratio = d["track_ratio"]
    fig = study_io.figure(9.0, 3.8)
    ax_s, ax_t = fig.subplots(1, 2)
    for name, colour in (("voronoi", "C0"), ("homogeneous", "C1")):
        s0 = float(d[f"{name}/translation_rms_slope"])
        e0 = float(d[f"{name}/translation_rms_slope_error"])
        rel = np.abs(d[f"{name}/rms_slope"] / s0 - 1.0)
        bar = (d[f"{name}/rms_slope_error"] + e0) / s0
        label = (f"Voronoi, $k_2/k_1$ = {p['ratio']:g}" if name == "voronoi"
                 else "homogeneous")
        ax_s.loglog(ratio, rel, "o-", color=colour,
                    label=f"{label}: 1 % beyond R/a = "
                          f"{a[f'{name}_rms_slope_within_1pc']:.3g}")
        ax_s.loglog(ratio, bar, ":", color=colour, lw=1)
        ax_t.loglog(ratio, np.abs(d[f"{name}/tilt"]), "o-", color=colour,
                    label=f"{label}: 1 % beyond R/a = {a[f'{name}_tilt_within_1pc']:.3g}")
    for ax in (ax_s, ax_t):
        ax.axhline(WITHIN, color="0.5", lw=0.8, ls="--")
        ax.set_xlabel("track radius / face radius, R / a")
        ax.legend(fontsize=7)
        study_io.plain_log_ticks(ax)
    # Seven decades: powers of ten only.
    ax_s.yaxis.set_major_locator(LogLocator())
    ax_s.yaxis.set_major_formatter(LogFormatterSciNotation())
    ax_s.set_ylabel("|rms slope / translation's - 1|")
    ax_s.set_title("(a) steady rms slope (dotted: the two error bars summed;\n"
                   "their errors are largely common to both)", fontsize=9)
    ax_t.set_ylabel(r"|tilt - translation's| / $\nabla f^0_\infty$")
    ax_t.set_title(f"(b) tilt of the steady face along x, n = {p['n']}", fontsize=9)
    study_io.save_figure(fig, png)


def main(argv=None):
    """Run the study from the command line (``--help`` lists the options); exit status."""
    return study_io.run_study(NAME, __doc__, compute, plot, PARAMS, QUICK, argv)


if __name__ == "__main__":
    sys.exit(main())
