"""A radio map in clear air and in heavy rain.

The ``uma`` preset (seven sites, three sectors each, 3GPP antennas) at 28 GHz, 100 m above the
ground, mapped with the ray engine in clear air and at 50 mm/h: the SINR in each, and what the
rain changes. Rain weakens distant interferers more than the serving cell, so here it raises
the SINR. A few seconds.
"""

import sys

import numpy as np
from _common import out_dir, stamp
from matplotlib.figure import Figure
from rainuav.radio import build_radio_map, presets

out = out_dir(__doc__, sys.argv[1:])
clear = build_radio_map(presets.uma(0.0, 28e9, engine="ray"))
rain = build_radio_map(presets.uma(50.0, 28e9, engine="ray"))
change = rain.sinr_db - clear.sinr_db
lo, hi = np.percentile(change, [5, 95])
print(
    f"SINR median: clear {np.median(clear.sinr_db):.1f} dB, 50 mm/h {np.median(rain.sinr_db):.1f}"
    f" dB; rain changes it by {lo:+.1f} to {hi:+.1f} dB (5-95%)"
)
fig = Figure(figsize=(11, 3.8), layout="constrained")
axes = fig.subplots(1, 3)
for ax, data, title, cmap, lim in (
    (axes[0], clear.sinr_db, "SINR, clear air [dB]", "RdYlGn", (-10, 10)),
    (axes[1], rain.sinr_db, "SINR, 50 mm/h [dB]", "RdYlGn", (-10, 10)),
    (axes[2], change, "change with rain [dB]", "PuOr", (-6, 6)),
):
    im = ax.imshow(data, origin="lower", extent=clear.extent_m, cmap=cmap, vmin=lim[0], vmax=lim[1])
    fig.colorbar(im, ax=ax, shrink=0.85)
    ax.set_title(title, fontsize=10)
    ax.set_xlabel("x [m]")
axes[0].set_ylabel("y [m]")
stamp(fig, "map_in_rain.py")
fig.savefig(out / "map_in_rain.png", dpi=80)
print(f"wrote {out / 'map_in_rain.png'}")
