"""A mission over hills that flies the height it was planned for.

``python -m rainuav.fly`` over the shipped DEM (``examples/dem.tif``, a ridge between the
sites), 60 m above the ground, with the ray engine: the mission's waypoints carry heights
above sea level, and there are as many as keep every straight leg the autopilot flies within
5 m of the planned height above the DEM. The figure samples every leg each metre against the
DEM: the profile of the ground, the flight, and its height above the ground. Ten seconds or
so.
"""

import contextlib
import io
import json
import sys
import tempfile
from pathlib import Path

import numpy as np
from _common import out_dir, stamp
from matplotlib.figure import Figure
from pymavlink import mavwp
from rainuav.fly import main as fly
from rainuav.geo import Georef
from rainuav.ground.dem import read_dem
from rainuav.missions import HOLD_M

out = out_dir(__doc__, sys.argv[1:])
EXAMPLES = Path(__file__).resolve().parents[1]
flight = Path(tempfile.mkdtemp()) / "flight"
argv = [
    "--sites",
    str(EXAMPLES / "sites.csv"),
    "--start",
    "47.3660,8.5380",
    "--goal",
    "47.3800,8.5560",
    "--terrain",
    str(EXAMPLES / "dem.tif"),
    "--altitude-m",
    "60",
    "--engine",
    "ray",
    "--out",
    str(flight),
]
with contextlib.redirect_stdout(io.StringIO()):  # the summary, printed by fly, kept quiet
    assert fly(argv) == 0
summary = json.loads((flight / "summary.json").read_text())
geo = Georef(summary["origin"]["lat"], summary["origin"]["lon"])
loader = mavwp.MAVWPLoader()
n = loader.load(str(flight / "mission.waypoints"))
wps = [loader.wp(k) for k in range(2, n - 1)]  # the waypoints after the take-off
wx, wy = geo.to_local(np.array([w.x for w in wps]), np.array([w.y for w in wps]))
z = np.array([w.z for w in wps])
a = summary["area_m"]
shape = (round((a[3] - a[2]) / 10.0), round((a[1] - a[0]) / 10.0))  # the map's 10 m pixels
dem = read_dem(EXAMPLES / "dem.tif", geo, (a[0], a[1], a[2], a[3]), shape)
s, flown, ground = [], [], []
walked = 0.0
for k in range(len(wps) - 1):
    leg = float(np.hypot(wx[k + 1] - wx[k], wy[k + 1] - wy[k]))
    f = np.linspace(0.0, 1.0, max(2, int(leg) + 1))
    s.append(walked + f * leg)
    flown.append(z[k] + f * (z[k + 1] - z[k]))
    ground.append(dem.at(wx[k] + f * (wx[k + 1] - wx[k]), wy[k] + f * (wy[k + 1] - wy[k])))
    walked += leg
s, flown, ground = (np.concatenate(v) for v in (s, flown, ground))
above = flown - ground
print(
    f"{len(wps)} waypoints; along the legs the flight is {above.min():.1f}-{above.max():.1f} m "
    f"above the ground (planned 60 m, held within {HOLD_M:g} m)"
)
fig = Figure(figsize=(7.2, 4.8), layout="constrained")
top, bottom = fig.subplots(2, 1, sharex=True, height_ratios=[2, 1])
top.fill_between(s, ground.min() - 20, ground, color="0.75", label="ground (the DEM)")
top.plot(s, flown, "k-", lw=1.2, label="the flight between waypoints")
at_waypoints = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(wx), np.diff(wy)))])
top.plot(at_waypoints, z, "ko", ms=4, label="waypoints")
top.set_ylabel("height above sea level [m]")
top.legend(fontsize="small", loc="upper left")
bottom.plot(s, above, "k-", lw=1.0)
bottom.axhspan(60 - HOLD_M, 60 + HOLD_M, color="C2", alpha=0.2, label=f"60 m +- {HOLD_M:g} m")
bottom.set_ylabel("above ground [m]")
bottom.set_xlabel("distance along the flight [m]")
bottom.legend(fontsize="small", loc="lower right")
stamp(fig, "mission_over_terrain.py")
fig.savefig(out / "mission_over_terrain.png", dpi=90)
print(f"wrote {out / 'mission_over_terrain.png'}")
