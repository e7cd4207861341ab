"""Random circular inclusions: the rms slope against their radius, fill factor and eq. 18.

The pillars argument of the paper (eq. 16-18) takes circular hard inclusions
and concludes that the rms slope is ``grad_f0 / rho_2`` whatever their
radius.  Here random non-overlapping circular inclusions
(:class:`steady.inclusions.Inclusions`) of three radii ``0.02, 0.04, 0.08 a``
at fill factors ``rho_2 = 0.05 .. 0.4`` are given the wear ratios
``k_2/k_1 = 10^-3`` (hard pillars), ``10^-1`` and ``10`` (soft inclusions).
For every map:

- the rms slope over the whole face, energy-corrected
  (:class:`steady.basis.PhaseBasis`, :func:`wear_exponent.exponent_slopes`)
  with its discretisation error, against
  the fine-grain closed form (:func:`steady.reference.fine_grain_rms_slope`,
  at the realised fill factor) and eq. 18;
- the rms slope over the inclusions only (the pixel quadrature of the exact
  slope at the inclusion pixels, :meth:`steady.halfspace.HalfSpace.gradient`,
  on the grids 512, 1024, 2048, extrapolated by Aitken's delta-squared, the
  size of the extrapolation as its error), against eq. 18
  (:func:`steady.reference.pillars_rms_slope`), which is a statement about
  the pillars' own area.

Run::

    python studies/random_inclusions.py            # n = 512 (2048), 120 maps, about 8 min
    python studies/random_inclusions.py --quick    # about 2 s
    python studies/random_inclusions.py --plot-only

Writes ``OUT/random_inclusions.h5`` and ``OUT/random_inclusions.png``.
"""

import functools
import sys

import numpy as np
import study_io
from matplotlib.colors import ListedColormap
from wear_exponent import exponent_slopes

from steady.halfspace import HalfSpace
from steady.inclusions import Inclusions
from steady.labels import validate_labels
from steady.outline import UNIT_DISK
from steady.pressures import phase_pressures
from steady.reference import fine_grain_rms_slope

NAME = "random_inclusions"
# The face is the unit disk (a = 1 m, the grid of a bare n): radii in m are in units of a.
PARAMS = {"n": 512, "radii": [0.02, 0.04, 0.08], "fill_factors": [0.05, 0.1, 0.2, 0.3, 0.4],
          "ratios": [1e-3, 1e-1, 1e1], "seeds": list(range(6100, 6108)), "picture_fill": 0.2,
          "inclusion_grids": [512, 1024, 2048]}
QUICK = {"n": 96, "radii": [0.08, 0.16], "fill_factors": [0.1, 0.3], "ratios": [1e-3, 1e1],
         "seeds": [6101, 6102], "picture_fill": 0.3, "inclusion_grids": [96, 192, 384]}


@functools.lru_cache(maxsize=4)
def _face_gradient(n):
    """Slope field of a unit pressure on the whole face, grid ``n`` (a = 1 m, E* = 1 Pa)."""
    grid = UNIT_DISK.grid(n)
    halfspace = HalfSpace(grid.shape, grid.h, 1.0)
    return halfspace, halfspace.gradient(grid.mask.astype(float))


def inclusion_rms(geometry, grids, wear_coefficients):
    """Rms slope over the inclusion pixels, extrapolated over a ladder of grids.

    The plain pixel rms over the inclusions converges slowly from below
    (the slope is log-singular at every inclusion's rim, a share of the
    area ``~ h / r``); on three grids ``n, 2n, 4n`` it is extrapolated by
    Aitken's delta-squared (a geometric sequence of errors).

    Parameters
    ----------
    geometry : steady.inclusions.Inclusions
    grids : sequence of int, shape (3,)
        ``n, 2n, 4n``.
    wear_coefficients : ndarray, shape (K, 2), 1/Pa
        Matrix and inclusion coefficients, one row per case.

    Returns
    -------
    values : ndarray, shape (3, K)
        Plain rms over the inclusions on each grid, in units of ``grad_f0``.
    extrapolated : ndarray, shape (K,)
    error : ndarray, shape (K,)
        ``|extrapolated - values[-1]|``: the size of the extrapolation (the
        last grid's own error); twice the last difference where the
        differences do not shrink.
    """
    values = []
    for m in grids:
        halfspace, (fx, fy) = _face_gradient(m)
        labels = geometry.labels(m)
        counts = validate_labels(labels, 2)
        # Unit force on unit area: p_i / pbar; with a = 1 m, E* = 1 Pa, grad_f0 = 4/pi.
        p = phase_pressures(counts / counts.sum(), wear_coefficients, 1.0, 1.0)
        hit = labels == 1
        ix, iy = halfspace.gradient(hit.astype(float))
        p0, p1 = p[:, :1], p[:, 1:]
        # Slope of p0 (face - inclusions) + p1 inclusions, at the inclusion pixels.
        gx = p0 * fx[hit] + (p1 - p0) * ix[hit]
        gy = p0 * fy[hit] + (p1 - p0) * iy[hit]
        values.append(np.sqrt(np.mean(gx * gx + gy * gy, axis=1)) / (4.0 / np.pi))
    values = np.asarray(values)
    d1, d2 = values[1] - values[0], values[2] - values[1]
    shrinking = np.abs(d2) < np.abs(d1)
    with np.errstate(divide="ignore", invalid="ignore"):
        aitken = values[2] + np.where(shrinking, d2 * d2 / (d1 - d2), 0.0)
    error = np.where(shrinking, np.abs(aitken - values[2]), 2 * np.abs(d2))
    return values, aitken, error


def inclusion_slopes(geometry, n, ratios, inclusion_grids):
    """Rms slopes over the face and over the inclusions for several wear ratios.

    Parameters
    ----------
    geometry : steady.inclusions.Inclusions
    n : int
        Grid of the face values.
    ratios : sequence of float, shape (K,)
        ``k_2 / k_1`` (inclusions over matrix).
    inclusion_grids : sequence of int, shape (3,)
        Grids of :func:`inclusion_rms`.

    Returns
    -------
    dict
        ``face`` (K,) energy-corrected ``rms / grad_f0`` over the face and
        ``face_error`` (K,) its ladder error (:func:`wear_exponent.exponent_slopes`
        at ``m = 1``); ``inclusions`` (K,) rms slope over the inclusions /
        ``grad_f0`` (extrapolated), ``inclusions_error`` (K,) and
        ``inclusions_grids`` (3, K) the plain values it comes from; ``fill``
        realised ``rho_2`` on grid ``n``.
    """
    ratios = np.asarray(ratios, dtype=float)
    face, face_error, _, fill = exponent_slopes(geometry, n, ratios, [1.0])
    k = np.column_stack([np.ones_like(ratios), ratios])
    plain, inside, error = inclusion_rms(geometry, inclusion_grids, k)
    return {"face": face[0], "face_error": face_error[0], "inclusions": inside,
            "inclusions_error": error, "inclusions_grids": plain, "fill": fill}


def compute(path, params):
    """Every (radius, fill factor, realisation) map; write HDF5."""
    radii, fills, seeds, ratios = (params[key] for key in ("radii", "fill_factors", "seeds",
                                                           "ratios"))
    shape = (len(radii), len(fills), len(seeds), len(ratios))
    out = {key: np.empty(shape) for key in ("face", "face_error", "inclusions",
                                            "inclusions_error")}
    out["inclusions_grids"] = np.empty(shape[:3] + (3, len(ratios)))
    realised = np.empty(shape[:3])
    counts = np.empty(shape[:3])
    for a, r in enumerate(radii):
        for b, rho in enumerate(fills):
            for s, seed in enumerate(seeds):
                geometry = Inclusions(r, seed, fill_factor=rho)
                v = inclusion_slopes(geometry, params["n"], ratios,
                                     params["inclusion_grids"])
                for key in out:
                    out[key][a, b, s] = v[key]
                realised[a, b, s] = v["fill"]
                centres, _ = geometry.placement()  # on the unit disk, m
                counts[a, b, s] = np.sum(np.hypot(*centres.T) < 1.0)
    k = np.column_stack([np.ones(len(ratios)), ratios])
    closed = fine_grain_rms_slope(np.stack([1 - realised, realised], axis=-1)[..., None, :], k)
    rel = out["face"] / closed - 1
    radius_spread = np.ptp(out["face"].mean(axis=2), axis=0)  # (fill, ratio)
    sem = out["face"].std(axis=2, ddof=1) / np.sqrt(len(seeds))
    pictures = np.array([Inclusions(r, seeds[0], fill_factor=params["picture_fill"])
                         .labels(params["n"]).astype(np.int8) for r in radii])
    fine = np.linspace(0.02, 0.45, 87)
    datasets = {
        "radii": (np.asarray(radii), "a"),
        "fill_factors": (np.asarray(fills), "1"),
        "ratios": (np.asarray(ratios), "1"),
        "realised_fill": (realised, "1"),
        "inclusions_on_face": (counts, "1"),
        "closed_form_realised": (closed, "grad_f0"),
        "relative_to_closed_form": (rel, "1"),
        "pictures": (pictures, "1"),
        "curve_fill": (fine, "1"),
        "curve_fine_grain": (fine_grain_rms_slope(np.stack([1 - fine, fine], axis=-1)[None],
                                                  k[:, None, :]), "grad_f0"),
    }
    for key, value in out.items():
        datasets[key] = (value, "grad_f0")
    # Eq. 18 over the inclusions: rms / (grad_f0 / rho_2) at the realised fill factor.
    datasets["inclusions_over_eq18"] = (out["inclusions"] * realised[..., None], "1")
    return study_io.write_study(path, NAME, params, datasets, {
        "realisations": (len(seeds), "1"),
        "max_face_error": (float(out["face_error"].max()), "grad_f0"),
        "max_inclusions_error": (float(out["inclusions_error"].max()), "grad_f0"),
        "mean_relative_to_closed_form": (float(rel.mean()), "1"),
        "max_relative_to_closed_form": (float(np.max(np.abs(rel.mean(axis=2)))), "1"),
        "max_radius_spread_over_sem": (float(np.max(radius_spread / sem.max(axis=0))), "1"),
        "max_radius_spread_relative": (float(np.max(radius_spread
                                                    / out["face"].mean(axis=(0, 2)))), "1"),
    })


def plot(path, png):
    """Three maps, the two rms slopes against the fill factor, from the HDF5 file."""
    d, a = study_io.read_study(path, NAME)
    p = a["params"]
    radii, fills, ratios = d["radii"], d["fill_factors"], d["ratios"]
    fig = study_io.figure(13.0, 8.4)
    top, bottom = fig.subfigures(2, 1, height_ratios=[1, 1.5])
    cmap = ListedColormap(["#bdbdbd", "#252525"])
    for ax, pic, r in zip(top.subplots(1, len(radii)), d["pictures"], radii, strict=True):
        ax.imshow(np.ma.masked_less(pic, 0).T, origin="lower", extent=(-1, 1, -1, 1), cmap=cmap,
                  interpolation="nearest")
        ax.set_title(f"radius {r:g} a, $\\rho_2$ = {p['picture_fill']:g}, seed {p['seeds'][0]}",
                     fontsize=9)
        ax.set_xticks([])
        ax.set_yticks([])
    ax_face, ax_inc = bottom.subplots(1, 2)
    markers = "os^v"
    for c, ratio in enumerate(ratios):
        for i, r in enumerate(radii):
            shift = 1 + 0.03 * (i - (len(radii) - 1) / 2)
            for ax, key in ((ax_face, "face"), (ax_inc, "inclusions")):
                v = d[key][i, :, :, c]
                ax.errorbar(fills * shift, v.mean(axis=1), yerr=v.std(axis=1, ddof=1),
                            fmt=markers[i % 4], ms=3.5, mfc="none", color=f"C{c}", capsize=2,
                            lw=0.7, label=f"$k_2/k_1$ = {ratio:g}, r = {r:g} a")
        ax_face.plot(d["curve_fill"], d["curve_fine_grain"][c], color=f"C{c}", lw=0.9)
    for ax in (ax_face, ax_inc):
        ax.plot(d["curve_fill"], 1 / d["curve_fill"], "k--", lw=0.8,
                label=r"eq. 18: $1/\rho_2$")
        ax.set_xscale("log")
        ax.set_yscale("log")
        study_io.plain_log_ticks(ax)
        ax.set_xlabel(r"fill factor of the inclusions $\rho_2$")
    ax_face.set_ylabel(r"rms slope over the face / $\nabla f^0_\infty$")
    ax_face.set_title(f"over the face (energy-corrected, n = {p['n']}); lines: fine-grain "
                      f"form\nmean deviation {100 * a['mean_relative_to_closed_form']:+.2f} %, "
                      f"worst point {100 * a['max_relative_to_closed_form']:.1f} %; radii "
                      f"differ by at most {a['max_radius_spread_over_sem']:.1f} standard "
                      f"errors", fontsize=8.5)
    ax_inc.set_ylabel(r"rms slope over the inclusions / $\nabla f^0_\infty$")
    grids = ", ".join(str(g) for g in p["inclusion_grids"])
    ax_inc.set_title(f"over the inclusions only (grids {grids}, extrapolated; error up to "
                     f"{a['max_inclusions_error']:.2f})\nbars: scatter of "
                     f"{a['realisations']} realisations", fontsize=8.5)
    ax_inc.legend(fontsize=6.5, ncol=2)
    study_io.save_figure(fig, png, dpi=75)


def main(argv=None):
    """Run the study from the command line (``--help`` lists the options); exit status."""
    return study_io.run_study(NAME, __doc__, compute, plot, PARAMS, QUICK, argv)


if __name__ == "__main__":
    sys.exit(main())
