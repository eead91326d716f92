"""A study in one command: where rain changes the flight.

A study of four cases (``uma`` at 28 GHz in clear air and in 25, 50 and 100 mm/h of rain; the
ray engine; per case its map and the exact planner's flights from 50 starts, no training), run
by ``rainuav.studies.run_study`` as ``python -m rainuav.study`` runs it. Left: the study's own
``maps.png`` (each case's SINR on one colour scale, and its change from clear air); right, from
its ``results.csv``: the share of pixels in outage, the outage along the exact optimum and the
straight line's excess cost over it. Rain attenuates the many distant
interferers more than the near server, so at 28 GHz the outage falls as the rain grows. About
20 s on 2 cores once the maps are cached.
"""

import csv
import sys
import tempfile
from pathlib import Path

import numpy as np
from _common import out_dir, stamp
from matplotlib.figure import Figure
from matplotlib.image import imread
from rainuav.studies import load_study, run_study

STUDY = """
name = "rain_sweep"
sweep = "one_at_a_time"
seeds = [0]
compute = ["map", "optimal"]
eval_starts = 50

[base]
scenario = "uma"
freq_ghz = 28.0
engine = "ray"

[axes]
rain_rate_mm_h = [0.0, 25.0, 50.0, 100.0]
"""

out = out_dir(__doc__, sys.argv[1:])
with tempfile.TemporaryDirectory() as tmp:
    spec = Path(tmp) / "rain_sweep.toml"
    spec.write_text(STUDY)
    run_study(load_study(spec), Path(tmp) / "study", workers=1, progress=False)
    with open(Path(tmp) / "study" / "results.csv", newline="") as f:
        cases = [r for r in csv.DictReader(f) if r["axis"] != "base"]  # the base is 0 mm/h again
    maps = imread(Path(tmp) / "study" / "maps.png")  # the study's own figure of its maps

rain = np.array([float(r["rain_rate_mm_h"]) for r in cases])
share = {
    "pixels in outage": "map_outage_share",
    "outage along the exact optimum": "optimal_outage_share",
    "straight line's excess cost": "straight_line_mean_excess_cost",
}
fig = Figure(figsize=(9.6, 6.4), layout="constrained")
left, right = fig.subplots(1, 2, gridspec_kw={"width_ratios": (1.0, 1.1)})
left.imshow(maps)
left.set_axis_off()
left.set_title("the study's maps.png: SINR, and its change from clear air", fontsize="small")
for label, key in share.items():
    y = 100 * np.array([float(r[key]) for r in cases])
    right.plot(rain, y, "o-", label=label)
    print(label + ": " + ", ".join(f"{v:.1f}%" for v in y) + f" at {rain.tolist()} mm/h")
right.set_xlabel("rain [mm/h]")
right.set_ylabel("[%]")
right.set_title("from the study's results.csv (uma, 28 GHz)", fontsize="small")
right.legend(fontsize="small")
right.grid(alpha=0.3)
stamp(fig, "study_rain_sweep.py")
fig.savefig(out / "study_rain_sweep.png", dpi=90)
print(f"wrote {out / 'study_rain_sweep.png'}")
