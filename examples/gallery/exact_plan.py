"""The Gymnasium environment and the exact optimum.

``rainuav/UAVNav-v0`` on the ``uma`` map at 28 GHz in 50 mm/h of rain (ray engine): the exact
dynamic-programming plan from a start, against the straight line, over the SINR. The plan is
the yardstick a learned policy is judged by. Seconds once the map is cached.
"""

import sys

import gymnasium as gym
import rainuav  # noqa: F401  (registers rainuav/UAVNav-v0)
from _common import out_dir, stamp
from matplotlib.figure import Figure
from rainuav.nav import planner

out = out_dir(__doc__, sys.argv[1:])
env = gym.make("rainuav/UAVNav-v0", scenario="uma", rain_rate_mm_h=50, engine="ray")
obs, info = env.reset(seed=0)
start = info["position_m"]
best = planner.optimal(env.unwrapped, start)
line = planner.straight_line(env.unwrapped, start)
task = env.unwrapped.cfg
for name, plan in (("optimum", best), ("straight line", line)):
    print(f"{name}: {len(plan.actions)} moves, return {plan.return_:.1f}")
field = env.unwrapped.field  # the SINR map the task reads (dB), over its extent
fig = Figure(figsize=(6.2, 5.4), layout="constrained")
ax = fig.subplots()
im = ax.imshow(
    field.db,
    origin="lower",
    extent=field.extent,
    cmap="RdYlGn",
    vmin=task.min_db - 10,
    vmax=task.min_db + 10,
)
fig.colorbar(im, ax=ax, label="SINR [dB]")
ax.plot(*best.path_m.T, "k-", lw=2, label="exact optimum")
ax.plot(*line.path_m.T, "b--", lw=1.2, label="straight line")
ax.plot(*start, "bs", label="start")
ax.plot(*task.goal_m, "b*", ms=12, label="destination")
ax.set_xlabel("x [m]")
ax.set_ylabel("y [m]")
fig.legend(loc="outside lower center", ncols=4, fontsize="small", frameon=False)
stamp(fig, "exact_plan.py")
fig.savefig(out / "exact_plan.png", dpi=90)
print(f"wrote {out / 'exact_plan.png'}")
