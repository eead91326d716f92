"""Measures the README's "What rain does" table: the per-pixel SINR change against clear air.

python docs/what_rain_does.py ray       # seconds
python docs/what_rain_does.py hybrid    # minutes (the PE marches)
"""

from __future__ import annotations

import sys
import time

import numpy as np
from rainuav.radio import build_radio_map, presets


def main(engine: str) -> None:
    for name, freq in (("paper", 4.9e9), ("uma", 4.9e9), ("uma", 28e9), ("rain_cell", 28e9)):
        make = presets.PRESETS[name]
        clear_scn = presets.with_rain(make(freq_hz=freq).replace(engine=engine), 0.0)
        clear = build_radio_map(clear_scn)
        th = presets.SINR_THRESHOLDS_DB[name]
        variants = [(f"{r} mm/h", presets.with_rain(clear_scn, r)) for r in (25.0, 50.0, 100.0)]
        if name == "rain_cell":
            variants = [("cell", make(freq_hz=freq).replace(engine=engine))]
        for label, scn in variants:
            t = time.perf_counter()
            rain = build_radio_map(scn)
            d = rain.sinr_db - clear.sinr_db
            p5, p50, p95 = np.percentile(d, [5, 50, 95])
            print(
                f"{name} {freq / 1e9:g} GHz, {label}: dSINR p5/median/p95 "
                f"{p5:+.2f}/{p50:+.2f}/{p95:+.2f} dB; below {th:g} dB: "
                f"clear {np.mean(clear.sinr_db < th):.3f}, rain {np.mean(rain.sinr_db < th):.3f}"
                f" ({time.perf_counter() - t:.1f} s)",
                flush=True,
            )


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "ray")
