"""The face mask of a road-aggregate chip: an irregular, star-shaped outline.

Makes ``steady/examples/aggregate_chip_mask.npy``, the outline of the shipped
scene ``steady/examples/aggregate_chip.toml`` (``[punch] shape = "mask"``): a
12 x 9 mm box of 0.125 mm pixels (96 x 72, x along axis 0) holding the
polished face of a crushed stone, the region inside the closed curve
``r(theta) = R (1 + sum_k a_k cos(k theta + phi_k))`` about the box centre
(``R = 3.6 mm`` stretched 1.3 times along x, harmonics ``k = 2..6`` with
random amplitudes ``a_k`` falling as ``1/k`` and random phases, fixed
seed).  ``True`` marks the face.

Run::

    python studies/make_face_mask.py          # about a second: OUT/aggregate_chip_mask.npy
    python studies/make_face_mask.py -o steady/examples/aggregate_chip_mask.npy  # the shipped one

The mask is a pure function of the parameters below (the seed included).
"""

import argparse
import pathlib
import sys

import numpy as np
import study_io

#: The file as shipped with the package (``-o`` writes it there).
SHIPPED = (pathlib.Path(__file__).resolve().parents[1] / "steady" / "examples"
           / "aggregate_chip_mask.npy")

#: Box (pixels along x and y), pixel size (mm), mean radius (mm), stretch along
#: x, harmonics, amplitude of the second harmonic, seed.
PARAMS = {"nx": 96, "ny": 72, "pixel": 0.125, "radius": 3.6, "stretch": 1.3,
          "harmonics": (2, 3, 4, 5, 6), "amplitude": 0.12, "seed": 6271}


def make_mask(nx, ny, pixel, radius, stretch, harmonics, amplitude, seed):
    """Boolean chip mask, shape (nx, ny): ``True`` where a pixel centre lies on the face."""
    rng = np.random.default_rng(seed)
    x = (np.arange(nx) + 0.5 - 0.5 * nx) * pixel
    y = (np.arange(ny) + 0.5 - 0.5 * ny) * pixel
    X, Y = np.meshgrid(x / stretch, y, indexing="ij")
    theta = np.arctan2(Y, X)
    outline = np.ones_like(theta)
    for k in harmonics:
        a = amplitude * 2.0 / k * rng.uniform(0.5, 1.0)
        outline += a * np.cos(k * theta + rng.uniform(0.0, 2.0 * np.pi))
    return np.hypot(X, Y) < radius * outline


def main(argv=None):
    """Write the mask (``--out`` or ``-o`` for another place)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-o", "--output", type=pathlib.Path, default=None,
                        help=f"file to write (default: OUT/{SHIPPED.name}; the shipped one: "
                             f"{SHIPPED})")
    study_io.add_output_arguments(parser, docs_figures=False)
    args = parser.parse_args(argv)
    output = args.output or args.out / SHIPPED.name
    output.parent.mkdir(parents=True, exist_ok=True)
    mask = make_mask(**PARAMS)
    np.save(output, mask)
    print(f"{output}: {mask.shape[0]} x {mask.shape[1]} pixels, "
          f"{int(mask.sum())} on the face ({mask.mean():.1%})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
