"""A synthetic two-phase micrograph: blurred, noisy grains of known phases.

Makes ``steady/examples/micrograph_example.png``, the image of the shipped
scene ``steady/examples/micrograph_steady.toml``: Voronoi grains (nearest of
random seeds), 30 % of them of a bright phase in a darker matrix, seen
through an optical blur (Gaussian, 1.5 pixels) with Gaussian noise of 5 %
of full scale, stored as 8-bit grey levels.  It stands in for an etched
micrograph of a two-phase alloy; the truth it was made from is known, so
the segmentation of :mod:`steady.micrograph` can be checked against it
(``tests/test_micrograph.py``).

:func:`make_particles` makes a harder image, like a secondary-electron
micrograph of carbide particles in a ferrite matrix: each particle is seen as
a bright rim (the edge effect) around a core darker than the matrix, the
brightness of the matrix drifts across the field, and the microscope's data
bar (black, with white lettering and a scale bar) fills the bottom rows.  A
global Otsu threshold picks the bar or the rims there, not the particles; a
crop, manual thresholds and hole filling recover them.

Run::

    python studies/make_micrograph.py          # about 2 s: OUT/micrograph_example.png
    python studies/make_micrograph.py -o steady/examples/micrograph_example.png  # the shipped one
    python studies/make_micrograph.py --particles -o se.png  # the particles image

The image is a pure function of the parameters below (the seed included).
"""

import argparse
import pathlib
import sys

import numpy as np
import study_io
from PIL import Image
from scipy import ndimage, spatial

#: The file as shipped with the package (``-o`` writes it there).
SHIPPED = (pathlib.Path(__file__).resolve().parents[1] / "steady" / "examples"
           / "micrograph_example.png")

#: Image size in pixels, grains, share of bright grains, grey levels of the
#: two phases (fraction of full scale), blur and noise (pixels, full scale).
PARAMS = {"rows": 360, "cols": 480, "n_grains": 400, "fill_factor": 0.3,
          "levels": (0.35, 0.65), "blur": 1.5, "noise": 0.05, "seed": 4111}


def make_grains(rows, cols, n_grains, fill_factor, levels, blur, noise, seed):
    """Grey levels and true phases of a synthetic micrograph.

    Parameters
    ----------
    rows, cols : int
        Image size, pixels.
    n_grains : int
        Voronoi grains (seeds uniform over the image).
    fill_factor : float or sequence of float
        Share of the grains of phase 1 (two phases), or of each phase
        ``1..P-1`` (phase 0 takes the rest); grains are counted, so the
        area fractions scatter around it.
    levels : sequence of float, shape (P,)
        Grey level of each phase, fraction of full scale.
    blur : float
        Gaussian blur, pixels (0: none).
    noise : float
        Standard deviation of the added Gaussian noise, fraction of full scale.
    seed : int
        Seed of :func:`numpy.random.default_rng`.

    Returns
    -------
    grey : ndarray, shape (rows, cols), float
        Blurred, noisy grey levels, clipped to [0, 1] (not quantised).
    truth : ndarray, shape (rows, cols), int
        Phase of each pixel before blur and noise.
    """
    rng = np.random.default_rng(seed)
    shares = np.atleast_1d(np.asarray(fill_factor, dtype=float))
    counts = np.rint(shares * n_grains).astype(int)
    phase = np.zeros(n_grains, dtype=np.int64)
    order = rng.permutation(n_grains)
    start = 0
    for p, count in enumerate(counts, start=1):
        phase[order[start:start + count]] = p
        start += count
    seeds = rng.uniform((0.0, 0.0), (rows, cols), size=(n_grains, 2))
    r, c = np.mgrid[0:rows, 0:cols]
    _, nearest = spatial.cKDTree(seeds).query(np.column_stack([r.ravel() + 0.5,
                                                              c.ravel() + 0.5]))
    truth = phase[nearest].reshape(rows, cols)
    grey = np.asarray(levels, dtype=float)[truth]
    if blur > 0:
        grey = ndimage.gaussian_filter(grey, blur, mode="nearest")
    grey = grey + rng.normal(0.0, noise, grey.shape)
    return np.clip(grey, 0.0, 1.0), truth


#: The particles image: size, data bar, particles (number, semi-axes in pixels,
#: gap between them), grey levels (matrix, particle core, rim peak), rim decay
#: length (pixels), matrix drift (peak to peak), blur and noise.
PARTICLES = {"rows": 300, "cols": 400, "bar_rows": 40, "n_particles": 140,
             "radii": (4.0, 12.0), "gap": 3, "matrix": 0.5, "core": 0.4, "rim": 1.0,
             "rim_width": 2.0, "drift": 0.02, "blur": 0.8, "noise": 0.04, "seed": 4127}


def _ellipse(window, centre, axes, angle):
    """Pixels of ``window`` (row and column slices) whose centre lies inside an ellipse.

    The ellipse has semi-axes ``axes`` (pixels) along directions turned by
    ``angle`` from the rows, and its centre at ``centre`` (row, column).
    """
    r, c = np.mgrid[window] + 0.5
    dr, dc = r - centre[0], c - centre[1]
    u = dc * np.cos(angle) + dr * np.sin(angle)
    v = -dc * np.sin(angle) + dr * np.cos(angle)
    return (u / axes[0]) ** 2 + (v / axes[1]) ** 2 < 1.0


def _data_bar(grey, bar_rows, rng):
    """Black bottom rows with white lettering and a scale bar, as a microscope writes them."""
    rows, cols = grey.shape
    top = rows - bar_rows
    grey[top:, :] = 0.0
    grey[top:top + 2, :] = 1.0                                 # the frame line
    glyph_h, glyph_w = max(bar_rows // 3, 3), max(bar_rows // 5, 2)
    row0 = top + bar_rows // 3
    col = cols // 40
    for _ in range(12):                                          # "EHT = 5.00 kV  WD = ..."
        glyph = rng.random((glyph_h, glyph_w)) < 0.45
        grey[row0:row0 + glyph_h, col:col + glyph_w][glyph] = 1.0
        col += glyph_w + (glyph_w if rng.random() < 0.8 else 3 * glyph_w)
    grey[row0 + glyph_h // 2:row0 + glyph_h // 2 + 2, -cols // 4:-cols // 20] = 1.0  # scale bar
    return grey


def make_particles(rows, cols, bar_rows, n_particles, radii, gap, matrix, core, rim, rim_width,
                   drift, blur, noise, seed):
    """Grey levels and true particles of a synthetic secondary-electron micrograph.

    Parameters
    ----------
    rows, cols : int
        Image size, pixels, the data bar included.
    bar_rows : int
        Height of the data bar at the bottom, pixels (0: none).
    n_particles : int
        Elliptic particles tried at random places; one that would come
        closer than ``gap`` pixels to another is left out.
    radii : (float, float)
        Range of the semi-axes, pixels (uniform).
    gap : int
        Least distance between particles, pixels.
    matrix, core, rim : float
        Grey levels (fraction of full scale) of the matrix, of a particle's
        centre and of its rim.
    rim_width : float
        Inside a particle the grey level falls from ``rim`` at the edge to
        ``core`` as ``exp(-d / rim_width)``, ``d`` the depth in pixels.
    drift : float
        Linear drift of the matrix's brightness across the field, peak to
        peak (fraction of full scale).
    blur : float
        Gaussian blur, pixels (0: none).
    noise : float
        Standard deviation of the added Gaussian noise, fraction of full scale.
    seed : int
        Seed of :func:`numpy.random.default_rng`.

    Returns
    -------
    grey : ndarray, shape (rows, cols), float
        Grey levels in [0, 1] (not quantised), the data bar included.
    truth : ndarray, shape (rows, cols), int
        1 on a particle, 0 on the matrix, under the data bar too.
    """
    rng = np.random.default_rng(seed)
    truth = np.zeros((rows, cols), dtype=bool)
    taken = np.zeros((rows, cols), dtype=bool)
    reach = int(np.ceil(radii[1])) + gap + 1
    for _ in range(n_particles):
        axes = rng.uniform(*radii, size=2)
        centre = rng.uniform((0.0, 0.0), (rows, cols))
        angle = rng.uniform(0.0, np.pi)
        window = tuple(slice(max(int(x) - reach, 0), min(int(x) + reach + 1, size))
                       for x, size in zip(centre, (rows, cols), strict=True))
        shape = _ellipse(window, centre, axes, angle)
        if not (shape & taken[window]).any():
            truth[window] |= shape
            taken[window] |= ndimage.binary_dilation(shape, iterations=gap)
    depth = ndimage.distance_transform_edt(truth) - 0.5
    inside = core + (rim - core) * np.exp(-depth / rim_width)
    ramp = drift * (np.arange(cols) / max(cols - 1, 1) - 0.5)
    grey = np.where(truth, inside, matrix + ramp[None, :])
    if blur > 0:
        grey = ndimage.gaussian_filter(grey, blur, mode="nearest")
    grey = grey + rng.normal(0.0, noise, grey.shape)
    if bar_rows:
        grey = _data_bar(grey, bar_rows, rng)
    return np.clip(grey, 0.0, 1.0), truth.astype(np.int64)


def write_png(path, grey):
    """Write grey levels in [0, 1] as an 8-bit grey PNG."""
    pixels = np.rint(np.asarray(grey) * 255).astype(np.uint8)
    Image.fromarray(pixels).save(path, optimize=True)  # uint8 2-d: mode "L"


def main(argv=None):
    """Make the image; return the exit status."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-o", "--output", type=pathlib.Path, default=None,
                        help=f"PNG to write (default: OUT/{SHIPPED.name}, or OUT/particles.png "
                             f"with --particles; the shipped one: {SHIPPED})")
    parser.add_argument("--particles", action="store_true",
                        help="the secondary-electron image of particles with a data bar "
                             "(make_particles) instead of the grains")
    study_io.add_output_arguments(parser, docs_figures=False)
    args = parser.parse_args(argv)
    output = args.output or args.out / ("particles.png" if args.particles else SHIPPED.name)
    output.parent.mkdir(parents=True, exist_ok=True)
    if args.particles:
        grey, truth = make_particles(**PARTICLES)
        truth = truth[:PARTICLES["rows"] - PARTICLES["bar_rows"]]
        what = f"above the {PARTICLES['bar_rows']}-row data bar"
    else:
        grey, truth = make_grains(**PARAMS)
        what = "whole image"
    write_png(output, grey)
    fill = np.bincount(truth.ravel(), minlength=2) / truth.size
    print(f"{output}: {grey.shape[1]} x {grey.shape[0]} pixels, true fill factors "
          f"{fill[0]:.4f}, {fill[1]:.4f} ({what})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
