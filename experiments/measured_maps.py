"""A map corrected by measurements against a truth the prior does not know (the guide page "Maps
from measurements" and the results page).

    python experiments/measured_maps.py [--worlds 101 102 103] [--json FILE] [--figure FILE]

The prior: ``uma`` at 28 GHz in clear air (ray engine, no ground, 200 x 200 pixels of 10 m).
Each truth: the ``rain_cell`` preset (a 100 mm/h cell in 5 mm/h rain) over the same sites with
each cell's power, tilt and azimuth off by draws of N(0, 3 dB), N(0, 2 deg), N(0, 5 deg) from the
world's seed. Logs: 1, 2, 4 and 10 east-west flight lines (0.5, 1, 2 and 5% of the pixels),
the 5 strongest cells at each pixel, 2 dB of noise. Scored at the pixels no line crossed, on the
serving cell's power: the median absolute error everywhere and where the prior was more than
8 dB off, the share of errors within one standard deviation, and the cross-validated RMSE.
The methods' settings were chosen on worlds 1 and 2 and other log seeds. The default worlds
(101-103) were first run before the deviation's last two changes (the offsets' uncertainty at
every pixel, the prior's RMS error for unmeasured cells), which that run prompted.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np
from rainuav.radio import Area, build_radio_map, presets
from rainuav.radio.measured import correct_map
from rainuav.radio.measured.synthetic import flight_line_pixels, perturbed_sites, sample_log

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "docs" / "tutorials"))
from radiomap_in_rain import made_by

LINES = (1, 2, 4, 10)


def worlds(seed: int):
    scn = presets.uma(0.0, 28e9, engine="ray", ground="none", area=Area(resolution_m=10.0))
    sites, _ = perturbed_sites(scn.sites, seed)
    truth = presets.rain_cell(5.0, 28e9, engine="ray", ground="none", area=scn.area, sites=sites)
    return build_radio_map(scn), build_radio_map(truth)


def serving(a: np.ndarray, truth) -> np.ndarray:
    ii, jj = np.indices(truth.serving_cell.shape)
    return a[truth.serving_cell, ii, jj]


def run(seeds: list[int]) -> tuple[list[dict], dict]:
    rows, keep = [], {}
    for w in seeds:
        prior, truth = worlds(w)
        h = truth.sinr_db.shape[0]
        e0 = serving(prior.rss_dbm, truth) - serving(truth.rss_dbm, truth)
        for lines in LINES:
            share = lines / h
            log = sample_log(truth, share, cells=5, seed=1000 + w)
            t0 = time.perf_counter()
            cm = correct_map(prior, log)
            sec = time.perf_counter() - t0
            held = np.ones(truth.sinr_db.shape, bool)
            px = flight_line_pixels(truth.sinr_db.shape, share)
            held[px[:, 0], px[:, 1]] = False
            e = serving(cm.rss_dbm, truth) - serving(truth.rss_dbm, truth)
            sd = serving(cm.rss_std_db, truth)
            big = held & (np.abs(e0) > 8)
            cv = cm.fit["cross_validation"]["stretch"]
            rows.append({
                "world": w, "lines": lines, "share": share, "rows": len(log), "seconds": sec,
                "prior_median_abs_db": float(np.median(np.abs(e0[held]))),
                "median_abs_db": float(np.median(np.abs(e[held]))),
                "prior_off_pixels": int(big.sum()),
                "prior_off_prior_db": float(np.median(np.abs(e0[big]))),
                "prior_off_corrected_db": float(np.median(np.abs(e[big]))),
                "within_one_sigma": float(np.mean(np.abs(e[held]) <= sd[held])),
                "cv_left_out": "stretch",
                "cv_rmse_prior_db": cv["prior"]["samples"]["rmse_db"],
                "cv_rmse_calibrated_db": cv["calibrated"]["samples"]["rmse_db"],
                "cv_rmse_corrected_db": cv["corrected"]["samples"]["rmse_db"],
                "cv_within_one_sigma": cv["corrected"]["samples"]["within_one_sigma"],
            })  # fmt: skip
            r = rows[-1]
            print(f"world {w}, {lines:2d} lines ({100 * share:.1f}%, {len(log)} rows, "
                  f"{sec:.1f} s): "
                  f"median |error| {r['prior_median_abs_db']:.2f} -> {r['median_abs_db']:.2f} dB; "
                  f"where the prior is >8 dB off ({r['prior_off_pixels']} px) "
                  f"{r['prior_off_prior_db']:.1f} -> {r['prior_off_corrected_db']:.2f} dB; "
                  f"{100 * r['within_one_sigma']:.0f}% within 1 sigma; CV RMSE "
                  f"{r['cv_rmse_prior_db']:.1f}/{r['cv_rmse_calibrated_db']:.1f}/"
                  f"{r['cv_rmse_corrected_db']:.1f} dB ({100 * r['cv_within_one_sigma']:.0f}%)",
                  flush=True)  # fmt: skip
            if w == seeds[0] and lines == 4:
                keep = {"prior": prior, "truth": truth, "corrected": cm, "pixels": px}
    return rows, keep


def figure(path: Path, rows: list[dict], keep: dict) -> None:
    import matplotlib
    import matplotlib.ticker

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    prior, truth, cm, px = keep["prior"], keep["truth"], keep["corrected"], keep["pixels"]
    ext = truth.extent_m
    fig, ax = plt.subplots(1, 4, figsize=(19, 4.6), layout="constrained")
    e0 = serving(prior.rss_dbm, truth) - serving(truth.rss_dbm, truth)
    e1 = serving(cm.rss_dbm, truth) - serving(truth.rss_dbm, truth)
    for a, data, title in ((ax[0], e0, "prior - truth"), (ax[1], e1, "corrected - truth")):
        im = a.imshow(data, origin="lower", extent=ext, cmap="RdBu_r", vmin=-15, vmax=15)
        a.set_title(f"{title}, serving cell [dB]", fontsize=10)
    fig.colorbar(im, ax=ax[:2], shrink=0.85, label="dB")
    for a in ax[:3]:
        a.plot(truth.x_m[px[:, 1]], truth.y_m[px[:, 0]], ",", color="k")
    sd = serving(cm.rss_std_db, truth)
    im = ax[2].imshow(sd, origin="lower", extent=ext, cmap="magma", vmin=0,
                      vmax=float(np.percentile(sd, 99)))  # fmt: skip
    ax[2].set_title(
        "standard deviation, serving cell [dB] (to its 99th percentile; lines: the log)",
        fontsize=10,
    )
    fig.colorbar(im, ax=ax[2], shrink=0.85, label="dB")
    for w in sorted({r["world"] for r in rows}):
        rr = [r for r in rows if r["world"] == w]
        s = [100 * r["share"] for r in rr]
        ax[3].plot(
            s, [r["prior_off_corrected_db"] for r in rr], "o-", label=f"world {w}: >8 dB off"
        )
        ax[3].plot(s, [r["median_abs_db"] for r in rr], "s--", color=ax[3].lines[-1].get_color(),
                   label=f"world {w}: all held-out")  # fmt: skip
    ax[3].axhline(3.0, color="k", lw=0.8, ls=":")
    ax[3].set_xscale("log")
    ax[3].set_xticks(sorted({100 * r["share"] for r in rows}))
    ax[3].xaxis.set_major_formatter(matplotlib.ticker.FormatStrFormatter("%g"))
    ax[3].xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    ax[3].set_xlabel("pixels measured [%]")
    ax[3].set_ylabel("median |corrected - truth| at held-out pixels [dB]")
    ax[3].legend(fontsize=7)
    stamp = made_by("python experiments/measured_maps.py")
    fig.suptitle(f"uma 28 GHz prior against rain_cell truth with wrong sites ({stamp})", fontsize=9)
    fig.savefig(path, dpi=100)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--worlds", type=int, nargs="+", default=[101, 102, 103])
    ap.add_argument("--json", type=Path, default=None)
    ap.add_argument("--figure", type=Path, default=None)
    args = ap.parse_args()
    rows, keep = run(args.worlds)
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1) + "\n")
    if args.figure:
        figure(args.figure, rows, keep)


if __name__ == "__main__":
    main()
