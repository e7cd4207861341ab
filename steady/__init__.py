"""Limiting worn face of a multi-phase punch on an elastic half-space.

The steady state of run-in wear has a closed form (paper eq. 7, 9): constant
pressure on each phase and the half-space displacement under it.  The face
is a disk (the paper's cylinder) or any other outline.  Modules, from the
bottom floor up:

- :mod:`steady.text`, :mod:`steady.memory` -- message text; memory
  estimates and the memory available;
- :mod:`steady.registry` -- registries of named entries, filled by decorators;
  :mod:`steady.schema` -- declarative scene keys and the registries of kinds;
- :mod:`steady.halfspace` -- the elastic half-space operator (eq. 8);
- :mod:`steady.array_files` -- ``.npy`` and PNG inputs, checked before
  their data are read; :mod:`steady.safe_files` -- atomic writes, file
  identity, backups, checksums and the writers' lock;
- :mod:`steady.outline` -- face outlines (disk, rectangle, ellipse, annulus,
  pixel mask) and the grid over each one's bounding box;
- :mod:`steady.labels` -- rasterised phase maps: checks, fill factors;
- :mod:`steady.phases`, :mod:`steady.inclusions`, :mod:`steady.micrograph`
  -- phase geometries rasterised at any grid size (micrographs need the
  extra ``runin[micrograph]``);
- :mod:`steady.depth`, :mod:`steady.depth_maps` -- phase maps that change
  with depth: columns of segments, voxel stacks, spheres, layers;
- :mod:`steady.pressures`, :mod:`steady.wear` -- eq. 7, and the local wear
  laws;
- :mod:`steady.sliding` -- the sliding kinematics (``[sliding]``): the local
  sliding speed over the face;
- :mod:`steady.load_programme` -- a normal force that steps along the
  sliding distance (``[load] programme``);
- :mod:`steady.problem` -- the one checked problem definition;
- :mod:`steady.reference` -- closed-form solutions (eq. 10, 12, 18, ...);
- :mod:`steady.rms_slope` -- the energy-corrected rms slope and its error
  bar; :mod:`steady.normalisation` -- the reference slope of each outline;
  :mod:`steady.relief` -- rms heights;
- :mod:`steady.validity` -- where the model holds (small slopes) and the
  warning beyond;
- :mod:`steady.scene` -- TOML scene files; :mod:`steady.examples` -- the
  example scenes shipped with the package;
- :mod:`steady.solution` -- the steady solve; :mod:`steady.basis` --
  per-phase fields for sweeps over wear coefficients;
  :mod:`steady.profiles` -- cross sections and differential profiles;
- :mod:`steady.output` -- HDF5 result files and the helpers every layout shares;
  :mod:`steady.plotting` -- figures;
- :mod:`steady.sweep`, :mod:`steady.voronoi_sweep` -- resumable parameter
  sweeps; :mod:`steady.design` -- the design table and the fill factor for
  a target rms slope; :mod:`steady.measured_face`, :mod:`steady.fit`,
  :mod:`steady.fit_files` -- wear ratios from a measured worn face;
- :mod:`steady.cli` -- the commands ``runin-steady`` (``python -m
  steady``), ``runin-fit``, ``runin-design`` and ``runin-examples``, and
  what every command shares.

``steady.__version__`` is the installed version (:mod:`steady.version`).

The names below are imported from their modules on first use, so that
``import steady`` is quick and needs neither h5py nor matplotlib until a
file or a figure is asked for.
"""

from .lazy import lazy_names

#: Public names and the module of each.
_MODULE_OF = {
    "__version__": "version",
    "Annulus": "outline",
    "ArrayMap": "phases",
    "Circle": "outline",
    "Ellipse": "outline",
    "FaceGrid": "outline",
    "FaceModel": "fit",
    "FacePhases": "problem",
    "FitResult": "fit",
    "HalfSpace": "halfspace",
    "Homogeneous": "phases",
    "Inclusions": "inclusions",
    "MaskOutline": "outline",
    "MeasuredFace": "measured_face",
    "Micrograph": "micrograph",
    "PhaseBasis": "basis",
    "ArchardLaw": "wear",
    "Factorisation": "wear",
    "PowerLaw": "wear",
    "TableLaw": "wear",
    "ThresholdLaw": "wear",
    "WEAR_LAWS": "wear",
    "WearLaw": "wear",
    "Problem": "problem",
    "Rectangle": "outline",
    "ReferenceSlope": "normalisation",
    "Rods": "phases",
    "Scene": "scene",
    "Segmentation": "micrograph",
    "SlopeEnergy": "rms_slope",
    "SlopeEstimate": "rms_slope",
    "SteadyResult": "solution",
    "StoredResult": "output",
    "SweepSlopes": "basis",
    "ValidityWarning": "validity",
    "Voronoi": "phases",
    "as_outline": "outline",
    "atomic_h5": "safe_files",
    "cross_section": "profiles",
    "differential_profile": "profiles",
    "estimate_rms_slope": "rms_slope",
    "fit_face": "fit",
    "fit_scene": "fit",
    "load_micrograph": "micrograph",
    "load_phase_map": "phases",
    "load_scene": "scene",
    "parse_scene": "scene",
    "phase_pressures": "pressures",
    "pressure_field": "wear",
    "problem_of": "scene",
    "read_fit": "fit_files",
    "read_measured": "fit_files",
    "read_result": "output",
    "realised_fill_factors": "labels",
    "reference": None,
    "reference_slope": "normalisation",
    "ring_average": "profiles",
    "segment": "micrograph",
    "solve": "solution",
    "solve_scene": "solution",
    "validate_labels": "labels",
    "write_fit": "fit_files",
    "write_result": "output",
}

__all__ = sorted(name for name in _MODULE_OF if not name.startswith("_"))


__getattr__, __dir__ = lazy_names(__name__, _MODULE_OF)
