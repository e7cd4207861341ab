"""
Wear ratios from a measured face
================================

The steady face is linear in the phase pressures (eq. 9), and the phase
pressures give the wear ratios (eq. 7).  A measured worn face therefore
tells how much faster one phase wears than another, with a confidence
interval, without knowing the load or the modulus.

Here the "measured" face is made: the steady face of the five steel rods in
a brass cylinder of the paper's Fig. 7 (``k_steel / k_brass = 1.7``), plus
noise of 5 % of its spread.  :func:`steady.fit_scene` fits it back.
"""


import matplotlib.pyplot as plt
import numpy as np

from steady import MeasuredFace, examples, fit_scene, load_scene, solve_scene

scene = load_scene(examples.path("rods_steel_in_brass"))   # phase 0 brass, phase 1 steel
n = 64

# %%
# The synthetic measurement: the steady face alone (``face_only``: no rms
# slope needed), white noise with an explicit seed.
face = solve_scene(scene, n=n, face_only=True).face
noise = np.random.default_rng(2718).standard_normal(face.shape)
measured = MeasuredFace(face + 0.05 * np.nanstd(face) * noise, scene.grid(n).h)

# %%
# The fit: the ratio ``k_1 / k_0`` of steel to brass with its 95 % interval,
# against the 1.7 the face was made with.
fit = fit_scene(scene, measured, n=n)
low, high = fit.ratio_intervals[1]
print(f"k_steel / k_brass = {fit.ratios[1]:.3f}, 95 % interval [{low:.3f}, {high:.3f}] "
      f"(made with {fit.scene_ratios[1]:.3g})")
print(f"residual rms {fit.residual_rms * 1e6:.2f} um of a {fit.relief * 1e6:.1f} um relief")

# %%
# The measured face and what the fit leaves of it: noise, no pattern of the
# rods.
extent = np.array([-1, 1, -1, 1]) * scene.outline.scale * 1e3
fig, axes = plt.subplots(1, 2, figsize=(9, 4), layout="constrained")
for ax, field, title in ((axes[0], measured.heights, "measured face"),
                         (axes[1], fit.residual, "residual of the fit")):
    image = ax.imshow(1e6 * (field - np.nanmean(field)).T, origin="lower", extent=extent,
                      cmap="viridis")
    ax.set(title=title, xlabel="x (mm)", ylabel="y (mm)")
    fig.colorbar(image, ax=ax, label="height (um)")
plt.show()
