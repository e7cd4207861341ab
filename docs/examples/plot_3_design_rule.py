"""
A design rule: the microstructure for a wanted friction proxy
=============================================================

The steady rms slope of a biphasic punch is ``grad_f0 = 4 pbar / (pi E*)``
(eq. 12) times a number that depends only on the fill factor ``rho_1`` of
phase 1 and the wear ratio ``k_1 / k_0`` (eq. 15).  The design table shipped
with the package holds that number, averaged over random Voronoi maps, and
:class:`steady.design.DesignTable` reads it both ways -- the command
``runin-design`` does the same.
"""

import warnings

import matplotlib.pyplot as plt
import numpy as np

from steady.design import DesignTable
from steady.validity import SLOPE_LIMIT, ValidityWarning

table = DesignTable.read()
pbar_over_estar = 0.08           # a tyre tread on a road
ratio = 1e-3                     # phase 1 wears a thousand times slower than phase 0

# %%
# Forward: the rms slope of a 30 % fill factor.  Backward: the fill factor
# for an rms slope of 0.3 rad.
value, scatter = table.rms_slope(pbar_over_estar, ratio, 0.3)
print(f"rho_1 = 0.3: rms slope {value:.3f} +- {scatter:.3f} rad (realisation scatter)")
design = table.fill_factor_for(pbar_over_estar, ratio, 0.3)
low, high = design.fill_factor_range
print(f"rms slope 0.3 rad: rho_1 = {design.fill_factor:.3f} (scatter {low:.3f} .. {high:.3f})")

# %%
# The paper's tyre rule asks for an rms slope of 1 at this load.  The table
# answers, but a slope of 1 rad is far beyond the small slopes of the linear
# half-space (docs/model.md, "Range of validity"), and the query says so.
with warnings.catch_warnings(record=True) as caught:
    warnings.simplefilter("always", ValidityWarning)
    tyre = table.fill_factor_for(pbar_over_estar, ratio, 1.0)
print(f"rms slope 1 rad: rho_1 = {tyre.fill_factor:.4f}")
for warning in caught:
    print(f"warning: {warning.message}")

# %%
# The rms slope against the fill factor for a few wear ratios, with the
# slope limit of the model.
rho = np.linspace(table.fill_factors[0], table.fill_factors[-1], 200)
grad_f0 = 4 * pbar_over_estar / np.pi
fig, ax = plt.subplots(figsize=(6, 4), layout="constrained")
for r in (1e-3, 1e-2, 1e-1, 10.0):
    mean, sd, _ = table.curve(r, rho)
    ax.plot(rho, grad_f0 * mean, label=f"$k_1/k_0$ = {r:g}")
    ax.fill_between(rho, grad_f0 * (mean - sd), grad_f0 * (mean + sd), alpha=0.3)
ax.axhline(SLOPE_LIMIT, color="k", ls="--", lw=1, label="limit of small slopes")
ax.plot(design.fill_factor, 0.3, "ko")
ax.set(xlabel=r"fill factor $\rho_1$ of phase 1", ylabel="steady rms slope (rad)",
       title=rf"$\bar p/E^*$ = {pbar_over_estar:g}", yscale="log")
ax.legend()
plt.show()
