"""Run-in wear of a multi-phase punch on an elastic half-space, step by step.

From an initial face, the punch wears by the local law ``dw/ds = k_i p^m``
while the contact pressure follows the worn shape, until the wear rates
equalise and the face reaches the steady state of :mod:`steady`.  Modules:

- :mod:`transient.contact` -- unilateral contact under load control (also
  the implicit wear step, with a diagonal shift);
- :mod:`transient.preconditioners` -- preconditioners of the contact solver;
- :mod:`transient.initial_face` -- initial face shapes;
- :mod:`transient.stepping` -- the registered time integrators;
- :mod:`transient.runin` -- the run loop, steady-state detection, history,
  checkpoints and the comparison with the steady face;
- :mod:`transient.scene` -- the ``[transient]`` and ``[initial_face]`` scene sections.
"""

from .contact import PRECONDITIONERS, ContactResult, solve_contact
from .initial_face import crowned, flat, from_array, from_file, tilted
from .preconditioners import (
    AMGPreconditioner,
    FourierPreconditioner,
    JacobiPreconditioner,
    influence_quadrant,
    influence_symbol,
)
from .runin import (
    FORMAT,
    HISTORY_UNITS,
    VERSION,
    RunOptions,
    RunResult,
    SteadyComparison,
    compare_with_steady,
    face_rms_slope,
    read_run,
    run_in,
    wear_rate_spread,
    write_run,
)
from .scene import (
    InitialFace,
    TransientSettings,
    initial_height,
    load_transient_scene,
    parse_initial_face,
    parse_transient,
)
from .stepping import (
    BDF2,
    SCHEMES,
    SDIRK2,
    ExplicitEuler,
    ImplicitEuler,
    Scheme,
    StepFailure,
    StepState,
    Trial,
    WearProblem,
    get_scheme,
    register_scheme,
)

__all__ = [
    "AMGPreconditioner",
    "BDF2",
    "ContactResult",
    "ExplicitEuler",
    "FORMAT",
    "FourierPreconditioner",
    "HISTORY_UNITS",
    "ImplicitEuler",
    "InitialFace",
    "JacobiPreconditioner",
    "PRECONDITIONERS",
    "RunOptions",
    "RunResult",
    "SCHEMES",
    "SDIRK2",
    "Scheme",
    "SteadyComparison",
    "StepFailure",
    "StepState",
    "TransientSettings",
    "Trial",
    "VERSION",
    "WearProblem",
    "compare_with_steady",
    "crowned",
    "face_rms_slope",
    "flat",
    "from_array",
    "from_file",
    "get_scheme",
    "influence_quadrant",
    "influence_symbol",
    "initial_height",
    "load_transient_scene",
    "parse_initial_face",
    "parse_transient",
    "read_run",
    "register_scheme",
    "run_in",
    "solve_contact",
    "tilted",
    "wear_rate_spread",
    "write_run",
]
