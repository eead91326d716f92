"""Plans on a map corrected by measurements, flown on the truth (the guide page "Maps from
measurements" and the results page).

    python experiments/measured_plans.py [--worlds 101 102 103] [--starts 20] [--json FILE]

The worlds are those of ``experiments/measured_maps.py``: the prior ``uma`` at 28 GHz in clear
air (200 x 200 pixels of 10 m), each truth the ``rain_cell`` weather over sites whose powers,
tilts and azimuths are off. Logs fly 0, 1, 4 and 10 east-west lines (0, 0.5, 2 and 5% of the
pixels: measurements along previous flights). The task: the ``"outage"`` reward (a move costs 1,
and ``mu`` = 2 more where the SINR is below the ``uma`` threshold), one destination, ``--starts``
starts drawn from the world's seed. Four exact plans from each start: on the prior, on the
corrected map's mean, chance-weighted on the corrected map (a move costs ``1 + mu P``, ``P`` the
pixel's outage probability from the corrected map's deviation), and on the truth itself. Each is
flown on the truth; the table gives the mean cost over the truth's own plan.

Each plan's **predicted outage** (the mean of its moves' outage probabilities on the map it was
planned on: the prior's spreads by mechanism, or the corrected map's) is set beside its
**realised outage** on the truth (the share of its moves that end below the threshold there).
The truth is a map of local means, so both are of the local mean: the probabilities use the
local mean's spread alone (``sample=False``).

Where a plan set's realised outage comes from is printed beside it: of its moves that end in
outage on the truth, how many the map gave a probability under 5%, and there the serving cell's
error and spread on the map (of the cell the map has serving).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import time
from pathlib import Path

import numpy as np
from measured_maps import worlds
from rainuav.nav import planner
from rainuav.nav.field import SignalField, pixel_index
from rainuav.nav.task import NavConfig
from rainuav.radio.measured import correct_map, outage_probability
from rainuav.radio.measured.outage import path_outage_draws
from rainuav.radio.measured.synthetic import sample_log
from rainuav.radio.scene.presets import SINR_THRESHOLDS_DB

MU = 2.0
GOAL = (1400.0, 1600.0)
PLAN_LINES = (0, 1, 4, 10)


def _field(values: np.ndarray, rm) -> SignalField:
    return SignalField(values, rm.extent_m, "sinr_db", rm.serving_cell, rm.not_flyable)


def cost_on(truth, path: np.ndarray, thr: float) -> float:
    """The path's moves plus ``MU`` per move ending where the truth's SINR is below ``thr``."""
    r, c = pixel_index(truth.sinr_db.shape, truth.extent_m, path[1:, 0], path[1:, 1])
    return float(len(path) - 1 + MU * np.sum(truth.sinr_db[r, c] < thr))


def outage_on(truth, prob: np.ndarray, path: np.ndarray, thr: float) -> tuple[float, float]:
    """The path's predicted outage share (its moves' mean probability in ``prob``) and its
    realised one (the share of its moves ending below ``thr`` on the truth)."""
    r, c = pixel_index(truth.sinr_db.shape, truth.extent_m, path[1:, 0], path[1:, 1])
    return float(np.mean(prob[r, c])), float(np.mean(truth.sinr_db[r, c] < thr))


def misses_on(rm, truth, prob: np.ndarray, paths: list[np.ndarray], thr: float) -> dict:
    """Where a set of plans' realised outage comes from: of the moves that end below ``thr`` on
    the truth, the share the map gave a probability under 5%, and at those moves the error of
    the cell the map has serving (map minus truth, dB) and its spread on the map (local mean),
    medians."""
    where = [pixel_index(truth.sinr_db.shape, truth.extent_m, p[1:, 0], p[1:, 1]) for p in paths]
    r, c = (np.concatenate(a) for a in zip(*where, strict=True))
    out = truth.sinr_db[r, c] < thr
    sure = out & (prob[r, c] < 0.05)
    cell = rm.serving_cell[r[sure], c[sure]]
    err = rm.rss_dbm[cell, r[sure], c[sure]] - truth.rss_dbm[cell, r[sure], c[sure]]
    std = getattr(rm, "rss_std_db", None)
    spread = None
    if std is not None and sure.any():
        spread = float(np.median(std[cell, r[sure], c[sure]]))
    return {"outage_moves": int(out.sum()),
            "outage_moves_under_5pct": int(sure.sum()),
            "under_5pct_error_db": float(np.median(err)) if sure.any() else None,
            "under_5pct_spread_db": spread}  # fmt: skip


def interval_on(rm, truth, path: np.ndarray, thr: float) -> tuple[bool, float]:
    """Whether the path's realised outage share on the truth lies within the 5-95% interval of
    its share drawn whole on the map ``rm`` (``path_outage_draws``, of the local mean), and the
    realised share's distance from the drawn mean in drawn standard deviations."""
    r, c = pixel_index(truth.sinr_db.shape, truth.extent_m, path[1:, 0], path[1:, 1])
    got = path_outage_draws(rm, (r, c), thr, draws=500, sample=False)
    real = float(np.mean(truth.sinr_db[r, c] < thr))
    inside = got["outage_share_p5"] <= real <= got["outage_share_p95"]
    z = (real - got["expected_outage_share"]) / max(got["spread_along_path"], 1e-9)
    return inside, z


def run(seeds: list[int], n_starts: int) -> list[dict]:
    thr = SINR_THRESHOLDS_DB["uma"]
    task = NavConfig(goal_m=GOAL, reward="outage", mu=MU, min_db=thr, max_steps=600)
    rows = []
    for w in seeds:
        prior, truth = worlds(w)
        rng = np.random.default_rng(2000 + w)
        starts = rng.uniform(100.0, 1900.0, size=(n_starts, 2))
        starts = np.round(starts / 10.0) * 10.0 + 5.0
        best = [cost_on(truth, p.path_m, thr) for p in
                planner.plan_on(_field(truth.sinr_db, truth), task, starts)]  # fmt: skip
        for lines in PLAN_LINES:
            t0 = time.perf_counter()
            if lines == 0:
                mean_map, prob = prior, None
            else:
                log = sample_log(truth, lines / 200, cells=5, seed=1000 + w)
                cm = correct_map(prior, log, cross_validate=False)
                mean_map, prob = cm, outage_probability(cm, thr, sample=False)
            shown = prob if prob is not None else outage_probability(prior, thr, sample=False)
            plans = {"mean": planner.plan_on(_field(mean_map.sinr_db, prior), task, starts)}
            if prob is not None:
                chance = dataclasses.replace(task, reward="chance")
                field = SignalField(
                    mean_map.sinr_db, prior.extent_m, "sinr_db", prior.serving_cell,
                    prior.not_flyable, outage_p=prob,
                )  # fmt: skip
                plans["chance"] = planner.plan_on(field, chance, starts)
            for kind, ps in plans.items():
                costs = [cost_on(truth, p.path_m, thr) for p in ps]
                excess = np.array(costs) / np.array(best) - 1.0
                pred, real = zip(*(outage_on(truth, shown, p.path_m, thr) for p in ps),
                                 strict=True)  # fmt: skip
                inside, z = zip(*(interval_on(mean_map, truth, p.path_m, thr) for p in ps),
                                strict=True)  # fmt: skip
                miss = misses_on(mean_map, truth, shown, [p.path_m for p in ps], thr)
                rows.append({"world": w, "lines": lines, "share": lines / 200, "plan": kind,
                             "excess_mean": float(excess.mean()),
                             "excess_median": float(np.median(excess)),
                             "predicted_outage": float(np.mean(pred)),
                             "realised_outage": float(np.mean(real)),
                             "plans": len(ps),
                             "within_90_interval": float(np.mean(inside)),
                             "within_one_spread": float(np.mean(np.abs(z) <= 1.0)),
                             **miss,
                             "seconds": time.perf_counter() - t0})  # fmt: skip
                r = rows[-1]
                print(f"world {w}, {lines:2d} lines ({lines / 2:.1f}%), plan on the "
                      f"{'prior' if lines == 0 else 'corrected ' + kind}: cost on the truth "
                      f"+{100 * excess.mean():.1f}% (median +{100 * np.median(excess):.1f}%) "
                      f"over the truth's own plan; outage predicted "
                      f"{100 * r['predicted_outage']:.1f}%, realised "
                      f"{100 * r['realised_outage']:.1f}%; realised within the drawn 5-95% "
                      f"interval for {100 * r['within_90_interval']:.0f}% of the plans, within "
                      f"one spread for {100 * r['within_one_spread']:.0f}%; of its "
                      f"{miss['outage_moves']} moves in outage {miss['outage_moves_under_5pct']} "
                      f"had P < 5% (the map's serving cell off by "
                      f"{miss['under_5pct_error_db']} dB there, spread "
                      f"{miss['under_5pct_spread_db']} dB)",
                      flush=True)  # fmt: skip
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--worlds", type=int, nargs="+", default=[101, 102, 103])
    ap.add_argument("--starts", type=int, default=20)
    ap.add_argument("--json", type=Path, default=None)
    args = ap.parse_args()
    rows = run(args.worlds, args.starts)
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1) + "\n")


if __name__ == "__main__":
    main()
