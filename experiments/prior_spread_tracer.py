"""The prior's local-mean spread by mechanism against Sionna RT's radio map (the page "How far to
trust a map").

    python experiments/prior_spread_tracer.py [--scenes district urban] [--tune [SCENE ...]]
        [--freq-ghz 3.5] [--altitude 20] [--samples 8e6] [--json FILE]

Per scene (by default the held-back ones, on which no choice of the engine's methods was made;
no ground, isotropic antennas, the ray engine): the tracer's radio map as released is the truth
of the local mean (a Monte Carlo average over each pixel), the engine's map the prediction. Each
pixel the tracer covers (both halves of its rays, outside the buildings) is given its mechanism
by the engine's excess loss over free space (``rainuav.radio.measured.prior``); per mechanism,
the pixels, the engine's error (median, RMS) and the share of errors within one and two of the
prior's local-mean spreads: the published ones (set from 3GPP's tables before this comparison
was run), and with ``--tune`` the engine's own, measured on other scenes.

``--tune SCENE ...``: on those scenes (none named: every scene but the held-back ones), per
mechanism, the error that 68.3% of the pixels stay within: the engine's measured spread (the page
"How far to trust a map" records it). The ``--scenes`` never enter it.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
from rainuav.radio.measured.prior import MECHANISMS, SPREADS, excess_at, mechanism_of
from rainuav.radio.reference import tracer
from rainuav.radio.reference.tracer_scenes import HELD_BACK, SCENES, scene
from rainuav.radio.scene.terrain import flight_heights


def errors(name: str, freq_hz: float, altitude_m: float, samples: int) -> dict[str, np.ndarray]:
    """The tracer's minus the engine's power, dB, at every covered pixel, by mechanism."""
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
    out: dict[str, list] = {m: [] for m in MECHANISMS}
    for s in range(ours.shape[0]):
        ex = excess_at(scn, s, gx.ravel(), gy.ravel(), gz.ravel(), ours[s].ravel())
        mech = mechanism_of(ex).reshape(gx.shape)
        for k, m in enumerate(MECHANISMS):
            sel = ok[s] & (mech == k)
            out[m].append((truth[s] - ours[s])[sel])
    return {m: np.concatenate(v) for m, v in out.items()}


def scores(e: np.ndarray, sd: float) -> dict:
    if not e.size:
        return {"pixels": 0}
    return {
        "pixels": int(e.size), "median_db": float(np.median(e)),
        "rms_db": float(np.sqrt(np.mean(e**2))), "spread_db": sd,
        "within_one_sigma": float(np.mean(np.abs(e) <= sd)),
        "within_two_sigma": float(np.mean(np.abs(e) <= 2 * sd)),
    }  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scenes", nargs="+", default=list(HELD_BACK))
    ap.add_argument("--tune", nargs="*", default=None,
                    help="measure the engine's spreads on these scenes (none named: every "
                         "scene but the held-back ones)")  # fmt: skip
    ap.add_argument("--freq-ghz", type=float, default=3.5)
    ap.add_argument("--altitude", type=float, default=20.0)
    ap.add_argument("--samples", type=float, default=8e6)
    ap.add_argument("--json", type=Path, default=None)
    args = ap.parse_args()
    f, h, n = args.freq_ghz * 1e9, args.altitude, int(args.samples)
    tables = {"published": {m: SPREADS[m].local_db for m in MECHANISMS}}
    report: dict = {}
    if args.tune is not None:
        names = args.tune or [s for s in SCENES if s not in HELD_BACK]
        pooled: dict[str, list] = {m: [] for m in MECHANISMS}
        for name in names:
            for m, e in errors(name, f, h, n).items():
                pooled[m].append(e)
        got = {m: np.concatenate(v) for m, v in pooled.items()}
        tables["measured"] = {m: float(np.percentile(np.abs(e), 68.27)) if e.size else None
                              for m, e in got.items()}  # fmt: skip
        report["tuned_on"] = {"scenes": names, "spreads_db": tables["measured"],
                              "pixels": {m: int(e.size) for m, e in got.items()}}  # fmt: skip
        print(f"engine spreads measured on {', '.join(names)}: " + ", ".join(
            f"{m} {'n/a' if v is None else f'{v:.1f}'} dB ({got[m].size} px)"
            for m, v in tables["measured"].items()), flush=True)  # fmt: skip
    for name in args.scenes:
        err = errors(name, f, h, n)
        for label, table in tables.items():
            for m, e in err.items():
                if table[m] is None:
                    continue
                r = scores(e, table[m])
                report.setdefault(name, {}).setdefault(label, {})[m] = r
                if not r["pixels"]:
                    print(f"{name}, {m}: no pixels")
                    continue
                print(f"{name}, {m}: {r['pixels']} pixels, tracer - engine median "
                      f"{r['median_db']:+.1f} dB, RMS {r['rms_db']:.1f} dB; {label} spread "
                      f"{r['spread_db']:.1f} dB holds {100 * r['within_one_sigma']:.0f}% within "
                      f"one sigma, {100 * r['within_two_sigma']:.0f}% within two",
                      flush=True)  # fmt: skip
    if args.json:
        args.json.write_text(json.dumps(report, indent=1) + "\n")


if __name__ == "__main__":
    main()
