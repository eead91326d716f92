"""The hybrid engine in time against its static builds (README, "Maps in time"):

    python benches/hybrid_in_time.py [--budget 1.0]

The `paper` network at 4.9 GHz (50 m pixels, where the PE carries part of the power) under two
moving rain cells (150 and 120 mm/h peaks, 12 and 10 m/s, over 5 mm/h): a series at 0, 60 and
120 s, whose PE part is marched once in clear air and attenuated like the direct ray, against a
static hybrid build of the frozen weather at each instant, whose PE marches through the rain.
Reported: the largest difference in SINR and, where the PE carries more than half of a cell's
power, in that cell's power, beside the rain loss on those pixels (what the approximation is
about), and the times.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from rainuav.radio import Area, build_radio_map, presets
from rainuav.radio.scene.scenario import PESettings
from rainuav.radio.scene.weather import Medium, RainCell

CELLS = [RainCell(700.0, 900.0, 500.0, 150.0, vx_m_s=12.0),
         RainCell(1300.0, 1300.0, 400.0, 120.0, vy_m_s=-10.0)]  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--budget", type=float, default=1.0, help="PE budget, 1e9 grid-point steps")
    args = ap.parse_args()
    scn = presets.paper().replace(
        area=Area(resolution_m=50.0),
        pe=PESettings(budget_gpoints=args.budget),
        medium=Medium(kind="cells", rain_rate_mm_h=5.0, cells=CELLS),
        engine="hybrid",
    )
    clear = build_radio_map(presets.with_rain(scn, 0.0), cache=False)
    t0 = time.perf_counter()
    series = build_radio_map(scn, times_s=[0.0, 60.0, 120.0], cache=False)
    t_series = time.perf_counter() - t0
    for k, t in enumerate(series.t_s):
        t1 = time.perf_counter()
        ref = build_radio_map(scn.replace(medium=scn.medium.at(t)), cache=False)
        t_ref = time.perf_counter() - t1
        pe = ref.pe_share > 0.5
        d_pe = np.abs(series.rss_dbm[k] - ref.rss_dbm)[pe]
        loss = (clear.rss_dbm - ref.rss_dbm)[pe]
        print(
            f"t = {t:5.0f} s: SINR differs by at most "
            f"{np.abs(series.sinr_db[k] - ref.sinr_db).max():.4f} dB; where the PE carries "
            f"over half ({pe.sum()} cell-pixels, rain loss there up to {loss.max():.3f} dB, "
            f"mean {loss.mean():.3f}), power by at most {d_pe.max():.4f} dB; static hybrid "
            f"build {t_ref:.1f} s"
        )
    print(f"the series (3 slices) took {t_series:.1f} s: {series.timings}")


if __name__ == "__main__":
    main()
