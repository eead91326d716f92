"""How far to trust a map, in one figure: the share of held-out errors within k sigma of each
predictive distribution, against the share a calibrated Gaussian holds (the page "How far to
trust a map").

    python experiments/trust_figure.py PATH/TO/flights.csv [--out docs/figures/trust_coverage.png]

Four predictive distributions, each on data no choice of its spread saw:

- the corrected map on the real flights (AERPAW, ``experiments/aerpaw_flights.py``'s log), one
  height left out at a time, single samples with both spreads;
- the physics map alone on the same flights at the heights its site error was not chosen on
  (50, 90, 110 m), with the default spreads (the measured table and ``SITE_DB``);
- the physics map alone against Sionna RT at the held-back sites of the city scenes (the
  measured table, sites known exactly; ``experiments/prior_spread_tracer.py``);
- a rain loss predicted from radar rain on pycomlink's links of odd index
  (``rainuav.radio.measured.prior.rain_spread_scores``).

A curve above the Gaussian's is too wide at that k, below it too sure.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import numpy as np
from aerpaw_flights import VALIDATION, read
from prior_spread_tracer import TUNING_SITES, pixels
from rainuav.cml import compare
from rainuav.radio.measured import read_log
from rainuav.radio.measured.fitting import _take, fit_correction
from rainuav.radio.measured.levels import prior_at
from rainuav.radio.measured.prior import (
    SITE_DB,
    excess_at,
    rain_spread_db,
    site_distance_at,
    spreads_of,
)
from rainuav.radio.outputs.maps import build_radio_map
from rainuav.radio.reference.tracer_scenes import HELD_BACK
from scipy.stats import norm

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "docs" / "tutorials"))
from radiomap_in_rain import made_by


def flights(path: Path) -> dict[str, np.ndarray]:
    """Standardised held-out errors on the flights: the corrected map (one height out) and the
    prior (at the heights its site error was not chosen on)."""
    with tempfile.TemporaryDirectory() as tmp:
        scn, p = read(path, 8, Path(tmp))
        rm = build_radio_map(scn)
        log = read_log(p, scn)
        prior = prior_at(rm, log)
    whole = fit_correction(rm, log, prior, params=("power_db", "height_m"))
    z = np.full(len(log), np.nan)
    for f in np.unique(log.flight):
        test = log.flight == f
        fc = fit_correction(rm, _take(log, ~test), prior[~test], params=("power_db", "height_m"),
                            like=whole, max_points=1000)  # fmt: skip
        mean, local, sample = fc.predict(_take(log, test), prior[test])
        z[test] = (log.rss_dbm[test] - mean) / np.hypot(local, sample)
    ex = excess_at(scn, 0, log.x_m, log.y_m, log.z_m, prior)
    dist = site_distance_at(scn, 0, log.x_m, log.y_m, log.z_m)
    local, sample = spreads_of(ex, dist, SITE_DB)
    nominal = np.array([round(float(np.median(log.alt_m[log.flight == f])) / 10) * 10
                        for f in log.flight])  # fmt: skip
    held = ~np.isin(nominal, VALIDATION)
    zp = (log.rss_dbm - prior) / np.hypot(local, sample)
    return {"flights, corrected map (one height out)": z,
            "flights, physics map alone (held-out heights)": zp[held]}  # fmt: skip


def tracer() -> np.ndarray:
    """Standardised errors of the physics map against the tracer at the held-back sites."""
    out = []
    for name in HELD_BACK:
        p = pixels(name, 3.5e9, 20.0, 8_000_000)
        held = p["site"] >= TUNING_SITES
        local, _ = spreads_of(p["excess_db"][held], p["distance_m"][held], 0.0)
        sd = np.hypot(local, np.nan_to_num(p["truth_se_db"][held]))
        out.append(p["error_db"][held] / sd)
    return np.concatenate(out)


def links() -> np.ndarray:
    """Standardised errors of rain losses on the links of odd index."""
    meas, ours, _, _, link = compare(500)["_arrays"]
    odd = link % 2 == 1
    sd = rain_spread_db(ours[odd])
    keep = sd > 0
    return ((meas - ours)[odd] / np.where(keep, sd, 1.0))[keep]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("flights", type=Path)
    ap.add_argument("--out", type=Path, default=Path("docs/figures/trust_coverage.png"))
    args = ap.parse_args()
    curves = flights(args.flights)
    curves["city scenes, physics map against Sionna RT (held-back sites)"] = tracer()
    curves["real links, rain loss from radar rain (held-out links)"] = links()
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    k = np.linspace(0.0, 3.0, 121)
    fig, ax = plt.subplots(figsize=(7.5, 5.2), layout="constrained")
    ax.plot(k, 2 * norm.cdf(k) - 1, "k--", lw=1.5, label="a calibrated Gaussian")
    for label, z in curves.items():
        a = np.abs(z[np.isfinite(z)])
        share = [(a <= v).mean() for v in k]
        one = 100 * (a <= 1).mean()
        ax.plot(k, share, lw=2, label=f"{label}: {one:.0f}% within one sigma ({len(a):,})")
        print(f"{label}: {len(a)} errors, {one:.1f}% within one sigma, "
              f"{100 * (a <= 2).mean():.1f}% within two", flush=True)  # fmt: skip
    ax.axvline(1.0, color="0.8", lw=1)
    ax.axvline(2.0, color="0.8", lw=1)
    ax.set_xlim(0, 3)
    ax.set_ylim(0, 1)
    ax.set_xlabel("k: the error within k standard deviations of the prediction")
    ax.set_ylabel("share of held-out errors")
    ax.legend(loc="lower right", fontsize=8)
    ax.set_title(made_by("python experiments/trust_figure.py FLIGHTS.csv"), fontsize=8)
    fig.savefig(args.out, dpi=110)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
