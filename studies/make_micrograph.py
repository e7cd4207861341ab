"""A synthetic two-phase micrograph: blurred, noisy grains of known phases.

Makes ``steady/examples/micrograph_example.png``, the image of the shipped
scene ``steady/examples/micrograph_steady.toml``: Voronoi grains (nearest of
random seeds), 30 % of them of a bright phase in a darker matrix, seen
through an optical blur (Gaussian, 1.5 pixels) with Gaussian noise of 5 %
of full scale, stored as 8-bit grey levels.  It stands in for an etched
micrograph of a two-phase alloy; the truth it was made from is known, so
the segmentation of :mod:`steady.micrograph` can be checked against it
(``tests/test_micrograph.py``).

Run::

    python studies/make_micrograph.py          # about 2 s: OUT/micrograph_example.png
    python studies/make_micrograph.py -o steady/examples/micrograph_example.png  # the shipped one

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


def write_png(path, grey):
    """Write grey levels in [0, 1] as an 8-bit grey PNG."""
    pixels = np.rint(np.asarray(grey) * 255).astype(np.uint8)
    Image.fromarray(pixels).save(path, optimize=True)  # uint8 2-d: mode "L"


def main(argv=None):
    """Make the image; return the exit status."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-o", "--output", type=pathlib.Path, default=None,
                        help=f"PNG to write (default: OUT/{SHIPPED.name}; the shipped one: "
                             f"{SHIPPED})")
    study_io.add_output_arguments(parser, docs_figures=False)
    args = parser.parse_args(argv)
    output = args.output or args.out / SHIPPED.name
    output.parent.mkdir(parents=True, exist_ok=True)
    grey, truth = make_grains(**PARAMS)
    write_png(output, grey)
    fill = np.bincount(truth.ravel(), minlength=2) / truth.size
    print(f"{output}: {PARAMS['cols']} x {PARAMS['rows']} pixels, true fill factors "
          f"{fill[0]:.4f}, {fill[1]:.4f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
