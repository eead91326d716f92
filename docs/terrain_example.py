"""The same flight planned with and without the ground (the Terrain page's figure and figures).

    python docs/terrain_example.py [--out figures/terrain_flight.png]   # make figures: docs/figures

The shipped place (``examples/sites.csv``, 28 GHz, 25 mm/h of rain, 100 m above the ground) from
47.3660 N 8.5380 E to 47.3800 N 8.5560 E, planned exactly on flat ground and over
``examples/dem.tif`` (a ridge between site ZH-001 and the east of the area). Prints each plan's
cost and outage share on the map over the ground, the flat plan flown there included: what a
flight planned without the terrain pays where the terrain is. Draws both paths over the SINR
with the ground, with the terrain's contours.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "docs" / "tutorials"))
from radiomap_in_rain import made_by  # noqa: E402

START, GOAL = (47.3660, 8.5380), (47.3800, 8.5560)
RAIN_MM_H = 25.0
ALTITUDE_MSL_M = 530.0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("figures") / "terrain_flight.png")
    args = ap.parse_args()

    from matplotlib.figure import Figure
    from rainuav.nav import planner
    from rainuav.nav.task import NavConfig
    from rainuav.radio.outputs.maps import build_radio_map
    from rainuav.radio.scene import presets
    from rainuav.radio.scene.terrain import scenario_terrain
    from rainuav.world import world_from
    from rainuav.world.place import place_scenario

    sites, dem = ROOT / "examples" / "sites.csv", ROOT / "examples" / "dem.tif"
    flat = place_scenario(
        sites, START, GOAL, rain_rate_mm_h=RAIN_MM_H, altitude_m=ALTITUDE_MSL_M - 410.0
    )
    hilly = place_scenario(sites, START, GOAL, rain_rate_mm_h=RAIN_MM_H, terrain=dem,
                           altitude_m=ALTITUDE_MSL_M, altitude_reference="msl")  # fmt: skip
    span = abs(flat.goal_m[0] - flat.start_m[0]) + abs(flat.goal_m[1] - flat.start_m[1])
    task = NavConfig(goal_m=flat.goal_m, start_m=flat.start_m,
                     max_steps=int(np.ceil(2 * span / 10)) + 50,
                     min_db=presets.SINR_THRESHOLDS_DB["uma"])  # fmt: skip
    envs = {k: world_from(build_radio_map(p.scenario), task).env() for k, p in
            (("flat", flat), ("ground", hilly))}  # fmt: skip
    plans = {k: planner.optimal(e, np.asarray(flat.start_m)) for k, e in envs.items()}
    on_ground = envs["ground"]
    rows = []
    for name, plan in plans.items():
        on_ground.reset(options={"start_m": np.asarray(flat.start_m)})
        ret, outage, arrived, moves = 0.0, 0, False, 0
        for a in plan.actions:
            _, r, term, trunc, info = on_ground.step(int(a))
            ret, moves = ret + r, moves + 1
            outage += bool(info["outage"])
            if term or trunc:
                arrived = bool(info["arrived"])
                break
        cost = -(ret - task.goal_reward) if arrived else float("nan")
        rows.append((name, cost, outage / max(moves, 1), arrived))
        print(f"planned on {name:6s}: over the ground costs {cost:.1f}, outage "
              f"{outage / max(moves, 1):.1%}, arrives: {arrived}")  # fmt: skip
    if rows[0][3]:
        best = rows[1][1]
        print(f"the flat plan pays {(rows[0][1] - best) / best:.1%} more over the ground")
    else:
        print("the flat plan does not arrive over the ground: it flies into terrain")

    rm = build_radio_map(hilly.scenario)
    a = hilly.scenario.area
    extent = (a.x_min_m, a.x_max_m, a.y_min_m, a.y_max_m)
    t = scenario_terrain(hilly.scenario)
    fig = Figure(figsize=(6.6, 5.8), layout="constrained")
    ax = fig.subplots()
    im = ax.imshow(rm.sinr_db, origin="lower", extent=extent, cmap="RdYlGn", vmin=-20, vmax=20)
    fig.colorbar(im, ax=ax, label="SINR over the ground, dB")
    xs = t.x0_m + t.dx_m * np.arange(t.heights_m.shape[1])
    ys = t.y0_m + t.dy_m * np.arange(t.heights_m.shape[0])
    cs = ax.contour(xs, ys, t.heights_m, levels=[450, 500, 550, 600], colors="0.25",
                    linewidths=0.7)  # fmt: skip
    ax.clabel(cs, fmt="%d m", fontsize=7)
    # The pixels a UAV may not enter at this height, grey over the SINR.
    blocked = np.ma.masked_where(~rm.not_flyable, np.ones(rm.not_flyable.shape))
    ax.imshow(blocked, origin="lower", extent=extent, cmap="Greys", vmin=0, vmax=1.4, alpha=0.9)
    from matplotlib.patches import Patch

    grey = Patch(facecolor="0.45", label="not flyable (terrain within 10 m)")
    for (name, plan), style in zip(plans.items(), ("--", "-"), strict=True):
        label = "planned on flat ground" if name == "flat" else "planned over the ground"
        ax.plot(plan.path_m[:, 0], plan.path_m[:, 1], style, color="k", lw=1.6, label=label)
    sx = [s.x_m for s in hilly.scenario.sites]
    sy = [s.y_m for s in hilly.scenario.sites]
    ax.plot(sx, sy, "^", color="navy", ms=8, label="sites")
    ax.set_xlabel("east, m")
    ax.set_ylabel("north, m")
    ax.set_title(
        f"The same flight at {ALTITUDE_MSL_M:.0f} m above sea level, planned with and\n"
        "without the ground (25 mm/h, 28 GHz)",
        fontsize=10,
    )
    handles, _ = ax.get_legend_handles_labels()
    ax.legend(handles=[*handles, grey], loc="upper left", fontsize=8)
    cmd = "python docs/terrain_example.py"
    fig.text(0.01, 0.005, made_by(cmd), fontsize=6, color="0.4")
    args.out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out, dpi=110)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
