"""Limiting worn face of a multi-phase punch on an elastic half-space.

The steady state of run-in wear has a closed form (paper eq. 7, 9): constant
pressure on each phase and the half-space displacement under it.  The face
is a disk (the paper's cylinder) or any other outline.  Modules:

- :mod:`steady.grid` -- the pixel grid over a circular face;
- :mod:`steady.outline` -- face outlines (disk, rectangle, ellipse, annulus,
  pixel mask) and the grid over each one's bounding box;
- :mod:`steady.normalisation` -- the reference slope of each outline;
- :mod:`steady.halfspace` -- the elastic half-space operator (eq. 8);
- :mod:`steady.reference` -- closed-form solutions (eq. 10, 12, 18, ...);
- :mod:`steady.phases` -- phase geometries rasterised at any grid size;
- :mod:`steady.micrograph` -- micrographs segmented into phases and placed
  on the face (needs the extra ``runin[micrograph]``);
- :mod:`steady.pressures` -- the steady phase pressures (eq. 7) and their field;
- :mod:`steady.solution` -- the steady solve;
- :mod:`steady.accuracy` -- the energy-corrected rms slope and its error bar;
- :mod:`steady.basis` -- per-phase fields for sweeps over wear coefficients;
- :mod:`steady.profiles` -- cross sections and differential profiles;
- :mod:`steady.scene` -- TOML scene files;
- :mod:`steady.output` -- HDF5 result files and the atomic HDF5 writer;
- :mod:`steady.plotting` -- figures (imported on demand: it loads matplotlib);
- :mod:`steady.sweep` -- resumable parameter sweeps on executors;
- :mod:`steady.voronoi_sweep` -- the sweep over random biphasic Voronoi maps;
- :mod:`steady.design` -- the design table and the fill factor for a target
  rms slope (command ``runin-design``);
- :mod:`steady.fit` -- wear ratios from a measured worn face (command
  ``runin-fit``); :mod:`steady.fit_files` -- its measured maps, HDF5 files
  and figure;
- :mod:`steady.text`, :mod:`steady.memory` -- message text and memory
  estimates;
- :mod:`steady.cli` -- the commands ``runin-steady`` (``python -m
  steady``), ``runin-fit`` and ``runin-design``, and what every command
  shares.
"""

from . import reference
from .accuracy import SlopeEnergy, SlopeEstimate, estimate_rms_slope
from .basis import PhaseBasis, SweepSlopes
from .fit import FaceModel, FitResult, fit_face, fit_scene
from .fit_files import MeasuredFace, read_fit, read_measured, write_fit
from .grid import face_mask, pixel_centres, pixel_size, polar
from .halfspace import HalfSpace
from .inclusions import Inclusions
from .micrograph import Micrograph, Segmentation, load_micrograph, segment
from .normalisation import ReferenceSlope, reference_slope
from .outline import Annulus, Circle, Ellipse, FaceGrid, MaskOutline, Rectangle, as_outline
from .output import StoredResult, atomic_h5, read_result, write_result
from .phases import (
    ArrayMap,
    Homogeneous,
    Rods,
    Voronoi,
    load_phase_map,
    realised_fill_factors,
    validate_labels,
)
from .pressures import phase_pressures, pressure_field
from .profiles import cross_section, differential_profile, ring_average
from .scene import Scene, load_scene, parse_scene
from .solution import SteadyResult, solve, solve_scene

__all__ = [
    "Annulus",
    "ArrayMap",
    "Circle",
    "Ellipse",
    "FaceGrid",
    "FaceModel",
    "FitResult",
    "HalfSpace",
    "Homogeneous",
    "Inclusions",
    "MaskOutline",
    "MeasuredFace",
    "Micrograph",
    "PhaseBasis",
    "Rectangle",
    "ReferenceSlope",
    "Rods",
    "Scene",
    "Segmentation",
    "SlopeEnergy",
    "SlopeEstimate",
    "SteadyResult",
    "StoredResult",
    "SweepSlopes",
    "Voronoi",
    "as_outline",
    "atomic_h5",
    "cross_section",
    "differential_profile",
    "estimate_rms_slope",
    "face_mask",
    "fit_face",
    "fit_scene",
    "load_micrograph",
    "load_phase_map",
    "load_scene",
    "parse_scene",
    "phase_pressures",
    "pixel_centres",
    "pixel_size",
    "polar",
    "pressure_field",
    "read_fit",
    "read_measured",
    "read_result",
    "realised_fill_factors",
    "reference",
    "reference_slope",
    "ring_average",
    "segment",
    "solve",
    "solve_scene",
    "validate_labels",
    "write_fit",
    "write_result",
]
