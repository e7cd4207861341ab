"""Agreement of a run's final face with the closed-form steady face (equation 9).

The transient and the steady module reach the same limiting face by two
independent routes (time integration of the contact problem against the
closed form of eq. 7 and 9); :func:`compare_with_steady` measures how well
they agree: the face's shape, the phase pressures and the friction proxy,
the run's converged rms slope (:mod:`transient.history`) against the steady
module's corrected one, each with its error bar.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from steady.rms_slope import estimate_map_rms_slope
from steady.solution import solve_scene

from .diagnostics import face_rms_slope
from .history import FaceEstimator

__all__ = ["SteadyComparison", "compare_with_steady", "steady_of_run"]


@dataclasses.dataclass(frozen=True)
class SteadyComparison:
    """Agreement of a run's final face with the closed-form steady face (eq. 9).

    Attributes
    ----------
    face_error : float
        ``max |(d - w) + c - f_inf| / relief(f_inf)`` over the face, ``c`` the
        best (minimax) constant, relief = max - min of ``f_inf``.
    face_rms_error : float
        Rms of the same difference with the least-squares constant, / relief.
    rms_slope, rms_slope_uncertainty : float
        The run's final rms slope, the converged estimate the history
        records (:class:`transient.history.FaceEstimator`), and its error
        bar.
    steady_rms_slope, steady_rms_slope_uncertainty : float
        The steady face's corrected rms slope and its error bar: those of
        the steady result when it carries them
        (:func:`steady.solution.solve_scene`), else the corrected estimate
        on its grid with the error of its own map's ladder
        (:func:`steady.rms_slope.estimate_map_rms_slope`).
    rms_slope_error : float
        ``rms_slope / steady_rms_slope - 1``.
    rms_slope_agrees : bool
        ``|rms_slope - steady_rms_slope|`` is within the sum of the two error
        bars.  Where either bar is not finite (no error could be estimated:
        :attr:`rms_slope_compared` is False) it is True: nothing bounds
        the difference, so no disagreement is claimed, and :meth:`summary`
        says "no error bar" rather than "within".
    rms_slope_plain, steady_rms_slope_plain : float
        Plain pixel rms slopes of the run's face and of ``f_inf`` (exact
        kernel gradient at the pixel centres of the face): the same
        definition on both sides, equal to round-off when the run has
        converged.
    rms_height, steady_rms_height : float, m
        Rms heights of the run's face and of ``f_inf`` about their
        least-squares planes.
    phase_pressures, steady_phase_pressures : ndarray, shape (P,), Pa
        Mean pressure on each phase, run and eq. 7.
    phase_pressure_error : float
        ``max_i |p_i / p_i,steady - 1|``.
    """

    face_error: float
    face_rms_error: float
    rms_slope: float
    rms_slope_uncertainty: float
    steady_rms_slope: float
    steady_rms_slope_uncertainty: float
    rms_slope_error: float
    rms_slope_agrees: bool
    rms_slope_plain: float
    steady_rms_slope_plain: float
    rms_height: float
    steady_rms_height: float
    phase_pressures: np.ndarray
    steady_phase_pressures: np.ndarray
    phase_pressure_error: float

    @property
    def rms_slope_compared(self):
        """Whether both rms slopes carry a finite error bar, so that they can be compared."""
        return bool(math.isfinite(self.rms_slope_uncertainty)
                    and math.isfinite(self.steady_rms_slope_uncertainty))

    def summary(self):
        """One line per figure, for the terminal."""
        pp = ", ".join(f"{a:.6g}/{b:.6g}" for a, b in
                       zip(self.phase_pressures, self.steady_phase_pressures, strict=True))
        if not self.rms_slope_compared:
            missing = [name for name, bar in (("the run's", self.rms_slope_uncertainty),
                                              ("the steady", self.steady_rms_slope_uncertainty))
                       if not math.isfinite(bar)]
            verdict = (f"no error bar: {' and '.join(missing)} discretisation error could not "
                       f"be estimated, not compared")
        else:
            verdict = ("within the error bars" if self.rms_slope_agrees
                       else "OUTSIDE the error bars")
        return (f"face shape error (max, / steady relief): {self.face_error:.3e}\n"
                f"face shape error (rms, / steady relief): {self.face_rms_error:.3e}\n"
                f"rms slope: {self.rms_slope:.6g} +- {self.rms_slope_uncertainty:.2g} vs steady "
                f"{self.steady_rms_slope:.6g} +- {self.steady_rms_slope_uncertainty:.2g} "
                f"(relative {self.rms_slope_error:+.3e}, {verdict})\n"
                f"rms slope, plain pixel: {self.rms_slope_plain:.6g} vs steady "
                f"{self.steady_rms_slope_plain:.6g}\n"
                f"rms height: {self.rms_height:.6g} m vs steady {self.steady_rms_height:.6g} m\n"
                f"phase pressures (run/steady, Pa): {pp} "
                f"(max relative {self.phase_pressure_error:.3e})")


def compare_with_steady(result, steady, problem):
    """Compare a run's face with the steady face.

    Parameters
    ----------
    result : transient.result.RunResult
    steady : steady.solution.SteadyResult
        For the same grid, phases, wear coefficients, force and exponent
        (:func:`steady.solution.solve` on ``problem.halfspace`` and
        ``problem.labels``, e.g. ``problem.solve_steady()``, or
        :func:`steady.solution.solve_scene` with its error bar).
    problem : transient.problem.WearProblem
        The problem the run solved.

    Returns
    -------
    SteadyComparison
    """
    labels = problem.labels
    face_mask = problem.face_mask
    fin = steady.face[face_mask]
    ft = result.face[face_mask]
    diff = ft - fin
    relief = float(fin.max() - fin.min())
    mid = 0.5 * (diff.max() + diff.min())
    face_error = float(np.max(np.abs(diff - mid)) / relief)
    face_rms = float(np.sqrt(np.mean((diff - diff.mean()) ** 2)) / relief)
    recession = np.where(face_mask, result.recession, 0.0)
    plain = face_rms_slope(problem.halfspace, face_mask, recession, result.pressure,
                           result.approach, periodic=problem.outline.periodic)
    estimator = FaceEstimator.of(problem, np.where(face_mask, result.initial_recession, 0.0))
    # A state a jump reached is the steady face at no particular distance: its rim layer is
    # fully worn (the distance of the history's end would measure it as barely worn, or, for a
    # jump at s = 0, as the initial face).
    jumped = result.state.jumps > 0 and result.status == "steady"
    final = estimator.figures(math.inf if jumped else result.distance, recession, result.pressure,
                              result.approach)
    if math.isfinite(steady.rms_slope_error):
        steady_rms, steady_error = float(steady.rms_slope), float(steady.rms_slope_error)
    else:
        estimate = estimate_map_rms_slope(steady.labels, problem.wear, steady.normal_force,
                                          steady.outline, steady.E_star,
                                          energy=estimator.energy)
        steady_rms, steady_error = estimate.rms_slope, estimate.error
    rms, error = final["rms_slope"], final["rms_slope_error"]
    n_phases = len(steady.phase_pressures)
    pp = np.array([result.pressure[labels == i].mean() for i in range(n_phases)])
    return SteadyComparison(
        face_error=face_error, face_rms_error=face_rms,
        rms_slope=rms, rms_slope_uncertainty=error,
        steady_rms_slope=steady_rms, steady_rms_slope_uncertainty=steady_error,
        rms_slope_error=rms / steady_rms - 1.0,
        # No finite bar (none could be estimated) bounds nothing: no disagreement.
        rms_slope_agrees=bool(abs(rms - steady_rms) <= error + steady_error
                              or not (math.isfinite(error) and math.isfinite(steady_error))),
        rms_slope_plain=plain, steady_rms_slope_plain=float(steady.rms_slope_plain),
        rms_height=final["rms_height"], steady_rms_height=float(steady.rms_height),
        phase_pressures=pp, steady_phase_pressures=np.asarray(steady.phase_pressures),
        phase_pressure_error=float(np.max(np.abs(pp / steady.phase_pressures - 1.0))))


def steady_of_run(scene, problem, initial_recession):
    """The steady result of ``runin-steady`` for a run's scene, on the run's own problem.

    :func:`steady.solution.solve_scene` with its error bar, on the run's
    phase map and operator (neither rasterised nor built a second time)
    and, for a columnar map under uniform sliding, with the ladder of the
    phase geometry that the run's :class:`transient.history.FaceEstimator`
    computed for its ``map_error``
    (:attr:`~transient.history.FaceEstimator.geometry_estimate`): the same
    ladder, so the same result as ``solve_scene`` computing it again.

    Parameters
    ----------
    scene : steady.scene.Scene
        The scene the problem was built from
        (:func:`transient.scene.wear_problem_of`, its grid).
    problem : transient.problem.WearProblem
    initial_recession : ndarray, shape (nx, ny), m
        The run's initial face (its estimator is shared, see
        :meth:`transient.history.FaceEstimator.of`).

    Returns
    -------
    steady.solution.SteadyResult
    """
    estimator = FaceEstimator.of(problem, initial_recession)
    shared = estimator.geometry_estimate if problem.problem.sliding is None else None
    return solve_scene(scene, problem=problem.problem, estimate=shared)
