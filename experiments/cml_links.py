"""rainuav's rain medium against 500 real commercial microwave links (the validation page "Rain
against real links"; the method is [`rainuav.cml`][rainuav.cml]'s).

    python experiments/cml_links.py [--links 500] [--json FILE] [--figure FILE]

Prints bias, RMSE and correlation of the predicted against the measured rain attenuation by
frequency band and polarisation, for rainuav's medium and ITU-R P.838-3; ``--figure``: both
predictions against the measurements (five-minute intervals, density).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np
from rainuav.cml import compare, stats
from rainuav.radio.measured.prior import rain_spread_scores

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "docs" / "tutorials"))
from radiomap_in_rain import made_by


def figure(path: Path, res: dict) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    meas, ours, p838 = res["_arrays"][:3]
    fig, ax = plt.subplots(1, 2, figsize=(11, 4.8), layout="constrained", sharey=True)
    top = float(np.percentile(np.concatenate([meas, ours, p838]), 99.5))
    for axis, pred, title in ((ax[0], ours, "rainuav's medium"), (ax[1], p838, "ITU-R P.838-3")):
        im = axis.hexbin(meas, pred, gridsize=70, extent=(0, top, 0, top), bins="log",
                         mincnt=1, cmap="viridis")  # fmt: skip
        axis.plot([0, top], [0, top], "k--", lw=1)
        s = stats(pred, meas)
        axis.set_title(f"{title}: bias {s['bias_db']:+.2f} dB, RMSE {s['rmse_db']:.2f} dB, "
                       f"r {s['r']:.2f}", fontsize=10)  # fmt: skip
        axis.set_xlim(0, top)
        axis.set_ylim(0, top)
        axis.set_xlabel("measured rain attenuation, dB (5-min mean)")
    ax[0].set_ylabel("predicted from the radar's rain, dB")
    fig.colorbar(im, ax=ax, label="five-minute intervals")
    stamp = made_by("python experiments/cml_links.py")
    fig.suptitle(f"{res['links']} links, {res['intervals']} wet five-minute intervals ({stamp})",
                 fontsize=9)  # fmt: skip
    fig.savefig(path, dpi=110)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--links", type=int, default=500)
    ap.add_argument("--json", type=Path, default=None)
    ap.add_argument("--figure", type=Path, default=None)
    args = ap.parse_args()
    t0 = time.perf_counter()
    res = compare(args.links)
    print(f"{res['links']} links, {res['intervals']} wet 5-min intervals "
          f"({time.perf_counter() - t0:.0f} s)")  # fmt: skip
    print(f"{'band GHz':>10} {'pol':>4} {'n':>7} | {'rainuav bias rmse r':>22} | "
          f"{'P.838 bias rmse r':>22}")  # fmt: skip
    rows = [*res["groups"], {"band_ghz": ["all", ""], "pol": "", **res["all"],
                             "n": res["all"]["rainuav"]["n"]}]  # fmt: skip
    for g in rows:
        a, b = g["rainuav"], g["p838"]
        band = f"{g['band_ghz'][0]}-{g['band_ghz'][1]}"
        one = "{bias_db:+7.2f} {rmse_db:6.2f} {r:6.3f}"
        print(f"{band:>10} {g['pol']:>4} {a['n']:>7} | {one.format(**a)} | {one.format(**b)}")
    meas, ours, _, _, link = res["_arrays"]
    spread = rain_spread_scores(meas, ours, link)
    res["rain_spread"] = spread
    h = spread["held_out"]
    bands = []
    for b in h["by_band"]:
        lo, hi = b["loss_db"]
        bands.append(f"{lo:g}-{'' if hi is None else f'{hi:g}'} dB "
                     f"{100 * b['within_one_sigma']:.0f}%")  # fmt: skip
    print("the spread of a rain loss, tuned on the even links: "
          + ", ".join(f"{v:.2f}" for v in spread["tuned"]) + " dB by band; on the odd links "
          f"({h['intervals']} intervals): {100 * h['within_one_sigma']:.1f}% within one sigma, "
          f"{100 * h['within_two_sigma']:.1f}% within two, CRPS {h['crps_db']:.2f} dB (no "
          f"spread: {h['crps_no_spread_db']:.2f}); by band: " + ", ".join(bands))  # fmt: skip
    if args.figure:
        figure(args.figure, res)
    if args.json:
        args.json.write_text(json.dumps({k: v for k, v in res.items() if k != "_arrays"}, indent=1))


if __name__ == "__main__":
    main()
