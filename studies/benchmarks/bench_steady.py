"""Speed and accuracy of the steady solver.

Speed: the steady face solve (eq. 7 pressures, eq. 9 face, exact slope field;
``solve(..., face_only=True)``) timed cold (spectra built) and warm (spectra
cached) side by side with one zero-padded real FFT pair of the same grid
(``rfft2`` + ``irfft2`` of a ``2n x 2n`` array), with the peak memory of a
process doing the solve.

Accuracy: the eq. 10 face and the homogeneous rms slope against their
closed forms, and the rms slope of Voronoi maps (plain pixel estimate and
energy-corrected estimate of :mod:`steady.rms_slope`, with its error bar)
against a fine-grid reference.

Run::

    python studies/benchmarks/bench_steady.py            # about 4 minutes
    python studies/benchmarks/bench_steady.py --quick    # a few seconds

Prints Markdown tables.
"""

import argparse
import json
import platform
import resource
import subprocess
import sys
import time

import numpy as np
import scipy.fft

SPEED_GRIDS = [256, 512, 1024, 2048]
ACCURACY_GRIDS = [128, 256, 512, 1024]
REFERENCE_GRID = 2048
SEEDS = [20**2, 160**2]
REPEATS = 5


def _best(fn, repeats):
    best = np.inf
    for _ in range(repeats):
        t = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t)
    return best


def speed_one(n, repeats):
    """Timings for one grid, run in a fresh process (for its peak memory)."""
    from steady.outline import Circle
    from steady.phases import Voronoi
    from steady.problem import FacePhases, Problem
    from steady.solution import solve

    radius, E_star, force = 0.004, 1.3e6, 10.0
    grid = Circle(radius).grid(n)
    labels = Voronoi(20**2, (0.5, 0.5), 2024).labels(grid)
    k = [1e-9, 1e-8]
    padded = np.zeros((2 * n, 2 * n))
    padded[:n, :n] = labels >= 0

    def fft_pair():
        scipy.fft.irfft2(scipy.fft.rfft2(padded, workers=-1), s=padded.shape, workers=-1)

    fft_pair()
    t_pair = _best(fft_pair, repeats)
    t0 = time.perf_counter()
    problem = Problem(FacePhases(grid, labels, 2), k, force, E_star)
    solve(problem, face_only=True)  # builds the half-space operator, kept by the problem
    t_cold = time.perf_counter() - t0
    t_warm = _best(lambda: solve(problem, face_only=True), repeats)
    t_pair2 = _best(fft_pair, repeats)  # again, after: the machine may drift
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20  # KiB -> GiB
    return dict(n=n, pair=min(t_pair, t_pair2), cold=t_cold, warm=t_warm, peak_gib=peak)


def speed(grids, repeats):
    """Print the speed table, one fresh process per grid (:func:`speed_one`).

    Parameters
    ----------
    grids : sequence of int
        Grid sizes.
    repeats : int
        Timings per figure; the best is kept.
    """
    rows = []
    for n in grids:
        out = subprocess.run([sys.executable, __file__, "--speed-one", str(n), "--repeats",
                              str(repeats)], check=True, capture_output=True, text=True)
        rows.append(json.loads(out.stdout))
    print("| n | FFT pair (ms) | warm solve (ms) | warm / pair | cold solve (ms) | cold / pair "
          "| peak memory (GiB) |")
    print("|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['n']} | {1e3 * r['pair']:.1f} | {1e3 * r['warm']:.1f} | "
              f"{r['warm'] / r['pair']:.2f} | {1e3 * r['cold']:.1f} | "
              f"{r['cold'] / r['pair']:.2f} | {r['peak_gib']:.2f} |")


def _steady_homogeneous(n):
    from steady import reference
    from steady.outline import UNIT_DISK
    from steady.phases import Homogeneous
    from steady.problem import FacePhases, Problem
    from steady.solution import solve

    grid = UNIT_DISK.grid(n)
    res = solve(Problem(FacePhases(grid, Homogeneous().labels(grid), 1), [1.0], np.pi, 1.0),
                face_only=True)
    r = grid.radii
    exact = reference.disk_face(r, 1.0, 1.0, 1.0)
    on = ~np.isnan(res.face)
    relief = np.nanmax(exact) - np.nanmin(exact)
    face_err = np.max(np.abs(res.face[on] - exact[on])) / relief
    return face_err, res.normalised_rms_slope_plain


def accuracy(grids, reference_grid, seeds):
    """Print the accuracy tables: eq. 10 cylinder, then Voronoi maps against a fine grid.

    Parameters
    ----------
    grids : sequence of int
        Grid sizes of the tables.
    reference_grid : int
        Grid of the Voronoi reference (corrected estimate).
    seeds : sequence of int
        Voronoi seed counts, one table each.
    """
    from steady import reference
    from steady.phases import Homogeneous, Voronoi
    from steady.rms_slope import estimate_rms_slope

    g0 = 4 / np.pi
    exact = reference.disk_normalised_rms_slope()
    print("Homogeneous cylinder (eq. 10): face error (max over the face / relief), rms slope "
          "error (plain pixel estimate, corrected estimate, reported error bar), "
          "in units of grad_f0.\n")
    print("| n | face error | plain rms error | corrected rms error | reported error bar |")
    print("|---|---|---|---|---|")
    orders = []
    for n in grids:
        face_err, plain = _steady_homogeneous(n)
        est = estimate_rms_slope(Homogeneous(), [1.0], np.pi, 1.0, 1.0, n)
        orders.append(face_err)
        print(f"| {n} | {face_err:.2e} | {plain - exact:+.2e} | "
              f"{est.rms_slope / g0 - exact:+.2e} | {est.error / g0:.2e} |")
    slope = -np.polyfit(np.log(grids), np.log(orders), 1)[0]
    print(f"\nFace error order (log-log fit): {slope:.2f}\n")

    for s in seeds:
        geo = Voronoi(s, (0.5, 0.5), 4321)
        ref = estimate_rms_slope(geo, [1.0, 10.0], np.pi, 1.0, 1.0, reference_grid)
        print(f"Voronoi, {int(round(np.sqrt(s)))}^2 seeds, rho_2 = 0.5, k_2/k_1 = 10, "
              f"seed 4321; reference: corrected at n = {ref.grids[-1]}, "
              f"{ref.rms_slope / g0:.5f} +- {ref.error / g0:.1e} grad_f0.\n")
        print("| n | plain | plain error | grids solved | corrected | corrected error "
              "| reported error bar |")
        print("|---|---|---|---|---|---|---|")
        for n in grids:
            try:
                geo.check_grid(n)
            except ValueError:
                continue
            est = estimate_rms_slope(geo, [1.0, 10.0], np.pi, 1.0, 1.0, n)
            print(f"| {n} | {est.rms_slope_plain / g0:.4f} | "
                  f"{est.rms_slope_plain / ref.rms_slope - 1:+.2%} | "
                  f"{', '.join(map(str, est.grids))} | {est.rms_slope / g0:.4f} | "
                  f"{est.rms_slope / ref.rms_slope - 1:+.3%} | "
                  f"{est.error / ref.rms_slope:.3%} |")
        print()


def main():
    """Command line of the benchmark (see the module docstring)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="small grids only")
    parser.add_argument("--speed-one", type=int, help=argparse.SUPPRESS)
    parser.add_argument("--repeats", type=int, default=REPEATS, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.speed_one:
        print(json.dumps(speed_one(args.speed_one, args.repeats)))
        return
    print(f"Machine: {platform.processor() or platform.machine()}, "
          f"python {platform.python_version()}, numpy {np.__version__}, "
          f"scipy {scipy.__version__}\n")
    if args.quick:
        speed([64, 128], 2)
        print()
        accuracy([64, 128], 256, [20**2])
    else:
        speed(SPEED_GRIDS, REPEATS)
        print()
        accuracy(ACCURACY_GRIDS, REFERENCE_GRID, SEEDS)


if __name__ == "__main__":
    main()
