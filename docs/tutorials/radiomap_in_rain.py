"""Tutorial: a radio map of your network in rain.

    python docs/tutorials/radiomap_in_rain.py     # full figures in figures/ (10 m, hybrid)
    python docs/tutorials/radiomap_in_rain.py --small    # a quick check (40 m, ray engine)

Your base stations as a sites file (latitude, longitude, height, azimuth clockwise from north,
electrical tilt, power: one row per sector), an area around them, the carrier, and the rain:
the SINR a UAV at 100 m sees in clear air and in 50 mm/h of rain at 28 GHz, the change rain
makes, and the share of the area in outage. Writes ``radiomap_in_rain.png`` into ``--out``.
Needs the ``geo`` extra (``pip install '.[geo]'``).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure
from rainuav.radio import build_radio_map, presets
from rainuav.world.place import place_scenario

ROOT = Path(__file__).resolve().parents[2]


def made_by(command: str) -> str:
    """The line a published figure carries: its command, the date and the machine."""
    import datetime
    import os
    import platform

    cpu = platform.processor() or "unknown CPU"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return f"{command}; {datetime.date.today()}; {cpu}, {os.cpu_count()} cores"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--small", action="store_true", help="40 m pixels and the ray engine")
    ap.add_argument("--out", type=Path, default=Path("figures"))
    args = ap.parse_args()

    # --8<-- [start:steps]
    # 1. The network and the area: the shipped sites file (three tri-sector sites in Zurich),
    #    and a take-off point and destination that set the area (with a 300 m margin).
    resolution = 40.0 if args.small else 10.0
    place = place_scenario(
        ROOT / "examples" / "sites.csv", (47.3660, 8.5380), (47.3800, 8.5560),
        freq_ghz=28.0, resolution_m=resolution,
    )  # fmt: skip
    clear = place.scenario
    if args.small:
        clear = clear.replace(engine="ray")

    # 2. The same network in 50 mm/h of homogeneous rain: only the weather changes.
    rain = presets.with_rain(clear, 50.0)
    maps = {"clear air": build_radio_map(clear), "50 mm/h": build_radio_map(rain)}

    # 3. What rain does: the SINR change and the outage share (SINR below -2 dB, the
    #    threshold of the uma settings the place takes).
    threshold = presets.SINR_THRESHOLDS_DB["uma"]
    change = maps["50 mm/h"].sinr_db - maps["clear air"].sinr_db
    for name, rm in maps.items():
        print(f"{name}: SINR median {np.median(rm.sinr_db):+.1f} dB, "
              f"outage {100 * np.mean(rm.sinr_db < threshold):.1f}% of the area")  # fmt: skip
    p5, p50, p95 = np.percentile(change, [5, 50, 95])
    print(f"rain changes the SINR by {p5:+.2f} / {p50:+.2f} / {p95:+.2f} dB (p5 / median / p95)")
    # --8<-- [end:steps]

    # 4. The figure: both maps and the change, with the sites.
    a = clear.area
    extent = (a.x_min_m, a.x_max_m, a.y_min_m, a.y_max_m)
    fig = Figure(figsize=(13.5, 4.2), layout="constrained")
    axes = fig.subplots(1, 3)
    for ax, (name, rm) in zip(axes[:2], maps.items(), strict=True):
        im = ax.imshow(rm.sinr_db, origin="lower", extent=extent, cmap="RdYlGn",
                       vmin=threshold - 15, vmax=threshold + 15)  # fmt: skip
        ax.set_title(f"SINR at 100 m, 28 GHz, {name}")
        fig.colorbar(im, ax=ax, label="SINR [dB]")
    im = axes[2].imshow(change, origin="lower", extent=extent, cmap="coolwarm", vmin=-13, vmax=13)
    axes[2].set_title("change: 50 mm/h minus clear air")
    fig.colorbar(im, ax=axes[2], label="SINR change [dB]")
    for ax in axes:
        for k, s in enumerate(clear.sites):
            ax.plot(s.x_m, s.y_m, "k^", ms=7, label="sites" if k == 0 else None)
        ax.set_xlabel("east of origin [m]")
        ax.set_ylabel("north of origin [m]")
    axes[0].legend(loc="upper left", fontsize="small")
    command = "python docs/tutorials/radiomap_in_rain.py" + (" --small" if args.small else "")
    fig.text(0.0, -0.02, made_by(command), fontsize=7, color="0.4")
    args.out.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out / "radiomap_in_rain.png", dpi=80, bbox_inches="tight")
    print(f"wrote {args.out / 'radiomap_in_rain.png'}")


if __name__ == "__main__":
    main()
