"""Which height to fly: the outage share of the area at each flight level.

The ``uma`` preset at 28 GHz, mapped with the ray engine at six levels from 25 to 150 m
(``build_radio_levels``), in clear air and in 25 and 50 mm/h of rain: the share of the area
whose SINR is below the preset's -2 dB threshold, level by level. Higher, a UAV sees more
interferers in line of sight; rain, which weakens the far interferers most, takes part of that
back. Ten seconds or so.
"""

import dataclasses
import sys

import numpy as np
from _common import out_dir, stamp
from matplotlib.figure import Figure
from rainuav.radio import presets
from rainuav.radio.outputs.levelmaps import build_radio_levels

out = out_dir(__doc__, sys.argv[1:])
levels = [25.0, 50.0, 75.0, 100.0, 125.0, 150.0]
threshold = presets.SINR_THRESHOLDS_DB["uma"]
fig = Figure(figsize=(6.4, 4.2), layout="constrained")
ax = fig.subplots()
for rate, style in ((0.0, "o-"), (25.0, "s--"), (50.0, "^:")):
    scn = presets.uma(rate, 28e9, engine="ray")
    stack = build_radio_levels(scn.replace(area=dataclasses.replace(scn.area, altitudes_m=levels)))
    share = 100 * np.mean(np.asarray(stack.sinr_db) < threshold, axis=(1, 2))
    label = "clear air" if rate == 0 else f"{rate:g} mm/h"
    ax.plot(levels, share, style, label=label)
    print(f"{label}: " + ", ".join(f"{h:g} m {s:.0f}%" for h, s in zip(levels, share, strict=True)))
ax.set_xlabel("flight level above the ground [m]")
ax.set_ylabel(f"area with SINR below {threshold:g} dB [%]")
ax.set_title("uma, 28 GHz: outage share of the area by height", fontsize=10)
ax.set_ylim(0, 100)
ax.grid(alpha=0.3)
ax.legend()
stamp(fig, "outage_by_height.py")
fig.savefig(out / "outage_by_height.png", dpi=80)
print(f"wrote {out / 'outage_by_height.png'}")
