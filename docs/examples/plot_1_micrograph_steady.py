"""
Steady face of a punch cut from a micrograph
============================================

A two-phase micrograph (``micrograph_example.png``, a synthetic image of
bright grains in a darker matrix) is segmented into two phases and cropped
to a disk of radius 4 mm; the bright grains wear ten times less than the
matrix.  In the steady state every point wears at the same rate, so the
pressure is constant on each phase (eq. 7) and the worn face is the
half-space's displacement under that pressure (eq. 9).

The example scene ``micrograph_steady`` (:mod:`steady.examples`;
``runin-examples`` copies it) holds all of it; :func:`steady.solve_scene`
solves it.  Needs ``runin[micrograph]`` (scikit-image).
"""

import warnings

import matplotlib.pyplot as plt
import numpy as np

from steady import ValidityWarning, examples, load_scene, solve_scene

scene = load_scene(examples.path("micrograph_steady"))

# %%
# Solve.  The rms slope of the face -- the friction proxy -- comes with its
# error bar (the same geometry rasterised on coarser grids); the plain pixel
# value is reported apart, and lies below it.  At this load the face's rms
# slope passes the 0.316 rad where the linear half-space stops holding
# (docs/model.md, "Range of validity"): the solve answers, and says so.
with warnings.catch_warnings(record=True) as caught:
    warnings.simplefilter("always", ValidityWarning)
    result = solve_scene(scene)
for warning in caught:  # the scene's file shown by its name, wherever it is installed
    print(f"warning: {warning.message}".replace(str(scene.source_path), scene.source_path.name))

print(f"rms slope       {result.rms_slope:.4f} +- {result.rms_slope_error:.4f} rad")
print(f"plain pixels    {result.rms_slope_plain:.4f} rad")
print(f"rms / grad_f0   {result.normalised_rms_slope:.3f} (load-independent, eq. 15)")
for i, (fill, pressure) in enumerate(zip(result.fill_factors, result.phase_pressures,
                                         strict=True)):
    print(f"phase {i}: fill factor {fill:.3f}, pressure {pressure / 1e3:.1f} kPa")

# %%
# Draw the phase map beside the worn face (the face is defined up to a
# constant: shown about its mean, in micrometres).
extent = np.array([-1, 1, -1, 1]) * result.scale * 1e3
face_um = (result.face - np.nanmean(result.face)) * 1e6
fig, (ax_map, ax_face) = plt.subplots(1, 2, figsize=(9, 4), layout="constrained")
ax_map.imshow(np.ma.masked_less(result.labels, 0).T, origin="lower", extent=extent,
              cmap="Greys_r", interpolation="nearest")
ax_map.set(title="phases (bright: grains)", xlabel="x (mm)", ylabel="y (mm)")
image = ax_face.imshow(face_um.T, origin="lower", extent=extent, cmap="viridis")
ax_face.set(title="steady worn face", xlabel="x (mm)")
fig.colorbar(image, ax=ax_face, label="height about the mean (um)")
plt.show()
