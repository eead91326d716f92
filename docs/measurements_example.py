"""A worked example of the page "Maps from measurements": a network whose database is wrong, a
drive test over the real one, and the map corrected by it.

    python docs/measurements_example.py [--out measured/]

Writes ``network.toml`` (``uma`` at 28 GHz in 5 mm/h of rain, 25 m pixels: the database's
sites) and ``drive.csv`` (a log drawn from the real network in the same rain: two cells' tilts
and one cell's power differ from the database's; 4 east-west lines, the 6 strongest cells at each
pixel, 2 dB of noise), then runs
``python -m rainuav.radiomap --config network.toml --measurements drive.csv --calibrate
power_db,tilt_deg`` into ``OUT/maps``. Prints the fitted offsets of the three wrong cells beside
the truth.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
from pathlib import Path

from rainuav.radio import Area, build_radio_map, presets
from rainuav.radio.measured.synthetic import sample_log, write_log
from rainuav.radiomap import main as radiomap

WRONG = {0: {"tilt_deg": 3.0}, 7: {"tilt_deg": -2.0}, 12: {"power_db": -6.0}}
"""The cells the database has wrong, and by how much the real network differs."""


def real_network(scn):
    cells = [(s, c) for s in scn.sites for c in s.cells]
    sites = []
    for s in scn.sites:
        moved = []
        for c in s.cells:
            k = next(i for i, (_, cc) in enumerate(cells) if cc is c)
            e = WRONG.get(k, {})
            moved.append(dataclasses.replace(
                c, tilt_deg=c.tilt_deg + e.get("tilt_deg", 0.0),
                tx_power_dbm=c.tx_power_dbm + e.get("power_db", 0.0),
            ))  # fmt: skip
        sites.append(dataclasses.replace(s, cells=moved))
    return scn.replace(sites=sites)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, default=Path("measured"))
    args = ap.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    scn = presets.uma(5.0, 28e9, engine="ray", ground="none", area=Area(resolution_m=25.0))
    cfg = scn.to_toml(args.out / "network.toml")
    truth = build_radio_map(real_network(scn))
    log = write_log(sample_log(truth, 0.05, cells=6, seed=0), args.out / "drive.csv")
    if radiomap(["--config", str(cfg), "--measurements", str(log), "--calibrate",
                 "power_db,tilt_deg", "--out", str(args.out / "maps")]) != 0:  # fmt: skip
        raise SystemExit(1)
    fit = json.loads((args.out / "maps" / "fit.json").read_text())
    for f in fit["calibration"]:
        if f["cell"] in WRONG:
            got = ", ".join(f"{k} {v:+.2f} +- {f['std'][k]:.2f}" for k, v in f["offsets"].items())
            print(f"cell {f['cell']:2d}: truth {WRONG[f['cell']]}; fitted {got}")


if __name__ == "__main__":
    main()
