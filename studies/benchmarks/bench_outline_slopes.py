"""Accuracy and error bar of the corrected rms-slope estimator on other face outlines.

The energy-corrected rms slope of :mod:`steady.rms_slope`
(:func:`steady.rms_slope.estimate_rms_slope`: the value on the finest grid of
the ladder ``n/4, n/2, n`` and its error bar) measured as the disk's is in
docs/benchmarks.md ("Rms slope accuracy"), on the faces of
:mod:`steady.outline`:

1. The homogeneous face (uniform pressure ``pbar = F / A``) of a circle, a
   square, a 1:3 rectangle both ways up (width < length and width >
   length), and annuli of radius ratio 0.5 and 0.8, against the closed
   forms of :mod:`steady.reference` (rms slope ``S pbar / E*``), at
   ``n = 32 .. 512`` pixels along the longer side: the relative error of
   the corrected and of the plain pixel value, the error bar, whether the
   bar covers the error, the relative error of the face's pixel area
   ``A_pix / A - 1`` on the finest grid, the error of the pixel face (the
   rasterised outline at its own mean pressure, see below) and the time of
   the whole estimate; then the convergence order of each (least-squares
   slope of ``log |error|`` against ``log n``, ``n`` the finest grid
   solved).
2. The homogeneous 1:2 ellipse (no closed form): self-convergence against
   the corrected value at a fine grid (with the face's area error, as
   in 3).
3. Two-phase faces (``k_2 / k_1 = 10``): Voronoi cells on a square and on
   a 1:3 rectangle, rods in a 1:3 rectangle, against the corrected value
   at a fine grid: internal boundaries that meet the rim and the corners;
   and a square cut into two halves along an axis (a straight internal
   boundary, pixel edges in a line like the rim's) and along a diagonal (a
   staircase), which tell the two kinds of internal boundary apart.

The pixel face: the grid's face is the set of pixels whose centre lies in
the outline; its area ``A_pix`` differs from ``A`` by the staircase, so its
mean pressure is ``F / A_pix``.  The column "pixel-face error" compares the
corrected value with ``S_pix F / (A_pix E*)``: ``S_pix`` is the closed form
of the pixel face itself for a rectangle (the pixels tile a rectangle of
``nx h x ny h``), the outline's ``S`` for a circle or an annulus (the
staircase's change of shape is not removed).  It separates the
estimator's quadrature error from the error of the face's rasterisation.

Times: the whole estimate (rasterise, solve the pressures and apply the
estimator on every grid of the ladder, kernels built), best of a few,
and in units of one zero-padded FFT pair (``rfft2`` + ``irfft2`` of a
``2 nx x 2 ny`` array) of the finest grid.

Run::

    python studies/benchmarks/bench_outline_slopes.py            # about a minute on 2 cores
    python studies/benchmarks/bench_outline_slopes.py --quick    # seconds

Writes ``out/bench_outline_slopes.h5`` (``out/quick/...`` with ``--quick``;
``--out`` to choose) and prints Markdown tables.
"""

import argparse
import dataclasses
import logging
import os
import pathlib
import platform
import sys
import time

import numpy as np
import scipy
import scipy.fft

ROOT = pathlib.Path(__file__).resolve().parents[2]

E_STAR = 1.3e6  # Pa
FORCE = 10.0    # N
A = 4e-3        # m, the epoxy cylinder's radius: every outline's scale L

GRIDS = [32, 64, 128, 256, 512]
QUICK_GRIDS = [32, 64, 128]
#: Fine grids of the self-convergence references (multiples of 3 for the 1:3
#: rectangle, so that its pixels tile it exactly).
REFERENCE = {"square": 2048, "rectangle": 1536, "ellipse": 2048}
QUICK_REFERENCE = {"square": 256, "rectangle": 192, "ellipse": 256}
REPEATS = 3
RATIO = 10.0  # k_2 / k_1 of the two-phase faces


def homogeneous_cases():
    """``name -> (outline, S, pixel-face factor or None)`` of the closed-form faces."""
    from steady import reference
    from steady.outline import Annulus, Circle, Rectangle

    return {
        "circle": (Circle(A), 4.0 / np.pi),
        "square": (Rectangle(2 * A, 2 * A), reference.rectangle_rms_slope(1.0)),
        "rectangle 1:3 (width < length)": (Rectangle(2 * A / 3, 2 * A),
                                           reference.rectangle_rms_slope(1.0, 3.0)),
        "rectangle 3:1 (width > length)": (Rectangle(2 * A, 2 * A / 3),
                                           reference.rectangle_rms_slope(3.0, 1.0)),
        "annulus 0.5": (Annulus(0.5 * A, A), reference.annulus_rms_slope(0.5)),
        "annulus 0.8": (Annulus(0.8 * A, A), reference.annulus_rms_slope(0.8)),
    }


@dataclasses.dataclass(frozen=True)
class HalfPlanes:
    """Two phases split by a straight line through the centre: phase 1 where ``x cos + y sin > 0``.

    Coordinates in units of the outline's scale ``L``.  Pixel centres on
    the line (a diagonal of a square grid) go to phase 1 in even rows,
    phase 0 in odd ones, so that the rasterised halves keep equal areas
    (all on one side, the boundary would sit half a pixel off the line, an
    error of the geometry of first order in ``h``).
    """

    angle: float
    n_phases = 2

    def min_grid(self, outline=None):
        """The smallest grid of any geometry (:data:`steady.outline.MIN_SIDE_PIXELS`)."""
        from steady.outline import MIN_SIDE_PIXELS

        return MIN_SIDE_PIXELS

    def check_grid(self, grid):
        """``n`` as an int; ``ValueError`` below :meth:`min_grid`."""
        from steady.outline import as_grid

        n = as_grid(grid).n
        if n < self.min_grid():
            raise ValueError(f"grid too coarse for two half-planes: n = {n}")
        return n

    def labels(self, grid):
        """Phase 0 or 1 on the face, -1 off it; shape of the grid."""
        from steady.outline import as_grid

        grid = as_grid(grid)
        value = (grid.unit_x[:, None] * np.cos(self.angle)
                 + grid.unit_y[None, :] * np.sin(self.angle))
        tie = np.abs(value) < 1e-9
        even = (np.arange(grid.shape[0]) % 2 == 0)[:, None]
        side = (value > 0) & ~tie | tie & even
        return np.where(grid.mask, side.astype(np.int64), -1)


def two_phase_cases():
    """``name -> (geometry, outline, reference key)`` of the two-phase faces."""
    from steady.outline import Rectangle
    from steady.phases import Rods, Voronoi

    rods = Rods(((0.0, -0.6 * A), (0.0, 0.0), (0.0, 0.6 * A)), (0.2 * A,) * 3)  # on 1:3, L = A
    square = Rectangle(2 * A, 2 * A)
    return {
        # About 25 seeds per L^2 on both.
        "Voronoi 100 seeds, square": (Voronoi(100, (0.5, 0.5), 4321), square, "square"),
        "Voronoi 36 seeds, 1:3": (Voronoi(36, (0.5, 0.5), 4321),
                                  Rectangle(2 * A / 3, 2 * A), "rectangle"),
        "3 rods r = 0.2 L, 1:3": (rods, Rectangle(2 * A / 3, 2 * A), "rectangle"),
        "square, halves along an axis": (HalfPlanes(0.0), square, "square"),
        "square, halves along the diagonal": (HalfPlanes(np.pi / 4), square, "square"),
    }


def _best(fn, repeats):
    best, out = np.inf, None
    for _ in range(repeats):
        t = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t)
    return best, out


def fft_pair_time(shape, repeats):
    """Best time of one zero-padded FFT pair on a grid of ``shape``, s."""
    padded = np.zeros((2 * shape[0], 2 * shape[1]))
    padded[:shape[0], :shape[1]] = 1.0

    def pair():
        scipy.fft.irfft2(scipy.fft.rfft2(padded, workers=-1), s=padded.shape, workers=-1)

    pair()
    return _best(pair, repeats)[0]


def estimate(geometry, k, outline, n, repeats):
    """``(SlopeEstimate, seconds, seconds per FFT pair)`` of one timed estimate."""
    from steady.outline import FaceGrid
    from steady.rms_slope import estimate_rms_slope

    seconds, est = _best(lambda: estimate_rms_slope(geometry, k, FORCE, outline, E_STAR, n),
                         repeats)
    pair = fft_pair_time(FaceGrid(outline, est.grids[-1]).shape, repeats)
    return est, seconds, pair


def order(rows, key):
    """Least-squares slope of ``-log |row[key]|`` against ``log`` of the finest grid.

    Each finest grid counts once (a ladder that refines, ``n, 2n``, repeats
    the row of ``2n``); NaN with fewer than two.
    """
    points = {r["grids"][-1]: abs(r[key]) for r in rows if r[key] != 0}
    if len(points) < 2:
        return float("nan")
    n, e = np.array(sorted(points.items()), dtype=float).T
    return float(-np.polyfit(np.log(n), np.log(e), 1)[0])


def homogeneous(grids, repeats):
    """Rows of table 1 and the orders, by case."""
    from steady import reference
    from steady.outline import FaceGrid, Rectangle
    from steady.phases import Homogeneous

    results = {}
    for name, (outline, factor) in homogeneous_cases().items():
        exact = factor * FORCE / outline.area / E_STAR
        rows = []
        for n in grids:
            est, seconds, pair = estimate(Homogeneous(), [1.0], outline, n, repeats)
            grid = FaceGrid(outline, est.grids[-1])
            if isinstance(outline, Rectangle):
                nx, ny = grid.shape
                s_pix = reference.rectangle_rms_slope(nx, ny)
            else:
                s_pix = factor
            pixel_exact = s_pix * FORCE / grid.face_area / E_STAR
            rows.append(dict(n=n, grids=est.grids, rms_slope=est.rms_slope,
                             rms_slope_plain=est.rms_slope_plain, error_bar=est.error,
                             relative_error=est.rms_slope / exact - 1,
                             plain_relative_error=est.rms_slope_plain / exact - 1,
                             relative_error_bar=est.error / exact,
                             covered=bool(abs(est.rms_slope - exact) <= est.error),
                             pixel_face_error=est.rms_slope / pixel_exact - 1,
                             area_error=grid.face_area / outline.area - 1,
                             seconds=seconds, pairs=seconds / pair))
        results[name] = dict(
            outline=outline, factor=factor, exact=exact, rows=rows,
            order_corrected=order(rows, "relative_error"),
            order_plain=order(rows, "plain_relative_error"),
            order_pixel_face=order(rows, "pixel_face_error"))
    return results


def self_convergence(cases, grids, references, repeats):
    """Rows against a fine-grid corrected reference, by case.

    ``cases``: ``name -> (geometry, k, outline, reference key)``.
    """
    results = {}
    from steady.outline import FaceGrid

    for name, (geometry, k, outline, key) in cases.items():
        ref, ref_seconds, _ = estimate(geometry, k, outline, references[key], 1)
        rows = []
        for n in grids:
            try:
                geometry.check_grid(outline.grid(n))
            except ValueError:
                continue
            est, seconds, pair = estimate(geometry, k, outline, n, repeats)
            rows.append(dict(n=n, grids=est.grids, rms_slope=est.rms_slope,
                             rms_slope_plain=est.rms_slope_plain, error_bar=est.error,
                             relative_error=est.rms_slope / ref.rms_slope - 1,
                             plain_relative_error=est.rms_slope_plain / ref.rms_slope - 1,
                             relative_error_bar=est.error / ref.rms_slope,
                             covered=bool(abs(est.rms_slope - ref.rms_slope)
                                          <= est.error + ref.error),
                             area_error=FaceGrid(outline, est.grids[-1]).face_area
                             / outline.area - 1,
                             seconds=seconds, pairs=seconds / pair))
        results[name] = dict(outline=outline, reference=ref, reference_seconds=ref_seconds,
                             rows=rows, order_corrected=order(rows, "relative_error"),
                             order_plain=order(rows, "plain_relative_error"))
    return results


def _grids(row):
    return ", ".join(map(str, row["grids"]))


def markdown_homogeneous(results):
    """Table 1 and the orders in Markdown."""
    lines = ["| face | n | grids solved | corrected error | plain error | error bar | covered "
             "| face area error | pixel-face error | time (s) | time (FFT pairs) |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    for name, res in results.items():
        for r in res["rows"]:
            lines.append(f"| {name} | {r['n']} | {_grids(r)} | {r['relative_error']:+.2e} | "
                         f"{r['plain_relative_error']:+.2e} | {r['relative_error_bar']:.2e} | "
                         f"{'yes' if r['covered'] else 'no'} | {r['area_error']:+.1e} | "
                         f"{r['pixel_face_error']:+.2e} | {r['seconds']:.3f} | {r['pairs']:.0f} |")
    lines += ["", "| face | S (closed form) | order corrected | order plain "
              "| order pixel face |", "|---|---|---|---|---|"]
    for name, res in results.items():
        lines.append(f"| {name} | {res['factor']:.12f} | {res['order_corrected']:.2f} | "
                     f"{res['order_plain']:.2f} | {res['order_pixel_face']:.2f} |")
    return "\n".join(lines)


def markdown_self_convergence(results):
    """Tables 2 and 3 in Markdown."""
    lines = ["| face | n | grids solved | corrected change | plain change | error bar "
             "| covered | face area error | time (s) | time (FFT pairs) |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for name, res in results.items():
        for r in res["rows"]:
            lines.append(f"| {name} | {r['n']} | {_grids(r)} | {r['relative_error']:+.2e} | "
                         f"{r['plain_relative_error']:+.2e} | {r['relative_error_bar']:.2e} | "
                         f"{'yes' if r['covered'] else 'no'} | {r['area_error']:+.1e} | "
                         f"{r['seconds']:.3f} | {r['pairs']:.0f} |")
    lines += ["", "| face | reference: n, grids | reference rms slope | its error bar "
              "| order corrected | order plain |", "|---|---|---|---|---|---|"]
    for name, res in results.items():
        ref = res["reference"]
        lines.append(f"| {name} | {ref.grids[-1]}: {', '.join(map(str, ref.grids))} | "
                     f"{ref.rms_slope:.8f} | {ref.error / ref.rms_slope:.1e} | "
                     f"{res['order_corrected']:.2f} | {res['order_plain']:.2f} |")
    return "\n".join(lines)


_UNITS = dict(n="1 (pixels along the longer side)", rms_slope="1", rms_slope_plain="1",
              error_bar="1", relative_error="1", plain_relative_error="1",
              relative_error_bar="1", covered="bool", pixel_face_error="1", area_error="1",
              seconds="s", pairs="1 (zero-padded FFT pairs of the finest grid)")


def _write_rows(group, rows):
    for key, unit in _UNITS.items():
        if rows and key in rows[0]:
            group.create_dataset(key, data=np.array([r[key] for r in rows])).attrs["units"] = unit
    finest = group.create_dataset("finest_grid", data=np.array([r["grids"][-1] for r in rows]))
    finest.attrs["units"] = "1 (pixels along the longer side)"
    group.attrs["grids"] = [_grids(r) for r in rows]


def _outline_attrs(group, outline):
    group.attrs["outline"] = outline.describe()
    for key, (value, unit) in outline.parameters().items():
        group.attrs[key] = value
        group.attrs[f"{key}_units"] = unit
    group.attrs["area"] = outline.area
    group.attrs["area_units"] = "m^2"


def write_h5(path, tables, meta):
    """Write every table (a group per face) and the run's metadata."""
    from steady.safe_files import atomic_h5

    with atomic_h5(path, format="runin.bench_outline_slopes", version=1, force=True) as f:
        for key, value in meta.items():
            f.attrs[key] = value
        f.attrs["E_star"], f.attrs["E_star_units"] = E_STAR, "Pa"
        f.attrs["normal_force"], f.attrs["normal_force_units"] = FORCE, "N"
        for table, results in tables.items():
            t = f.create_group(table)
            for name, res in results.items():
                g = t.create_group(name.replace("/", "-"))
                _outline_attrs(g, res["outline"])
                _write_rows(g, res["rows"])
                for key in ("order_corrected", "order_plain", "order_pixel_face"):
                    if key in res:
                        g.attrs[key] = res[key]
                        g.attrs[f"{key}_units"] = "1"
                if "factor" in res:
                    g.attrs["factor"] = res["factor"]
                    g.attrs["factor_units"] = "1 (rms slope in units of pbar / E*)"
                    g.attrs["exact"] = res["exact"]
                    g.attrs["exact_units"] = "1"
                if "reference" in res:
                    ref = res["reference"]
                    g.attrs["reference"] = ref.rms_slope
                    g.attrs["reference_units"] = "1"
                    g.attrs["reference_error"] = ref.error
                    g.attrs["reference_error_units"] = "1"
                    g.attrs["reference_grids"] = list(ref.grids)
                    g.attrs["reference_seconds"] = res["reference_seconds"]
                    g.attrs["reference_seconds_units"] = "s"


def main(argv=None):
    """Command line of the benchmark (see the module docstring).

    Returns
    -------
    dict
        The results of the three tables, by table name.
    """
    from steady.outline import Ellipse
    from steady.phases import Homogeneous

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true",
                        help=f"grids {QUICK_GRIDS}, references at n = 192 .. 256 (seconds)")
    parser.add_argument("--out", type=pathlib.Path, default=None,
                        help="HDF5 file (default out/bench_outline_slopes.h5, "
                             "out/quick/... with --quick)")
    parser.add_argument("--repeats", type=int, default=REPEATS, help="timing repeats")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.WARNING)
    grids = QUICK_GRIDS if args.quick else GRIDS
    references = QUICK_REFERENCE if args.quick else REFERENCE
    out = args.out or (ROOT / "out" / ("quick" if args.quick else "") / "bench_outline_slopes.h5")
    meta = dict(machine=platform.processor() or platform.machine(), cores=os.cpu_count(),
                python=platform.python_version(), numpy=np.__version__,
                scipy=scipy.__version__, quick=bool(args.quick),
                command="python " + " ".join([str(pathlib.Path(sys.argv[0]))] + (
                    argv if argv is not None else sys.argv[1:])))
    print(f"Machine: {meta['machine']}, {meta['cores']} cores, python {meta['python']}, "
          f"numpy {meta['numpy']}, scipy {meta['scipy']}\n")
    tables = {}
    print(f"Homogeneous faces against their closed forms (E* = {E_STAR:g} Pa, F = {FORCE:g} N, "
          f"scale L = {A * 1e3:g} mm); errors relative to the closed form.\n")
    tables["homogeneous"] = homogeneous(grids, args.repeats)
    print(markdown_homogeneous(tables["homogeneous"]))
    print("\nHomogeneous 1:2 ellipse (semi-axes L/2 x L): changes relative to the corrected "
          "value at the reference grid.\n")
    ellipse = {"ellipse 1:2": (Homogeneous(), [1.0], Ellipse(0.5 * A, A), "ellipse")}
    tables["ellipse"] = self_convergence(ellipse, grids, references, args.repeats)
    print(markdown_self_convergence(tables["ellipse"]))
    print(f"\nTwo-phase faces, k_2/k_1 = {RATIO:g} (Voronoi: rho_2 = 0.5, seed 4321; rods at "
          "(0, -0.6 L), (0, 0), (0, 0.6 L)): changes relative to the corrected value at the "
          "reference grid; covered: |change| <= error bar + the reference's error bar.\n")
    cases = {name: (geometry, [1.0, RATIO], outline, key)
             for name, (geometry, outline, key) in two_phase_cases().items()}
    tables["two_phase"] = self_convergence(cases, grids, references, args.repeats)
    print(markdown_self_convergence(tables["two_phase"]))
    write_h5(out, tables, meta)
    print(f"\nwrote {out}")
    return tables


if __name__ == "__main__":
    main()
