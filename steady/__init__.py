"""Limiting worn face of a multi-phase punch on an elastic half-space.

The steady state of run-in wear has a closed form (paper eq. 7, 9): constant
pressure on each phase and the half-space displacement under it.  The face
is a disk (the paper's cylinder) or any other outline.  Modules, by the
floors they stand on, from the bottom up (``FLOORS`` in tests/test_layers.py;
a module imports only from its floor and below):

- base: :mod:`steady.text`, :mod:`steady.memory` -- message text, memory
  estimates; :mod:`steady.registry` -- registries of named entries;
  :mod:`steady.schema` -- declarative scene keys and the registries of kinds;
- fields, arrays that know no outline: :mod:`steady.halfspace` -- the
  elastic half-space operator (eq. 8); :mod:`steady.periodic` -- the same
  on a periodic cell; :mod:`steady.counterbody` -- the counter-body, a
  half-space or a layer on a rigid flat, the layer's operator and the one
  choice of a grid's operator (``Counterbody.operator``);
  :mod:`steady.array_files` -- ``.npy``
  and PNG inputs, checked before their data are read; :mod:`steady.labels`
  -- rasterised phase maps; :mod:`steady.pressures` -- eq. 7;
  :mod:`steady.depth` -- columns of segments below the face;
  :mod:`steady.relief` -- rms heights; :mod:`steady.validity` -- where the
  model holds; :mod:`steady.measured_face` -- a measured height map;
  :mod:`steady.reference` -- closed-form solutions (eq. 10, 12, 18, ...);
  :mod:`steady.topography` -- a face's power spectrum, and the face as a
  SurfaceTopography topography;
- the face: :mod:`steady.outline` -- face outlines and their grids;
  :mod:`steady.phases` (the :class:`~steady.phases.PhaseMap` contract),
  :mod:`steady.inclusions`, :mod:`steady.micrograph`,
  :mod:`steady.depth_maps` -- phase geometries, in the plane and in depth;
  :mod:`steady.wear` -- the local wear laws (the
  :class:`~steady.wear.WearLaw` contract); :mod:`steady.sliding` -- the
  sliding kinematics; :mod:`steady.load_programme` -- a stepping load;
- estimators: :mod:`steady.rms_slope` -- the energy-corrected rms slope and
  its error bar; :mod:`steady.normalisation` -- the reference slope;
- :mod:`steady.problem` -- the one checked problem definition;
- scenes: :mod:`steady.scene` -- TOML scene files and the factory
  ``problem_of``; :mod:`steady.examples` -- the shipped scenes;
  :mod:`steady.safe_files` -- atomic writes, identity, checksums, locks;
- the steady features: :mod:`steady.solution` -- the steady solve;
  :mod:`steady.basis` -- per-phase fields for sweeps; :mod:`steady.profiles`
  -- cross sections and differential profiles; :mod:`steady.fit` -- wear
  ratios from a measured worn face;
- results: :mod:`steady.output` -- HDF5 result files and the helpers every
  layout shares; :mod:`steady.plotting` -- figures;
- studies: :mod:`steady.sweep`, :mod:`steady.voronoi_sweep` -- resumable
  parameter sweeps; :mod:`steady.design` -- the design table;
  :mod:`steady.fit_files` -- the fit's files;
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
    "Counterbody": "counterbody",
    "Ellipse": "outline",
    "FaceGrid": "outline",
    "FaceModel": "fit",
    "FacePhases": "problem",
    "FitResult": "fit",
    "HalfSpace": "halfspace",
    "Homogeneous": "phases",
    "Inclusions": "inclusions",
    "LayeredHalfSpace": "counterbody",
    "MaskOutline": "outline",
    "MeasuredFace": "measured_face",
    "Micrograph": "micrograph",
    "PeriodicCell": "outline",
    "PeriodicHalfSpace": "periodic",
    "PhaseBasis": "basis",
    "PowerSpectrum": "topography",
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
    "isotropic_psd": "topography",
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
    "to_topography": "topography",
    "validate_labels": "labels",
    "write_fit": "fit_files",
    "write_result": "output",
}

__all__ = sorted(name for name in _MODULE_OF if not name.startswith("_"))


__getattr__, __dir__ = lazy_names(__name__, _MODULE_OF)
