"""A map corrected by measurements where the truth is a full ray tracer's (the page "How far to
trust a map").

    python experiments/tracer_measured.py [--scene district] [--freq-ghz 3.5] [--altitude 20]
        [--samples 8e6] [--shares 0.005 0.02 0.05] [--json FILE]

The truth: Sionna RT's radio map as released of a held-back building scene (no ground, isotropic
antennas, one cell a site), at the pixels its rays cover outside the buildings. The prior: the
ray engine's map of the same scene. Logs fly east-west lines over the truth covering 0.5, 2 and
5% of the pixels, every cell at each pixel with 2 dB of noise. Scored at the covered pixels no
line crossed, on every cell's power: the median absolute error of the prior and of the corrected
map, everywhere and where the prior is more than 8 dB off, and the share of errors within one
and two of the corrected map's local-mean spread (the truth is a local mean) and of the prior's.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
from pathlib import Path

import numpy as np
from rainuav.radio.measured import correct_map
from rainuav.radio.measured.prior import MECHANISMS, excess_loss_db, mechanism_of, prior_spread
from rainuav.radio.measured.synthetic import flight_line_pixels, sample_log
from rainuav.radio.outputs.maps import build_radio_map
from rainuav.radio.outputs.sinr import RSS_FLOOR_DBM
from rainuav.radio.reference import tracer
from rainuav.radio.reference.tracer_scenes import scene


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scene", default="district")
    ap.add_argument("--freq-ghz", type=float, default=3.5)
    ap.add_argument("--altitude", type=float, default=20.0)
    ap.add_argument("--samples", type=float, default=8e6)
    ap.add_argument("--shares", type=float, nargs="+", default=[0.005, 0.02, 0.05])
    ap.add_argument("--json", type=Path, default=None)
    args = ap.parse_args()
    scn = tracer.isotropic_scenario(scene(args.scene, args.freq_ghz * 1e9, args.altitude))
    prior = build_radio_map(scn, cache=False)
    tm = tracer.tracer_gain(scn, samples=int(args.samples))
    covered = tm.covered & ~tracer.inside_buildings(scn)[None]
    with np.errstate(divide="ignore"):
        truth_db = np.where(covered, 10 * np.log10(tm.gain), RSS_FLOOR_DBM)
    truth = dataclasses.replace(prior, rss_dbm=truth_db)
    e0 = prior.rss_dbm - truth_db
    p_local = prior_spread(prior, model_db=0.0)[0]  # the tracer's sites are known exactly
    mech = mechanism_of(excess_loss_db(prior))
    rows = []
    for share in args.shares:
        log = sample_log(truth, share, cells=len(prior.rss_dbm), seed=3)
        cm = correct_map(prior, log, cross_validate=False)
        held = np.ones(prior.sinr_db.shape, bool)
        px = flight_line_pixels(prior.sinr_db.shape, share)
        held[px[:, 0], px[:, 1]] = False
        m = covered & held[None]
        e = cm.rss_dbm - truth_db
        big = m & (np.abs(e0) > 8)
        sd = cm.rss_std_db
        r = {
            "share": share, "rows": len(log), "pixels": int(m.sum()),
            "prior_median_abs_db": float(np.median(np.abs(e0[m]))),
            "median_abs_db": float(np.median(np.abs(e[m]))),
            "prior_off_pixels": int(big.sum()),
            "prior_off_prior_db": float(np.median(np.abs(e0[big]))),
            "prior_off_corrected_db": float(np.median(np.abs(e[big]))),
            "within_one_sigma": float(np.mean(np.abs(e[m]) <= sd[m])),
            "within_two_sigma": float(np.mean(np.abs(e[m]) <= 2 * sd[m])),
            "prior_off_within_one_sigma": float(np.mean(np.abs(e[big]) <= sd[big])),
            "prior_within_one_sigma": float(np.mean(np.abs(e0[m]) <= p_local[m])),
            "prior_within_two_sigma": float(np.mean(np.abs(e0[m]) <= 2 * p_local[m])),
            # by the prior's mechanism, a condition the forecast knows (the error does not)
            "within_one_sigma_by_mechanism": {
                name: float(np.mean(np.abs(e[m & (mech == k)]) <= sd[m & (mech == k)]))
                for k, name in enumerate(MECHANISMS) if (m & (mech == k)).any()
            },
            "prior_within_one_sigma_by_mechanism": {
                name: float(np.mean(np.abs(e0[m & (mech == k)]) <= p_local[m & (mech == k)]))
                for k, name in enumerate(MECHANISMS) if (m & (mech == k)).any()
            },
        }  # fmt: skip
        rows.append(r)
        print(f"{args.scene}, {100 * share:.1f}% of the pixels ({r['rows']} rows): median "
              f"|error| {r['prior_median_abs_db']:.2f} -> {r['median_abs_db']:.2f} dB; where the "
              f"prior is >8 dB off ({r['prior_off_pixels']} px) {r['prior_off_prior_db']:.1f} -> "
              f"{r['prior_off_corrected_db']:.1f} dB; corrected within one / two sigma "
              f"{100 * r['within_one_sigma']:.0f}% / {100 * r['within_two_sigma']:.0f}% "
              f"({100 * r['prior_off_within_one_sigma']:.0f}% within one where the prior is >8 dB "
              "off) "
              f"(the prior's spreads: {100 * r['prior_within_one_sigma']:.0f}% / "
              f"{100 * r['prior_within_two_sigma']:.0f}%); within one sigma by mechanism, "
              "corrected / prior: " + ", ".join(
                  f"{k} {100 * v:.0f}% / "
                  f"{100 * r['prior_within_one_sigma_by_mechanism'][k]:.0f}%"
                  for k, v in r["within_one_sigma_by_mechanism"].items()), flush=True)  # fmt: skip
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1) + "\n")


if __name__ == "__main__":
    main()
