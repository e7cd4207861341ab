"""Wear ratios from a worn face: the rods of Fig. 7-8 tell k_steel/k_brass = 1.7 from 1/1.7.

A synthetic measured face is made with the project's own forward model
(eq. 7, 9) for each rods scene (``steady/examples/rods_steel_in_brass.toml``
and ``rods_brass_in_steel.toml``) and each of the two wear ratios
``k_steel / k_brass = 1.7`` (as printed in the paper) and ``1/1.7``, plus a
tilt, an offset and noise correlated over 2 pixels (0.2 mm), at levels from
1 % to 300 % of the face's relief.  :func:`steady.fit.fit_scene` then fits
the ratio with its 95 % interval.  Also measured: the coverage of the
intervals at 10 % noise over many noise realisations, and the bias that the
model's discretisation adds when the measured face is the continuum (a face
on a 4x finer grid, averaged over the measured pixels) rather than the
model's own grid.

Run::

    python studies/fit_rods.py            # about 2 min
    python studies/fit_rods.py --quick    # about 5 s
    python studies/fit_rods.py --plot-only

Writes ``OUT/fit_rods.h5`` and ``OUT/fit_rods.png``.
"""

import sys

import numpy as np
import study_io
from scipy import ndimage

from steady import Circle, FaceModel, FacePhases, MeasuredFace, Problem, load_scene, solve

NAME = "fit_rods"
SCENES = {"steel_in_brass": "rods_steel_in_brass.toml",
          "brass_in_steel": "rods_brass_in_steel.toml"}
TITLES = {"steel_in_brass": "steel rods in brass", "brass_in_steel": "brass rods in steel"}
#: Phase index of steel in each scene (the other phase is brass).
STEEL = {"steel_in_brass": 1, "brass_in_steel": 0}
#: k_steel / k_brass of the synthetic faces: the printed value and its inverse.
TRUTHS = {"1.7": 1.7, "1/1.7": 1 / 1.7}
PARAMS = {"n": 200, "levels": [0.01, 0.03, 0.1, 0.3, 1.0, 3.0], "correlation_px": 2.0,
          "offset": 2e-5, "tilt": [1e-3, -5e-4], "seed": 3119, "coverage_level": 0.1,
          "coverage_trials": 40, "fine": 4, "model_grids": [100, 200, 400]}
QUICK = {"n": 48, "levels": [0.01, 0.1, 1.0], "correlation_px": 2.0, "offset": 2e-5,
         "tilt": [1e-3, -5e-4], "seed": 3119, "coverage_level": 0.1, "coverage_trials": 3,
         "fine": 2, "model_grids": [48]}


def _noise(rng, n, correlation):
    """Unit-variance noise, Gaussian-filtered over ``correlation`` pixels."""
    pad = int(4 * correlation) + 1
    w = ndimage.gaussian_filter(rng.standard_normal((n + 2 * pad, n + 2 * pad)), correlation)
    return w[pad:pad + n, pad:pad + n] / w.std()


def _truth(scene, key, ratio, n):
    """Steady face (m) for k_steel / k_brass = ``ratio`` on the n x n grid, and its relief."""
    k = np.full(2, 1e-13)
    k[STEEL[key]] = ratio * 1e-13
    grid = scene.grid(n)
    phases = FacePhases(grid, scene.phase_labels(grid), scene.n_phases)
    face = solve(Problem(phases, k, scene.normal_force, scene.E_star)).face
    return face, float(np.nanmax(face) - np.nanmin(face))


def _plane(n, radius, offset, tilt):
    x = (np.arange(n) - 0.5 * (n - 1)) * Circle(radius).grid(n).h
    return offset + tilt[0] * x[:, None] + tilt[1] * x[None, :]


def _steel_over_brass(fit, key):
    """Fitted k_steel / k_brass and its interval (the fit refers to the brass phase)."""
    s = STEEL[key]
    return fit.ratios[s], fit.ratio_intervals[s]


def compute(path, params):
    """Fit synthetic faces of both scenes and both ratios at every noise level; write HDF5."""
    n, levels = params["n"], params["levels"]
    rng = np.random.default_rng(params["seed"])
    datasets, attrs = {}, {}
    coverage_hits, coverage_total = 0, 0
    separated = {}
    for key, file in SCENES.items():
        scene = load_scene(study_io.ROOT / "steady" / "examples" / file)
        k = scene.wear.coefficients
        ratio_printed = max(k) / min(k)
        if abs(k[STEEL[key]] / k[1 - STEEL[key]] - 1.7) > 1e-12 or abs(ratio_printed - 1.7) > 1e-12:
            raise ValueError(f"scene {file}: expected k_steel / k_brass = 1.7")
        model = FaceModel.from_scene(scene, n=n)
        brass = 1 - STEEL[key]
        plane = _plane(n, scene.outline.radius, params["offset"], params["tilt"])
        h = scene.grid(n).h
        for label, ratio in TRUTHS.items():
            face, relief = _truth(scene, key, ratio, n)
            fitted, lower, upper = [], [], []
            noise = _noise(rng, n, params["correlation_px"])
            for level in levels:
                fit = model.fit(MeasuredFace(face + plane + level * relief * noise, h),
                                reference_phase=brass)
                r, (lo, hi) = _steel_over_brass(fit, key)
                fitted.append(r)
                lower.append(lo)
                upper.append(hi)
                if level == params["coverage_level"] and label == "1.7" and \
                        key == "steel_in_brass":
                    datasets["example/measured"] = (fit.measured.heights, "m")
                    datasets["example/fitted"] = (fit.fitted, "m")
                    datasets["example/residual"] = (fit.residual, "m")
                    datasets["example/phase"] = (fit.phase.astype(np.int8), "1")
                    attrs["example_offset"] = (fit.offset, "m")
                    attrs["example_tilt"] = (np.asarray(fit.tilt), "1")
                    attrs["example_ratio"] = (r, "1")
                    attrs["example_interval"] = (np.array([lo, hi]), "1")
                    attrs["example_residual_rms"] = (fit.residual_rms, "m")
                    attrs["example_effective_samples"] = (fit.effective_samples, "1")
                    attrs["example_samples"] = (fit.samples, "1")
                    attrs["example_load_scale"] = (fit.load_scale, "1")
                    attrs["example_load_scale_interval"] = (
                        np.asarray(fit.load_scale_interval), "1")
            group = f"{key}/{label.replace('/', '_over_')}"
            datasets[f"{group}/fitted"] = (np.array(fitted), "1")
            datasets[f"{group}/lower"] = (np.array(lower), "1")
            datasets[f"{group}/upper"] = (np.array(upper), "1")
            datasets[f"{group}/relief"] = (relief, "m")
            other = 1 / ratio
            excluded = (np.array(lower) > other) | (np.array(upper) < other)
            covered = (np.array(lower) <= ratio) & (ratio <= np.array(upper))
            datasets[f"{group}/excludes_other"] = (excluded.astype(np.int8), "1")
            datasets[f"{group}/covers_truth"] = (covered.astype(np.int8), "1")
            # The largest noise level up to which the other ratio stays outside the interval.
            ok = np.cumprod(excluded).astype(bool)
            separated[f"{key}_{label}"] = levels[int(ok.sum()) - 1] if ok.any() else 0.0
            for _ in range(params["coverage_trials"]):
                heights = face + plane + params["coverage_level"] * relief * _noise(
                    rng, n, params["correlation_px"])
                r, (lo, hi) = _steel_over_brass(
                    model.fit(MeasuredFace(heights, h), reference_phase=brass), key)
                coverage_hits += lo <= ratio <= hi
                coverage_total += 1
    datasets["levels"] = (np.asarray(levels), "1")
    attrs["radius"] = (scene.outline.radius, "m")
    for name, value in separated.items():
        attrs[f"separated_up_to_{name.replace('/', '_over_')}"] = (value, "1")
    attrs["coverage"] = (coverage_hits / coverage_total, "1")
    attrs["coverage_trials"] = (coverage_total, "1")

    # Discretisation bias: the "measured" face is the steel-in-brass face at
    # k_steel/k_brass = 1.7 on a grid `fine` times finer, averaged over the
    # measured pixels (no noise), fitted with models of several grids.
    scene = load_scene(study_io.ROOT / "steady" / "examples" / SCENES["steel_in_brass"])
    fine = params["fine"] * n
    face, _ = _truth(scene, "steel_in_brass", 1.7, fine)
    b = params["fine"]
    measured = MeasuredFace(face.reshape(n, b, n, b).mean(axis=(1, 3)),
                            scene.grid(n).h)
    bias = []
    for n_model in params["model_grids"]:
        fit = FaceModel.from_scene(scene, n=n_model).fit(measured, reference_phase=0)
        bias.append(fit.ratios[1] / 1.7 - 1)
    datasets["model_grids"] = (np.asarray(params["model_grids"]), "1")
    datasets["model_bias"] = (np.asarray(bias), "1")
    study_io.write_study(path, NAME, params, datasets, attrs)


def plot(path, png):
    """Draw the example fit and the fitted ratio against the noise level from the HDF5 file."""
    d, a = study_io.read_study(path, NAME)
    p = a["params"]
    fig = study_io.figure(12.5, 8.2)
    top, bottom = fig.subfigures(2, 1, height_ratios=[1, 1.05])
    axes = top.subplots(1, 3, sharex=True, sharey=True)
    measured = d["example/measured"]
    n = measured.shape[0]
    r_mm = a["radius"] * 1e3
    h = 2 * r_mm / n
    x = (np.arange(n) - 0.5 * (n - 1)) * h
    plane = (a["example_offset"] + a["example_tilt"][0] * x[:, None] * 1e-3
             + a["example_tilt"][1] * x[None, :] * 1e-3)
    on = d["example/phase"] >= 0
    panels = [(np.where(on, measured - plane, np.nan) * 1e6, "measured, plane removed"),
              ((d["example/fitted"] - plane) * 1e6, r"fitted $\sum_i p_i K\chi_i$"),
              (d["example/residual"] * 1e6,
               f"residual, rms {a['example_residual_rms'] * 1e6:.3g} µm")]
    lo, hi = np.nanpercentile(panels[1][0], [0.5, 99.5])
    rmax = np.nanpercentile(np.abs(panels[2][0]), 99.5)
    extent = (-r_mm, r_mm, -r_mm, r_mm)
    for ax, (field, title) in zip(axes, panels, strict=True):
        residual = title.startswith("residual")
        im = ax.imshow(field.T, origin="lower", extent=extent, interpolation="nearest",
                       cmap="RdBu_r" if residual else "viridis",
                       vmin=-rmax if residual else lo, vmax=rmax if residual else hi)
        top.colorbar(im, ax=ax, shrink=0.85).set_label("height (µm)")
        ax.set_title(title, fontsize=9)
        ax.set_xlabel("x (mm)")
    axes[0].set_ylabel("y (mm)")
    axes[2].contour(x, x, d["example/phase"].T.astype(float), levels=[0.5], colors="k",
                    linewidths=0.5)
    ex_lo, ex_hi = a["example_interval"]
    top.suptitle(f"steel rods in brass, k_steel/k_brass = 1.7, noise {100 * p['coverage_level']:g} "
                 f"% of the relief (correlated over {p['correlation_px']:g} px): fitted "
                 f"{a['example_ratio']:.3f} [{ex_lo:.3f}, {ex_hi:.3f}], load scale "
                 f"{a['example_load_scale']:.3f}", fontsize=9)

    ax = bottom.subplots()
    levels = d["levels"] * 100
    markers = {"steel_in_brass": "o", "brass_in_steel": "s"}
    colours = {"1.7": "C3", "1/1.7": "C0"}
    for i, key in enumerate(SCENES):
        for label in TRUTHS:
            g = f"{key}/{label.replace('/', '_over_')}"
            shift = 1.0 + 0.05 * (2 * i - 1) + (0.02 if label == "1.7" else -0.02)
            fitted, lower, upper = d[f"{g}/fitted"], d[f"{g}/lower"], d[f"{g}/upper"]
            upper_plot = np.where(np.isfinite(upper), upper, 1e3)
            lower_plot = np.maximum(lower, 1e-3)
            ax.errorbar(levels * shift, fitted, yerr=[fitted - lower_plot, upper_plot - fitted],
                        fmt=markers[key], color=colours[label], ms=4, capsize=2, lw=0.8,
                        label=f"{TITLES[key]}, true {label}")
    for value, label in ((1.7, "1.7"), (1 / 1.7, "1/1.7")):
        ax.axhline(value, color=colours[label], lw=0.6, ls="--")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_ylim(0.2, 6)
    study_io.plain_log_ticks(ax)
    ax.set_xlabel("noise, % of the relief (rms, correlated over "
                  f"{p['correlation_px']:g} pixels of {2 * r_mm / p['n']:.2g} mm)")
    ax.set_ylabel("fitted k_steel / k_brass (95 % interval)")
    bias = ", ".join(f"n = {g}: {100 * b:+.2f} %" for g, b in zip(d["model_grids"],
                                                                 d["model_bias"], strict=True))
    ax.set_title(f"coverage of the 95 % intervals at {100 * p['coverage_level']:g} % noise: "
                 f"{a['coverage']:.3f} over {int(a['coverage_trials'])} faces; model "
                 f"discretisation bias of the ratio: {bias}", fontsize=9)
    ax.legend(fontsize=8, ncol=2, loc="upper left")
    study_io.save_figure(fig, png, dpi=80)


def main(argv=None):
    """Run the study from the command line (``--help`` lists the options); exit status."""
    return study_io.run_study(NAME, __doc__, compute, plot, PARAMS, QUICK, argv)


if __name__ == "__main__":
    sys.exit(main())
