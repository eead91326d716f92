"""The prior's local-mean spread by mechanism against Sionna RT's radio map (the page "How far to
trust a map").

    python experiments/prior_spread_tracer.py [--scenes district urban] [--freq-ghz 3.5]
        [--altitude 20] [--samples 8e6] [--json FILE]

Per scene (by default the held-back ones, on which no choice of the engine's methods was made;
no ground, isotropic antennas, the ray engine): the tracer's radio map as released is the truth
of the local mean (a Monte Carlo average over each pixel), the engine's map the prediction. Each
pixel the tracer covers (both halves of its rays, outside the buildings) is given its mechanism
by the engine's excess loss over free space (``rainuav.radio.measured.prior``); per mechanism,
the pixels, the engine's error (median, RMS) and the share of errors within one and two of the
prior's local-mean spreads. The prior's spreads were set from published tables before this
comparison was run; nothing here was fitted to it.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
from rainuav.radio.measured.prior import MECHANISMS, SPREADS, excess_at
from rainuav.radio.reference import tracer
from rainuav.radio.reference.tracer_scenes import HELD_BACK, scene
from rainuav.radio.scene.terrain import flight_heights


def run(name: str, freq_hz: float, altitude_m: float, samples: int) -> dict:
    scn = tracer.isotropic_scenario(scene(name, freq_hz, altitude_m))
    ours = 10 * np.log10(np.maximum(tracer.engine_gain(scn), 1e-30))
    tm = tracer.tracer_gain(scn, samples=samples)
    ok = tm.covered & ~tracer.inside_buildings(scn)[None]
    with np.errstate(divide="ignore"):
        truth = 10 * np.log10(tm.gain)
    a = scn.area
    x = np.linspace(a.x_min_m, a.x_max_m, ours.shape[2], endpoint=False) + a.resolution_m / 2
    y = np.linspace(a.y_min_m, a.y_max_m, ours.shape[1], endpoint=False) + a.resolution_m / 2
    gx, gy = np.meshgrid(x, y)
    gz = np.broadcast_to(flight_heights(scn), gx.shape)
    rows = {}
    for s in range(ours.shape[0]):
        ex = excess_at(scn, s, gx.ravel(), gy.ravel(), gz.ravel(), ours[s].ravel())
        ex = ex.reshape(gx.shape)
        err = truth[s] - ours[s]
        for k, mech in enumerate(MECHANISMS):
            lo, hi = {0: (-np.inf, 3.0), 1: (3.0, 20.0), 2: (20.0, np.inf)}[k]
            m = ok[s] & (ex > lo) & (ex <= hi)
            rows.setdefault(mech, []).append(err[m])
    out = {}
    for mech, parts in rows.items():
        e = np.concatenate(parts)
        sd = SPREADS[mech].local_db
        out[mech] = {
            "pixels": int(e.size),
            "median_db": float(np.median(e)) if e.size else None,
            "rms_db": float(np.sqrt(np.mean(e**2))) if e.size else None,
            "spread_db": sd,
            "within_one_sigma": float(np.mean(np.abs(e) <= sd)) if e.size else None,
            "within_two_sigma": float(np.mean(np.abs(e) <= 2 * sd)) if e.size else None,
        }
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scenes", nargs="+", default=list(HELD_BACK))
    ap.add_argument("--freq-ghz", type=float, default=3.5)
    ap.add_argument("--altitude", type=float, default=20.0)
    ap.add_argument("--samples", type=float, default=8e6)
    ap.add_argument("--json", type=Path, default=None)
    args = ap.parse_args()
    report = {}
    for name in args.scenes:
        report[name] = run(name, args.freq_ghz * 1e9, args.altitude, int(args.samples))
        for mech, r in report[name].items():
            if not r["pixels"]:
                print(f"{name}, {mech}: no pixels")
                continue
            print(f"{name}, {mech}: {r['pixels']} pixels, tracer - engine median "
                  f"{r['median_db']:+.1f} dB, RMS {r['rms_db']:.1f} dB; spread {r['spread_db']} dB "
                  f"holds {100 * r['within_one_sigma']:.0f}% within one sigma, "
                  f"{100 * r['within_two_sigma']:.0f}% within two", flush=True)  # fmt: skip
    if args.json:
        args.json.write_text(json.dumps(report, indent=1) + "\n")


if __name__ == "__main__":
    main()
