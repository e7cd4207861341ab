"""Agreement of a run's final face with the closed-form steady face (eq. 9).

The transient and the steady module reach the same limiting face by two
independent routes (time integration of the contact problem against the
closed form of eq. 7 and 9); :func:`compare_with_steady` measures how well
they agree.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from .diagnostics import face_rms_slope

__all__ = ["SteadyComparison", "compare_with_steady"]


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
    rms_slope, steady_rms_slope : float
        Plain pixel rms slopes of the run's face and of ``f_inf`` (exact kernel
        gradient at the pixel centres of the face).
    rms_slope_error : float
        ``rms_slope / steady_rms_slope - 1``.
    phase_pressures, steady_phase_pressures : ndarray, shape (P,), Pa
        Mean pressure on each phase, run and eq. 7.
    phase_pressure_error : float
        ``max_i |p_i / p_i,steady - 1|``.
    """

    face_error: float
    face_rms_error: float
    rms_slope: float
    steady_rms_slope: float
    rms_slope_error: float
    phase_pressures: np.ndarray
    steady_phase_pressures: np.ndarray
    phase_pressure_error: float

    def summary(self):
        """One line per figure, for the terminal."""
        pp = ", ".join(f"{a:.6g}/{b:.6g}" for a, b in
                       zip(self.phase_pressures, self.steady_phase_pressures, strict=True))
        return (f"face shape error (max, / steady relief): {self.face_error:.3e}\n"
                f"face shape error (rms, / steady relief): {self.face_rms_error:.3e}\n"
                f"rms slope: {self.rms_slope:.6g} vs steady {self.steady_rms_slope:.6g} "
                f"(relative {self.rms_slope_error:+.3e})\n"
                f"phase pressures (run/steady, Pa): {pp} "
                f"(max relative {self.phase_pressure_error:.3e})")


def compare_with_steady(result, steady, problem):
    """Compare a run's face with the steady face.

    Parameters
    ----------
    result : transient.runin.RunResult
    steady : steady.solution.SteadyResult
        For the same grid, phases, wear coefficients, force and exponent
        (:func:`steady.solution.solve` on ``problem.halfspace`` and
        ``problem.labels``).
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
    rms = face_rms_slope(problem.halfspace, face_mask, np.where(face_mask, result.height, 0.0),
                         result.pressure, result.approach)
    # The plain pixel rms slope: the definition the run measures (``rms_slope``
    # of a steady result may be the corrected continuum estimate).
    steady_rms = float(steady.rms_slope_plain)
    n_phases = len(steady.phase_pressures)
    pp = np.array([result.pressure[labels == i].mean() for i in range(n_phases)])
    return SteadyComparison(
        face_error=face_error, face_rms_error=face_rms, rms_slope=rms,
        steady_rms_slope=steady_rms,
        rms_slope_error=rms / steady_rms - 1.0,
        phase_pressures=pp, steady_phase_pressures=np.asarray(steady.phase_pressures),
        phase_pressure_error=float(np.max(np.abs(pp / steady.phase_pressures - 1.0))))
