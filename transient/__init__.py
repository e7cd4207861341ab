"""Run-in wear of a multi-phase punch on an elastic half-space, step by step.

From an initial face, the punch wears by the local law ``dw/ds = k_i p^m``
while the contact pressure follows the worn shape, until the wear rates
equalise and the face reaches the steady state of :mod:`steady`.  Modules, by
the floors they stand on, from the bottom up (``FLOORS`` in
tests/test_layers.py):

- contact: :mod:`transient.contact` -- unilateral contact under load control
  (also the implicit wear step, with a diagonal shift);
  :mod:`transient.preconditioners` -- its registered preconditioners;
  :mod:`transient.depth` -- the worn depth as a function of the wear work,
  across interfaces; :mod:`transient.initial_face` -- registered initial
  faces; :mod:`transient.axisymmetric` -- the axisymmetric run-in of the
  homogeneous and the coated cylinder, the references of the history;
  :mod:`transient.memory` -- the memory a run-in needs;
- :mod:`transient.problem` -- the discretised wear problem, fixed data;
- stepping: :mod:`transient.solver` -- the stage solver, the contact solves
  of a run and the state they carry; :mod:`transient.warm_start` -- the
  warm start of its implicit stages; :mod:`transient.stepping` -- the
  registered time integrators; :mod:`transient.control` -- step control and
  stop tests; :mod:`transient.options` -- the run options, each declared
  once for the library, the scene and the command line;
- :mod:`transient.scene` -- the ``[transient]`` and ``[initial_face]`` scene
  sections, and the factory ``wear_problem_of``;
- history: :mod:`transient.diagnostics` -- what the history records of the
  face; :mod:`transient.history` -- the friction proxy along the run: the
  rms slope with its error bar, the rms height;
- the run: :mod:`transient.runin` -- the loop and its checkpoints;
  :mod:`transient.recording` -- the history and snapshots it records;
  :mod:`transient.result` -- its result and the state a resumed run needs;
  :mod:`transient.run_in_distance` -- the run-in distance within a
  tolerance of the steady state, with its uncertainty;
- comparisons: :mod:`transient.comparison` -- agreement with the steady
  face; :mod:`transient.spatial_error` -- the history's spatial error bar
  from the same run on a coarser grid;
- run files and figures: :mod:`transient.output` -- HDF5 run files;
  :mod:`transient.plotting` -- figures of run files (imported on demand: it
  loads matplotlib).

The command ``runin-transient`` (``python -m transient``,
:mod:`transient.__main__`) runs the run-in of a scene file.
``transient.__version__`` is the installed version (:mod:`transient.version`, which
reads :mod:`steady.version`).

The names below are imported from their modules on first use, so that
``import transient`` is quick: the command installs its Ctrl-C handling
before numpy, scipy and h5py load (:mod:`steady.cli.entry`).
"""

from steady.lazy import lazy_names

#: Public names and the module of each.
_MODULE_OF = {
    "__version__": "version",
    "BDF2": "stepping",
    "ContactResult": "contact",
    "ExplicitEuler": "stepping",
    "FORMAT": "output",
    "FORMAT_VERSION": "output",
    "FourierPreconditioner": "preconditioners",
    "HISTORY_UNITS": "result",
    "INITIAL_FACES": "initial_face",
    "ImplicitEuler": "stepping",
    "InitialFace": "scene",
    "JacobiPreconditioner": "preconditioners",
    "PRECONDITIONERS": "preconditioners",
    "RunInDistance": "run_in_distance",
    "RunOptions": "options",
    "RunResult": "result",
    "RunState": "result",
    "SCHEMES": "stepping",
    "SDIRK2": "stepping",
    "Scheme": "stepping",
    "SteadyComparison": "comparison",
    "StepController": "control",
    "StageSolver": "solver",
    "StepFailure": "solver",
    "StepState": "stepping",
    "StopTests": "control",
    "Trial": "stepping",
    "WarmStart": "warm_start",
    "WearProblem": "problem",
    "compare_with_steady": "comparison",
    "crowned": "initial_face",
    "face_rms_slope": "diagnostics",
    "flat": "initial_face",
    "from_array": "initial_face",
    "from_file": "initial_face",
    "get_scheme": "stepping",
    "initial_recession": "initial_face",
    "load_transient_scene": "scene",
    "make_preconditioner": "preconditioners",
    "parse_initial_face": "scene",
    "parse_transient": "scene",
    "read_run": "output",
    "register_preconditioner": "preconditioners",
    "register_scheme": "stepping",
    "run_in": "runin",
    "solve_contact": "contact",
    "tilted": "initial_face",
    "wear_problem_of": "scene",
    "wear_rate_spread": "diagnostics",
    "write_run": "output",
}

__all__ = sorted(name for name in _MODULE_OF if not name.startswith("_"))


__getattr__, __dir__ = lazy_names(__name__, _MODULE_OF)
