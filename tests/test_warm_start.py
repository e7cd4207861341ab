"""The warm start of the implicit stages on a grid of several summation blocks.

:class:`transient.warm_start.WarmStart` sums its products block by block
(``transient.problem._BLOCK`` columns at a time); the grids of the other
warm-start tests (tests/test_preconditioners.py) fit in one block.  Here the
grid holds one full block and a partial one.
"""

import numpy as np
import pytest
from conftest import wear_problem

from transient import warm_start as warm_start_module
from transient.warm_start import WarmStart

N = 272  # 73984 pixels: one block of 65536 and a partial one


@pytest.fixture(scope="module")
def history():
    """A wear problem at ``N`` and a history of four pressures (five pushed) carrying one load."""
    assert N * N > warm_start_module._BLOCK, "the grid must span more than one block"
    problem = wear_problem("voronoi", (1.0, 10.0), N)
    rng = np.random.default_rng(15485863)
    history = WarmStart(problem, size=4)
    base = np.where(problem.face_mask, 1e5, 0.0)
    for step in range(5):
        p = base * (1 + 0.01 * step + 1e-3 * rng.random((N, N)))
        history.push(p * base.sum() / p.sum())
    return problem, history, 1e-7 * rng.random((N, N))


@pytest.mark.parametrize("kind", ["shift_scale", "shift", "none"])
def test_prediction_is_galerkin_orthogonal_across_blocks(history, kind):
    # The minimiser of E(x) = x (K + S) x / 2 + x h over the affine span of the
    # pressures held: its gradient less the load's multiplier (the mean over
    # the face) is orthogonal to every difference of pressures held, and x
    # carries the load.  Measured: normalised products up to 1.2e-15, the load
    # kept to 1.5e-14 (no shift; 6e-15 and 9e-16 with one), K x to 2.2e-13 of
    # its peak (the FFT's round-off).
    problem, history, height = history
    face = problem.face_mask
    c = 1e-3 * problem.distance_scale
    shift = {"shift_scale": c * problem.wear_field,
             "shift": 2 * c * problem.wear_field[::-1], "none": 0.0}[kind]
    if kind == "shift_scale":
        x, kx = history.predict(height, shift_scale=c)
    else:
        x, kx = history.predict(height, None if kind == "none" else shift)
    gradient = kx + np.where(face, shift, 0.0) * x + height
    gradient = np.where(face, gradient - gradient[face].mean(), 0.0)
    held = history.pressures()
    for i in range(1, len(held)):
        d = held[i] - held[0]
        product = abs(np.sum(d * gradient)) / (np.linalg.norm(d) * np.linalg.norm(gradient))
        assert product < 1e-13, f"{kind}: gradient not orthogonal to difference {i}: {product:.1e}"
    assert abs(x.sum() / held[0].sum() - 1) < 1e-13, f"{kind}: the prediction changes the load"
    assert np.abs(kx - problem.halfspace.displacement(x)).max() < 1e-12 * np.abs(kx).max(), \
        f"{kind}: K x of the prediction"


def test_history_restored_across_blocks_predicts_bit_for_bit(history):
    # The blocked sums depend only on the pressures held: a history rebuilt from
    # a checkpoint's pressures and displacements repeats every prediction.
    problem, history, height = history
    c = 1e-3 * problem.distance_scale
    first = history.predict(height, shift_scale=c)
    again = WarmStart(problem, size=4, pressures=history.pressures(),
                      displacements=history.displacements())
    for a, b in zip(first, again.predict(height, shift_scale=c), strict=True):
        assert np.array_equal(a, b), "restored history predicts differently"


def test_where_the_rows_lie_changes_no_prediction():
    # The rows held form a ring (a push writes over the oldest), put in order
    # when handed out: two histories of the same pushes, one handed out at
    # irregular times, must predict bit for bit alike and hold the same
    # pressures, newest first.
    n = 33
    problem = wear_problem("voronoi", (1.0, 10.0), n)
    rng = np.random.default_rng(32452843)
    base = np.where(problem.face_mask, 1e5, 0.0)
    pushed = [base * (1 + 0.01 * step + 1e-3 * rng.random((n, n))) for step in range(9)]
    height = 1e-7 * rng.random((n, n))
    c = 1e-3 * problem.distance_scale
    plain, handed = WarmStart(problem, size=4), WarmStart(problem, size=4)
    for step, p in enumerate(pushed):
        plain.push(p)
        handed.push(p)
        if step in (2, 5, 6):
            newest_first = pushed[max(step - 3, 0):step + 1][::-1]
            assert np.array_equal(handed.pressures(), np.array(newest_first)), f"push {step}"
        for a, b in zip(plain.predict(height, shift_scale=c), handed.predict(height, shift_scale=c),
                        strict=True):
            assert np.array_equal(a, b), f"push {step}: the predictions differ"
    assert np.array_equal(plain.pressures(), np.array(pushed[8:4:-1])), "pressures held"
    assert np.array_equal(plain.displacements(), handed.displacements()), "displacements held"
