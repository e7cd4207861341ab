"""
A run-in from a script: how far the face slides before it is run in
=====================================================================

A biphasic Voronoi punch (radius 4 mm, 10 N on a counter-body with
``E* = 1.3 MPa``; phase 1 wears ten times faster than phase 0) starts flat
and wears until every point wears at the same rate.  Along the way its rms
slope -- the friction proxy -- rises from zero to the steady value of the
closed form.  The answer a run-in study wants is the *run-in distance*: the
sliding distance after which the rms slope and the face stay within 1 %
(and 0.1 %) of the steady state, in metres.

The example scene ``voronoi_transient`` (:mod:`steady.examples`;
``runin-examples`` copies it) holds the punch, the load and the run's
settings; here it runs on a 48-pixel grid so that the example takes a few
seconds.
"""

import pathlib
import tempfile

import h5py
import matplotlib.pyplot as plt

from steady import examples
from transient.output import write_run
from transient.plotting import plot_history
from transient.runin import run_in
from transient.scene import load_transient_scene, wear_problem_of

scene, options, initial = load_transient_scene(examples.path("voronoi_transient"))
problem = wear_problem_of(scene, n=48)
result = run_in(problem, initial.recession(problem.grid), options)
print(f"{result.status}: {result.steps} steps; the dynamics end at "
      f"{result.history['distance'][-1]:.4g} m")

# %%
# The run-in distance within 1 % and within 0.1 %, in metres and in units of
# the distance scale ``s*`` (the sliding distance over which a face wears by
# its own relief), with the uncertainty of the step errors.  The worn depth
# at that point, mean and at the rim, tells how much material the run-in
# costs.
for within in (0.01, 0.001):
    d = result.run_in_distance(within)
    print(f"within {within:.1%}: {d.distance_m:.4g} +- {d.uncertainty_m:.2g} m "
          f"({d.distance_s_star:.3f} s*); worn {d.mean_worn_depth_m * 1e6:.1f} um on average, "
          f"{d.rim_worn_depth_m * 1e6:.1f} um at the rim")

# %%
# The run file holds the history, the faces and the inputs, in SI units with
# CF attributes (``units``, ``long_name``); ``xarray.open_dataset(path,
# engine="h5netcdf")`` opens it as labelled arrays.
with tempfile.TemporaryDirectory() as tmp:
    path = pathlib.Path(tmp) / "run.h5"
    write_run(path, result)
    with h5py.File(path, "r") as f:
        distance = f["history/distance"]
        print(f"history: {distance.shape[0]} points along "
              f"{distance.attrs['long_name']!r} ({distance.attrs['units']})")

# %%
# The history in metres, in one call: the rms slope with its error band, the
# steady value and the run-in distance marked; ``s*`` on the top axis.
fig = plot_history(result, units="m", quantities=("rms_slope", "rms_height"))
plt.show()
