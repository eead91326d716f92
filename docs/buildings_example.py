"""The shipped district's buildings: what their walls add to the map, and the same flight
planned with and without them (the Buildings page's figure and figures).

    python docs/buildings_example.py [--out figures/buildings.png]   # make figures: docs/figures

The shipped place (``examples/sites.csv``, 28 GHz, clear air, 40 m above the ground) among
the footprints of ``examples/buildings.geojson`` (ray engine, so the wall rays can be shown
apart). Prints the share of the area where the walls and corners (reflections once and twice,
diffraction round the corners) raise the serving cell's power by more than 1 dB and 3 dB, and
each plan's cost and outage share on the map with the buildings, the plan made without them
flown there included. Draws (left) what the walls and corners add to the serving cell's power,
(right) both flights over the SINR with the buildings.
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
ALTITUDE_M = 40.0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("figures") / "buildings.png")
    args = ap.parse_args()

    from matplotlib.figure import Figure
    from matplotlib.patches import Patch
    from rainuav.nav import planner
    from rainuav.nav.task import NavConfig
    from rainuav.radio.engines.ray_engine import ray_terms
    from rainuav.radio.outputs.maps import build_radio_map
    from rainuav.radio.scene import presets
    from rainuav.world import world_from
    from rainuav.world.place import place_scenario

    sites, city = ROOT / "examples" / "sites.csv", ROOT / "examples" / "buildings.geojson"
    open_ground = place_scenario(sites, START, GOAL, altitude_m=ALTITUDE_M)
    among = place_scenario(sites, START, GOAL, altitude_m=ALTITUDE_M, footprints=city)
    scn = among.scenario.replace(engine="ray")

    # What the walls and corners add: each cell's power with and without those rays (clear air).
    jobs = [(s, c) for s in scn.sites for c in s.cells]
    x, y = scn.area.centres()
    t = ray_terms(scn, jobs, x, y)
    rest = np.clip(t[..., 0] + t[..., 1] + t[..., 2], 1e-30, None)
    total = rest + t[..., 5]
    serving = np.argmax(total, axis=0)
    pick = np.take_along_axis(total, serving[None], 0)[0]
    pick_rest = np.take_along_axis(rest, serving[None], 0)[0]
    gain_db = 10 * np.log10(pick / pick_rest)
    print(f"walls and corners raise the serving cell's power by > 1 dB over "
          f"{np.mean(gain_db > 1):.1%} of the area, > 3 dB over {np.mean(gain_db > 3):.1%}, "
          f"> 10 dB over {np.mean(gain_db > 10):.1%}")  # fmt: skip

    span = abs(among.goal_m[0] - among.start_m[0]) + abs(among.goal_m[1] - among.start_m[1])
    task = NavConfig(goal_m=among.goal_m, start_m=among.start_m,
                     max_steps=int(np.ceil(2 * span / 10)) + 50,
                     min_db=presets.SINR_THRESHOLDS_DB["uma"])  # fmt: skip
    maps = {"open": build_radio_map(open_ground.scenario.replace(engine="ray")),
            "buildings": build_radio_map(scn)}  # fmt: skip
    envs = {k: world_from(m, task).env() for k, m in maps.items()}
    plans = {k: planner.optimal(e, np.asarray(among.start_m)) for k, e in envs.items()}
    env = envs["buildings"]
    rows = []
    for name, plan in plans.items():
        env.reset(options={"start_m": np.asarray(among.start_m)})
        ret, outage, arrived, moves = 0.0, 0, False, 0
        for a in plan.actions:
            _, r, term, trunc, info = env.step(int(a))
            ret, moves = ret + r, moves + 1
            outage += bool(info["outage"])
            if term or trunc:
                arrived = bool(info["arrived"])
                break
        cost = -(ret - task.goal_reward) if arrived else float("nan")
        rows.append((name, cost, outage / max(moves, 1), arrived))
        print(f"planned {'among buildings' if name == 'buildings' else 'on open ground':16s}: "
              f"among the buildings costs {cost:.1f}, outage {outage / max(moves, 1):.1%}, "
              f"arrives: {arrived}")  # fmt: skip
    if rows[0][3]:
        best = rows[1][1]
        print(f"the open-ground plan pays {(rows[0][1] - best) / best:.1%} more among buildings")
    else:
        print("the open-ground plan does not arrive among the buildings: it flies into a tower")

    a = scn.area
    extent = (a.x_min_m, a.x_max_m, a.y_min_m, a.y_max_m)
    fig = Figure(figsize=(12.0, 5.6), layout="constrained")
    left, right = fig.subplots(1, 2)
    im = left.imshow(gain_db, origin="lower", extent=extent, cmap="magma", vmin=0, vmax=12)
    fig.colorbar(im, ax=left, label="serving cell's power added by walls and corners, dB")
    left.set_title(f"What walls and corners add (28 GHz, {ALTITUDE_M:.0f} m)", fontsize=10)
    rm = maps["buildings"]
    im = right.imshow(rm.sinr_db, origin="lower", extent=extent, cmap="RdYlGn", vmin=-20,
                      vmax=20)  # fmt: skip
    fig.colorbar(im, ax=right, label="SINR among the buildings, dB")
    blocked = np.ma.masked_where(~rm.not_flyable, np.ones(rm.not_flyable.shape))
    from rainuav.radio.scene.buildings import scenario_buildings

    outlines = scenario_buildings(scn)
    for ax in (left, right):
        for f in outlines.footprints if outlines is not None else ():
            bx, by = f.polygon.exterior.xy
            ax.plot(bx, by, color="0.55", lw=0.3)
        ax.imshow(blocked, origin="lower", extent=extent, cmap="Greys", vmin=0, vmax=1.4,
                  alpha=0.9)  # fmt: skip
        ax.plot([s.x_m for s in scn.sites], [s.y_m for s in scn.sites], "^", color="navy",
                ms=7, label="sites")  # fmt: skip
        ax.set_xlabel("east, m")
        ax.set_ylabel("north, m")
    for (name, plan), style in zip(plans.items(), ("--", "-"), strict=True):
        label = "planned on open ground" if name == "open" else "planned among the buildings"
        right.plot(plan.path_m[:, 0], plan.path_m[:, 1], style, color="k", lw=1.6, label=label)
    right.set_title(f"One flight at {ALTITUDE_M:.0f} m, planned with and without buildings",
                    fontsize=10)  # fmt: skip
    grey = Patch(facecolor="0.45", label="not flyable (a building within 10 m)")
    handles, _ = right.get_legend_handles_labels()
    right.legend(handles=[*handles, grey], loc="upper left", fontsize=8)
    left.legend(handles=[grey], loc="upper left", fontsize=8)
    fig.text(0.01, 0.005, made_by("python docs/buildings_example.py"), fontsize=6, color="0.4")
    args.out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out, dpi=100)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
