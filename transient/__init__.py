"""Run-in wear of a multi-phase punch on an elastic half-space, step by step.

From an initial face, the punch wears by the local law ``dw/ds = k_i p^m``
while the contact pressure follows the worn shape, until the wear rates
equalise and the face reaches the steady state of :mod:`steady`.  Modules:

- :mod:`transient.contact` -- unilateral contact under load control (also
  the implicit wear step, with a diagonal shift);
- :mod:`transient.preconditioners` -- registered preconditioners of the
  contact solver;
- :mod:`transient.initial_face` -- registered initial face shapes;
- :mod:`transient.problem` -- the discretised wear problem and its factory
  from a scene;
- :mod:`transient.stepping` -- the registered time integrators;
- :mod:`transient.control` -- step control and stop tests;
- :mod:`transient.diagnostics` -- what the history records of the face;
- :mod:`transient.runin` -- the run loop, its result and the state a
  resumed run needs, history and checkpoints;
- :mod:`transient.comparison` -- agreement with the steady face;
- :mod:`transient.output` -- HDF5 run files;
- :mod:`transient.options` -- the run options, each declared once for the
  library, the scene and the command line;
- :mod:`transient.scene` -- the ``[transient]`` and ``[initial_face]`` scene
  sections;
- :mod:`transient.memory` -- the memory a run-in needs;
- :mod:`transient.plotting` -- figures of run files (imported on demand: it
  loads matplotlib).

The command ``runin-transient`` (``python -m transient``,
:mod:`transient.__main__`) runs the run-in of a scene file.
"""

from .comparison import SteadyComparison, compare_with_steady
from .contact import ContactResult, solve_contact
from .control import StepController, StopTests
from .diagnostics import face_rms_slope, wear_rate_spread
from .initial_face import (
    INITIAL_FACES,
    crowned,
    flat,
    from_array,
    from_file,
    initial_height,
    tilted,
)
from .options import RunOptions
from .output import FORMAT, FORMAT_VERSION, read_run, write_run
from .preconditioners import (
    PRECONDITIONERS,
    AMGPreconditioner,
    FourierPreconditioner,
    JacobiPreconditioner,
    make_preconditioner,
    register_preconditioner,
)
from .problem import StepFailure, WearProblem
from .runin import HISTORY_UNITS, RunResult, RunState, run_in
from .scene import (
    InitialFace,
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
    StepState,
    Trial,
    get_scheme,
    register_scheme,
)

__all__ = [
    "AMGPreconditioner",
    "BDF2",
    "ContactResult",
    "ExplicitEuler",
    "FORMAT",
    "FORMAT_VERSION",
    "FourierPreconditioner",
    "HISTORY_UNITS",
    "INITIAL_FACES",
    "ImplicitEuler",
    "InitialFace",
    "JacobiPreconditioner",
    "PRECONDITIONERS",
    "RunOptions",
    "RunResult",
    "RunState",
    "SCHEMES",
    "SDIRK2",
    "Scheme",
    "SteadyComparison",
    "StepController",
    "StepFailure",
    "StepState",
    "StopTests",
    "Trial",
    "WearProblem",
    "compare_with_steady",
    "crowned",
    "face_rms_slope",
    "flat",
    "from_array",
    "from_file",
    "get_scheme",
    "initial_height",
    "load_transient_scene",
    "make_preconditioner",
    "parse_initial_face",
    "parse_transient",
    "read_run",
    "register_preconditioner",
    "register_scheme",
    "run_in",
    "solve_contact",
    "tilted",
    "wear_rate_spread",
    "write_run",
]
