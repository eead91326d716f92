"""A storm that moves.

The ``storm`` preset (the ``uma`` network at 28 GHz under a random storm of rain cells that
drift with the wind and grow or decay; seed 0): its rain rate over the area at take-off, after
one minute and after two. The maps in time, the exact plan in space and time and
the learned policy all fly through this weather (the Weather in time page). A second.
"""

import sys

import numpy as np
from _common import out_dir, stamp
from matplotlib.figure import Figure
from rainuav.radio.engines.pe_engine import rain_rate_at
from rainuav.radio.scene import presets

out = out_dir(__doc__, sys.argv[1:])
scn = presets.storm(seed=0)
a = scn.area
x = np.linspace(a.x_min_m, a.x_max_m, 200)
y = np.linspace(a.y_min_m, a.y_max_m, 200)
xx, yy = np.meshgrid(x, y)
fig = Figure(figsize=(11, 3.7), layout="constrained")
axes = fig.subplots(1, 3)
for ax, t in zip(axes, (0.0, 60.0, 120.0), strict=True):
    rate = rain_rate_at(scn.replace(medium=scn.medium.at(t)), xx, yy)
    im = ax.imshow(rate, origin="lower", extent=(x[0], x[-1], y[0], y[-1]), cmap="Blues",
                   vmin=0, vmax=100)  # fmt: skip
    ax.plot([s.x_m for s in scn.sites], [s.y_m for s in scn.sites], "k^", ms=5)
    ax.set_title(f"rain at t = {t:g} s", fontsize=10)
    ax.set_xlabel("x [m]")
    print(f"t = {t:g} s: peak {rate.max():.0f} mm/h, {100 * np.mean(rate > 25):.0f}% over 25 mm/h")
axes[0].set_ylabel("y [m]")
fig.colorbar(im, ax=axes, shrink=0.85, label="rain rate [mm/h]")
stamp(fig, "storm_that_moves.py")
fig.savefig(out / "storm_that_moves.png", dpi=80)
print(f"wrote {out / 'storm_that_moves.png'}")
