"""Coarse space for the stage solves: deflation and two-level preconditioners, side by side.

What it reproduces
    docs/benchmarks.md, "Coarse space for the stage solves".

    A run-in (the shipped Voronoi scene with only ``n`` changed, the
    homogeneous 1:2 rectangle from flat of ``bench_runin.py --levers``, the
    shipped ``spheres_transient`` across interfaces) runs as shipped; every
    stage solve it makes (a contact solve with a shift and an absolute
    tolerance) is solved again, from the same inputs and to the same
    tolerance in the same norm, by each variant of the preconditioner below,
    the variants alternated solve by solve so that a loaded machine weighs on
    them alike.  The run goes on with the shipped solve's result, so every
    variant meets the same problems (``shipped`` is solved again too, so that
    its CPU time is measured as the others').  Per variant: iterations, products
    (iterations, the first iterate's ``K p`` when not known, and, for a
    fixed coarse space, its ``K Z`` once per run), the solves' CPU time over
    the shipped ones', and the largest pressure difference to the shipped
    solve (in units of the mean pressure).

    Variants (``M`` the shipped preconditioner of the stage, Fourier or
    Jacobi; ``Z`` a few pressures on the active set with zero mean there,
    ``A = K + diag(shift)``, ``E = Z^T A Z`` and ``E^+`` its pseudo-inverse,
    eigenvalues below ``1e-10`` of the largest dropped):

    - ``shipped``: ``M``.
    - ``deflate-history``: A-DEF2 (Tang, Nabben, Vuik & Erlangga 2009,
      ``P^T M + Q`` with ``P^T = I - Z E^+ (A Z)^T`` and ``Q = Z E^+ Z^T``)
      with ``Z`` the differences of the warm start's pressures (the newest
      minus each older one), whose ``K Z`` the warm start holds: the
      directions stay A-orthogonal to the span the Galerkin start already
      resolved; the first iterate is corrected to ``Z^T r = 0`` where that
      keeps the pressure positive (counted).  Free of products; exact only
      where ``Z`` lies on the active set (elsewhere ``M`` alone, counted).
    - ``coarse-additive``: the two-level additive preconditioner
      ``M r + Z Z^T r`` with a fixed ``Z`` of the face: the wear pattern's
      level indicators, five rings of the rim's boundary layer (distance to
      the outline 0-1, 1-2, 2-4, 4-8, 8-16 pixels), the flat punch's rim
      profile ``1 / sqrt(distance)`` and the smooth modes ``x, y, x^2, xy,
      y^2``; ``K Z`` once per run.
    - ``coarse-deflate``: the same ``Z`` in A-DEF2, with the corrected start;
      ``coarse-deflate:phases``, ``:rim``, ``:smooth``: one part of it alone;
      ``coarse-deflate:smooth+quartic``: the smooth modes with the nine
      monomials of degree 3 and 4.
    - ``one-level``: the stitched Fourier preconditioner of a two-level
      wear pattern replaced by one level at the face's mean shift (one FFT
      pair instead of two per application).

    ``--costs``: the coarse work's CPU time at each of ``--sizes`` (the best
    of five calls): per stage, ``A Z`` with ``E^+`` and the corrected start;
    per application, the two-level direction against the shipped
    preconditioner's; one padded product.

How to run
    python studies/benchmarks/bench_coarse_space.py --sizes 256              # ~5 min
    python studies/benchmarks/bench_coarse_space.py --sizes 1024 --cases voronoi \
        --variants coarse-deflate:smooth coarse-deflate:smooth+quartic    # ~4 min
    python studies/benchmarks/bench_coarse_space.py --costs --sizes 256 1024
    python studies/benchmarks/bench_coarse_space.py --sizes 40 --cases voronoi --quick  # smoke

Prints the table in Markdown.
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import functools
import platform
import time
import timeit

import numpy as np
import scipy.ndimage
from bench_runin import INTERFACES_SCENE, SCENE, lever_cases

import transient.solver
from transient.contact import solve_trusted_contact
from transient.preconditioners import FourierPreconditioner, ScaledShift, make_preconditioner
from transient.runin import run_in
from transient.scene import load_transient_scene, wear_problem_of

VARIANTS = ("shipped", "deflate-history", "coarse-additive", "coarse-deflate",
            "coarse-deflate:phases", "coarse-deflate:rim", "coarse-deflate:smooth",
            "coarse-deflate:smooth+quartic", "one-level")
# Eigenvalues of Z^T A Z below this fraction of the largest are dropped (the
# differences of a run's pressures are nearly collinear).
_CUTOFF = 1e-10


def _zero_mean(z, weight, count):
    """``z`` restricted to the set ``weight`` (1/0) with zero mean there (fresh array)."""
    z = z * weight
    z -= (float(np.einsum("ij,ij->", z, weight)) / count) * weight
    return z


def pseudo_inverse(Z, AZ):
    """``E^+`` of ``E = Z^T A Z`` (shape (m, m)), its eigenvalues below ``_CUTOFF`` dropped."""
    E = np.einsum("mn,kn->mk", Z, AZ)
    lam, V = np.linalg.eigh(0.5 * (E + E.T))
    keep = lam > _CUTOFF * lam.max()
    return (V[:, keep] / lam[keep]) @ V[:, keep].T


def stage_operator(Z, KZ, shift, out=None):
    """``A Z = K Z + diag(shift) Z`` (into ``out`` if given) and ``E^+``: a stage's coarse work.

    ``Z``, ``K Z``: shape (m, nx * ny); ``shift``: m/Pa, shape (nx, ny).
    """
    AZ = np.multiply(Z, shift.reshape(1, -1), out=out)
    AZ += KZ
    return AZ, pseudo_inverse(Z, AZ)


class TwoLevel:
    """``M`` with a coarse space ``Z``: A-DEF2 or additive.

    Called as the solver calls a preconditioner, ``z = self(r, active)``:
    ``M r`` restricted to ``active`` with zero mean there, then
    ``- Z E^+ ((A Z)^T M r - Z^T r)`` (A-DEF2: ``P^T M + Q``, which needs no
    particular start) or ``+ Z E^+ Z^T r`` (additive).
    ``Z`` and ``A Z`` (shape (m, nx * ny), C-contiguous: two matrix-vector
    products per application) are given on the face; on an active set that
    does not hold ``Z``'s support the coarse part is skipped (``skipped``
    counts the applications).
    """

    def __init__(self, base, Z, AZ, Einv, support, additive):
        self.base, self.Z, self.AZ, self.Einv = base, Z, AZ, Einv
        self.support, self.additive = support, additive
        self.applied = self.skipped = 0
        self._active, self._holds = None, False

    def __call__(self, residual, active, accurate=False):
        """The two-level direction (Pa) of a gap residual (m) on the set ``active``."""
        base = self.base
        if accurate and hasattr(base, "accurate"):
            z = base.accurate(residual, active)
        else:
            z = base(residual, active)
        if active is not self._active:
            self._active = active
            self._holds = not np.any(self.support & ~active)
            self._weight = active.astype(float)
            self._count = float(np.count_nonzero(active))
        weight = self._weight
        z *= weight
        z -= (float(np.einsum("ij,ij->", z, weight)) / self._count) * weight
        if not self._holds:
            self.skipped += 1
            return z
        self.applied += 1
        flat = z.reshape(-1)
        # einsum rather than BLAS: a threaded BLAS call spins its threads (CPU time) and can
        # cost more than an FFT pair on a loaded machine.
        if self.additive:
            y = self.Einv @ np.einsum("mn,n->m", self.Z, residual.reshape(-1))
            flat += np.einsum("m,mn->n", y, self.Z)
        else:
            # A-DEF2: P^T M r + Q r, P^T = I - Z E^+ (A Z)^T, Q = Z E^+ Z^T.
            y = self.Einv @ (np.einsum("mn,n->m", self.AZ, flat)
                             - np.einsum("mn,n->m", self.Z, residual.reshape(-1)))
            flat -= np.einsum("m,mn->n", y, self.Z)
        return z

    def accurate(self, residual, active):
        """:meth:`__call__` with the base preconditioner's double-precision form."""
        return self(residual, active, accurate=True)


def corrected_start(stage, Z, KZ, Einv, support):
    """The first iterate with ``Z^T r = 0`` (A-DEF2's start), or None if it leaves ``p >= 0``.

    ``stage``: the arguments of the solve (``halfspace``, ``face``,
    ``recession``, ``shift``, ``force``, ``x0``, ``x0_displacement``).
    Returns ``(p, K p, products)``: the solver's own start (``x0`` clipped and
    scaled to the load), moved by ``- Z E^+ Z^T r``.
    """
    hs, face = stage["halfspace"], stage["face"]
    p = np.where(face, stage["x0"], 0.0)
    np.maximum(p, 0.0, out=p)
    c = stage["force"] / (hs.h ** 2 * p.sum())
    products = 0
    if stage["x0_displacement"] is not None and np.array_equal(p, stage["x0"]):
        v = c * stage["x0_displacement"]
    else:
        v = hs.displacement(c * p)
        products = 1
    p = c * p
    active = p > 0
    if np.any(support & ~active):
        return None, None, products
    weight = active.astype(float)
    g = (v + stage["shift"] * p + stage["recession"]) * weight
    g -= (g.sum() / weight.sum()) * weight
    y = Einv @ np.einsum("mn,n->m", Z, g.reshape(-1))
    p1 = p - np.einsum("m,mn->n", y, Z).reshape(p.shape)
    if p1[active].min() <= 0:
        return None, None, products
    return p1, v - np.einsum("m,mn->n", y, KZ).reshape(p.shape), products


#: The parts of the fixed coarse space (see the module docstring).
PARTS = ("phases", "rim", "smooth", "quartic")


def fixed_space(problem):
    """The fixed coarse space's columns by part: ``{part: (Z, K Z)}``, shape (m, nx * ny)."""
    face = problem.face_mask
    hs = problem.halfspace
    weight, count = face.astype(float), float(np.count_nonzero(face))
    field = problem.wear_field
    distance = scipy.ndimage.distance_transform_edt(face)
    ii, jj = np.indices(face.shape, dtype=float)
    x = (ii - ii[face].mean()) / face.shape[0]
    y = (jj - jj[face].mean()) / face.shape[1]
    columns = dict(
        phases=[field == value for value in np.unique(field[face])[1:]],
        rim=[(distance > lo) & (distance <= hi)
             for lo, hi in ((0, 1.5), (1.5, 2.5), (2.5, 4.5), (4.5, 8.5), (8.5, 16.5))]
        + [np.where(face, 1.0 / np.sqrt(np.maximum(distance, 0.5)), 0.0)],
        smooth=[x, y, x * x, x * y, y * y],
        quartic=[x ** i * y ** (d - i) for d in (3, 4) for i in range(d + 1)])
    parts = {}
    for part, cols in columns.items():
        Z = np.stack([_zero_mean(np.asarray(c, float), weight, count).reshape(-1)
                      for c in cols]) if cols else np.empty((0, face.size))
        KZ = np.stack([hs.displacement(z.reshape(face.shape)).reshape(-1) for z in Z]) \
            if len(Z) else np.empty((0, face.size))
        parts[part] = (Z, KZ)
    return parts


def one_level(base, shift, face):
    """The stitched Fourier preconditioner ``base`` with one level, the face's mean shift."""
    if not isinstance(base, FourierPreconditioner) or base.weights is None:
        return base
    return FourierPreconditioner.from_levels(base.halfspace, [float(shift[face].mean())], None)


def variant_parts(variant):
    """The parts of the fixed space a ``coarse-...`` variant takes (all, or its suffix's)."""
    if ":" not in variant:
        return PARTS[:3]
    return tuple(variant.split(":")[1].split("+"))


class Recorder:
    """Every stage solve of a run, solved again by each variant; the counts and times."""

    def __init__(self, problem, variants):
        self.problem = problem
        self.variants = variants
        self.rows = {v: dict(iterations=0, products=0, cpu=0.0, change=0.0, solves=0,
                             coarse_applied=0, coarse_skipped=0, starts_kept=0)
                     for v in variants}
        self.fixed = None
        self._stacks = {}
        if any(v.startswith("coarse") for v in variants):
            t = time.process_time()
            self.fixed = fixed_space(problem)
            cpu = time.process_time() - t
            products = {part: len(Z) for part, (Z, _) in self.fixed.items()}
            for v in variants:
                if v.startswith("coarse"):
                    parts = variant_parts(v)
                    self.rows[v]["products"] += sum(products[part] for part in parts)
                    self.rows[v]["cpu"] += cpu * sum(products[part] for part in parts) \
                        / sum(products.values())

    def spaces(self, solver, shift, variant):
        """``(Z, A Z, K Z, E^+, support)`` of a variant at this stage, or None."""
        if variant == "deflate-history":
            history = solver.warm_start
            if history is None or len(history) < 2:
                return None
            P, KP = np.array(history.pressures()), np.array(history.displacements())
            m = len(P)
            Z = (P[0] - P[1:]).reshape(m - 1, -1)
            KZ = (KP[0] - KP[1:]).reshape(m - 1, -1)
            support, AZ = np.any(Z != 0, axis=0).reshape(shift.shape), None
        else:
            # A fixed space's stacks, its support and the buffer of A Z are built once per
            # run: a stage forms A Z (two passes over the stack) and E.
            cached = self._stacks.get(variant)
            if cached is None:
                parts = [self.fixed[part] for part in variant_parts(variant)]
                Z = np.concatenate([Z for Z, _ in parts])
                KZ = np.concatenate([KZ for _, KZ in parts])
                support = np.any(Z != 0, axis=0).reshape(shift.shape)
                cached = self._stacks[variant] = (Z, KZ, support, np.empty_like(KZ))
            Z, KZ, support, AZ = cached
        if not len(Z):
            return None
        AZ, einv = stage_operator(Z, KZ, shift, out=AZ)
        return Z, AZ, KZ, einv, support

    def solve(self, solver, stage, shipped):
        """Solve ``stage`` by every variant; add to the rows."""
        pbar = self.problem.pixel_mean_pressure
        for variant in self.variants:
            row = self.rows[variant]
            row["solves"] += 1
            t = time.process_time()
            pre, x0, kx0, products = stage["preconditioner"], stage["x0"], \
                stage["x0_displacement"], 0
            if not callable(pre):
                pre = make_preconditioner(pre, stage["halfspace"], stage["face"],
                                          stage["shift"])
            if variant == "shipped":
                pass
            elif variant == "one-level":
                pre = one_level(pre, stage["shift"], stage["face"])
            else:
                spaces = self.spaces(solver, stage["shift"], variant)
                if spaces is not None:
                    Z, AZ, KZ, Einv, support = spaces
                    additive = variant.startswith("coarse-additive")
                    if not additive:
                        p1, v1, products = corrected_start(stage, Z, KZ, Einv, support)
                        if p1 is not None:
                            x0, kx0 = p1, v1
                            row["starts_kept"] += 1
                    pre = TwoLevel(pre, Z, AZ, Einv, support, additive)
            res = solve_trusted_contact(
                stage["halfspace"], stage["face"], stage["recession"], stage["force"],
                shift=stage["shift"], x0=x0, x0_displacement=kx0, rtol=stage["rtol"],
                atol=stage["atol"], norm=stage["norm"], maxiter=stage["maxiter"],
                preconditioner=pre)
            row["cpu"] += time.process_time() - t
            row["iterations"] += res.nit
            row["products"] += res.nit + products + int(kx0 is None)
            if isinstance(pre, TwoLevel):
                row["coarse_applied"] += pre.applied
                row["coarse_skipped"] += pre.skipped
            row["change"] = max(row["change"],
                                float(np.max(np.abs(res.pressure - shipped.pressure))) / pbar)


@contextlib.contextmanager
def recorded(recorder):
    """Every stage solve of :class:`transient.solver.StageSolver` passed to ``recorder``."""
    contact = transient.solver.StageSolver.contact
    captured = {}
    trusted = solve_trusted_contact

    def capturing(halfspace, face_mask, recession, normal_force, **kwargs):
        captured.update(halfspace=halfspace, face=face_mask, recession=recession.copy(),
                        force=normal_force, **kwargs)
        if kwargs.get("x0") is not None:
            captured["x0"] = np.array(kwargs["x0"])
        return trusted(halfspace, face_mask, recession, normal_force, **kwargs)

    def wrapped(self, recession, *, shift=None, x0=None, x0_displacement=None, atol=0.0,
                preconditioner="auto"):
        if shift is None or x0 is None:
            return contact(self, recession, shift=shift, x0=x0,
                           x0_displacement=x0_displacement, atol=atol,
                           preconditioner=preconditioner)
        captured.clear()
        transient.solver.solve_trusted_contact = capturing
        try:
            res = contact(self, recession, shift=shift, x0=x0, x0_displacement=x0_displacement,
                          atol=atol, preconditioner=preconditioner)
        finally:
            transient.solver.solve_trusted_contact = trusted
        stage = dict(captured)
        stage["shift"] = np.asarray(stage["shift"])
        recorder.solve(self, stage, res)
        return res

    transient.solver.StageSolver.contact = wrapped
    try:
        yield recorder
    finally:
        transient.solver.StageSolver.contact = contact


def cases(names, sizes, spheres_n=None):
    """``(n, name, problem, initial recession, options)`` of the cases asked for."""
    for n, name, problem, initial, options in lever_cases(SCENE, sizes):
        if name in names:
            yield n, name, problem, initial, options
    if "spheres" in names:
        scene, options, initial = load_transient_scene(INTERFACES_SCENE)
        options = dataclasses.replace(options, checkpoint_interval=1e9)
        problem = wear_problem_of(scene, n=spheres_n)
        yield max(problem.grid.shape), "spheres", problem, initial.recession(problem.grid), \
            options


def table(names, sizes, variants, quick, spheres_n=None):
    """Rows: one per case and variant."""
    rows = []
    for n, name, problem, initial, options in cases(names, sizes, spheres_n):
        if quick:
            options = dataclasses.replace(options, max_steps=8)
        recorder = Recorder(problem, variants)
        with recorded(recorder):
            result = run_in(problem, initial, options)
        shipped = recorder.rows["shipped"]
        for variant in variants:
            row = dict(recorder.rows[variant], case=name, n=n, variant=variant,
                       steps=result.steps, solves_run=result.solves)
            row["cpu_ratio"] = row["cpu"] / shipped["cpu"] if shipped["cpu"] else np.nan
            row["iterations_ratio"] = row["iterations"] / max(shipped["iterations"], 1)
            rows.append(row)
        print(markdown(rows[-len(variants):]), flush=True)
    return rows


def _best_cpu(call, repeats):
    """The least CPU time (ms) of ``repeats`` calls of ``call()``."""
    return 1e3 * min(timeit.repeat(call, timer=time.process_time, number=1, repeat=repeats))


def _costs_at(problem, variants, repeats):
    """The rows of :func:`cost_table` on one grid."""
    face, hs = problem.face_mask, problem.halfspace
    parts = fixed_space(problem)
    shift = 1e-3 * np.where(face, problem.wear_field, 0.0)
    base = ScaledShift(hs, face, problem.wear_field).preconditioner(1e-3, shift)
    p = face.astype(float)
    residual = np.where(face, np.random.default_rng(0).random(face.shape), 0.0)
    stage = dict(halfspace=hs, face=face, x0=p, x0_displacement=hs.displacement(p),
                 force=problem.normal_force, shift=shift, recession=np.zeros(face.shape))
    product = _best_cpu(lambda: hs.displacement(residual), repeats)
    shipped = _best_cpu(lambda: base(residual, face), repeats)
    rows = []
    for variant in variants:
        if not variant.startswith("coarse-deflate"):
            continue
        Z = np.concatenate([parts[part][0] for part in variant_parts(variant)])
        KZ = np.concatenate([parts[part][1] for part in variant_parts(variant)])
        support = np.any(Z != 0, axis=0).reshape(face.shape)
        AZ, Einv = stage_operator(Z, KZ, shift)
        two_level = TwoLevel(base, Z, AZ, Einv, support, additive=False)
        rows.append(dict(
            n=max(face.shape), variant=variant, m=len(Z),
            gram=_best_cpu(functools.partial(stage_operator, Z, KZ, shift, out=np.empty_like(KZ)),
                           repeats),
            start=_best_cpu(functools.partial(corrected_start, stage, Z, KZ, Einv, support),
                            repeats),
            two_level=_best_cpu(functools.partial(two_level, residual, face), repeats),
            base=shipped, product=product))
    return rows


def cost_table(sizes, variants, repeats=5):
    """CPU time (ms, the best of ``repeats``) of the coarse work against a product, per grid.

    On the Voronoi scene's face at each grid, the stage shift of ``c = 1e-3`` (m/Pa per
    coefficient): per stage, ``A Z`` and ``E^+`` and the corrected start; per application, the
    two-level direction against the shipped preconditioner's; one padded product ``K p``.
    """
    scene, _, _ = load_transient_scene(SCENE)
    rows = []
    for n in sizes:
        rows += _costs_at(wear_problem_of(scene, n=n), variants, repeats)
    return rows


def markdown_costs(rows):
    """The cost table in Markdown."""
    lines = ["| n | space | m | per stage: A Z and E (ms) | corrected start (ms) | "
             "two-level direction (ms) | shipped preconditioner (ms) | padded product (ms) |",
             "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['n']} | {r['variant'].split(':')[-1]} | {r['m']} | "
                     f"{r['gram']:.1f} | {r['start']:.1f} | {r['two_level']:.1f} | "
                     f"{r['base']:.1f} | {r['product']:.1f} |")
    return "\n".join(lines)


def markdown(rows):
    """The table in Markdown."""
    lines = ["| case | n | variant | stage solves | iterations | per solve | products | "
             "iterations / shipped | CPU / shipped | coarse applied, skipped | "
             "corrected starts | largest change / pbar |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(
            f"| {r['case']} | {r['n']} | {r['variant']} | {r['solves']} | {r['iterations']} | "
            f"{r['iterations'] / max(r['solves'], 1):.2f} | {r['products']} | "
            f"{r['iterations_ratio']:.3f} | {r['cpu_ratio']:.2f} | "
            f"{r['coarse_applied']}, {r['coarse_skipped']} | {r['starts_kept']} | "
            f"{r['change']:.1e} |")
    return "\n".join(lines)


def main(argv=None):
    """Run the comparison; return the rows."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[256, 512])
    parser.add_argument("--cases", nargs="+", default=["voronoi", "rectangle", "spheres"],
                        choices=["voronoi", "rectangle", "spheres"])
    parser.add_argument("--variants", nargs="+", default=list(VARIANTS),
                        help=f"variants (default all: {', '.join(VARIANTS)}; coarse-deflate:A+B "
                        f"takes the parts A and B of {', '.join(PARTS)})")
    parser.add_argument("--spheres-n", type=int,
                        help="grid of the spheres case (default: the scene's, 64)")
    parser.add_argument("--costs", action="store_true",
                        help="the coarse work's CPU time per stage and per application instead")
    parser.add_argument("--quick", action="store_true", help="smoke test: a short run")
    args = parser.parse_args(argv)
    variants = ["shipped"] + [v for v in args.variants if v != "shipped"]
    print(f"machine: {platform.processor() or platform.machine()}, numpy {np.__version__}")
    if args.costs:
        rows = cost_table(args.sizes, variants)
        print(markdown_costs(rows))
        return rows
    rows = table(args.cases, args.sizes, variants, args.quick, args.spheres_n)
    print(markdown(rows))
    return rows


if __name__ == "__main__":
    main()
