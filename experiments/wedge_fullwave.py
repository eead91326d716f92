"""Which wedge coefficient is right for a concrete corner: the tracer's own (Sionna RT 2.2 as
released) or ITU-R P.526-15's, against a full-wave solution
([`rainuav.radio.reference.wedge_fullwave`][rainuav.radio.reference.wedge_fullwave]).

    python experiments/wedge_fullwave.py [--markdown] [--json FILE] [--figure FILE]
        [--from-json FILE]

Per case (a right-angled corner of a solid P.2040 block, a line source at 0.5 m from the edge at
3.5 GHz, 30 or 45 degrees from the lit face; the same in wavelengths at 28 GHz; a conducting
corner, where the exact series is a fourth column) and polarisation (soft: the field along the
edge, a vertical corner's vertical polarisation; hard: across it), the |difference| in dB of the
field round the corner from the FDFD's, median and 90th percentile over each region: the lit
face's reflection zone, the rest of the lit side, and the shadow (each 5 degrees clear of the
shadow and reflection boundaries). About 10 minutes on 2 cores (the FDFD solves).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np
from rainuav.radio.reference.wedge_fullwave import (
    WedgeCase,
    exact_pec,
    fdfd_total,
    p526_coefficient,
    tracer_coefficient,
    utd_total,
)

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "docs" / "tutorials"))
from radiomap_in_rain import made_by

CASES = {
    "concrete, 3.5 GHz, 45 deg": WedgeCase(3.5e9, "concrete", 45.0, 0.5),
    "concrete, 3.5 GHz, 30 deg": WedgeCase(3.5e9, "concrete", 30.0, 0.5),
    "concrete, 28 GHz, 45 deg": WedgeCase(28e9, "concrete", 45.0, 0.5 * 3.5 / 28.0),
    "metal, 3.5 GHz, 45 deg": WedgeCase(3.5e9, "metal", 45.0, 0.5),
}
PHI_DEG = np.arange(2.0, 269.0, 1.0)
METHODS = ("P.526 (engine)", "faces at the incident ray", "tracer, P.526", "tracer as released")


def _db(v: np.ndarray) -> np.ndarray:
    return 20.0 * np.log10(np.abs(v))


def regions(case: WedgeCase) -> dict[str, np.ndarray]:
    """The field points of each region (module docstring), as masks over ``PHI_DEG``."""
    _, phi1 = case.source()
    p1 = math.degrees(phi1)
    d = PHI_DEG
    return {
        "reflection zone": d < 180.0 - p1 - 5.0,
        "lit": (d > 180.0 - p1 + 5.0) & (d < 180.0 + p1 - 5.0),
        "shadow": d > 180.0 + p1 + 5.0,
    }


def run_case(case: WedgeCase) -> dict:
    phi = np.radians(PHI_DEG)
    out: dict = {"case": case.__dict__, "pols": {}}
    for soft in (True, False):
        t0 = time.perf_counter()
        ref = _db(fdfd_total(case, phi, soft))
        solve_s = time.perf_counter() - t0
        fields = {
            METHODS[0]: utd_total(case, phi, soft, p526_coefficient(case, phi, soft)),
            METHODS[1]: utd_total(case, phi, soft, p526_coefficient(case, phi, soft, "incident")),
            METHODS[2]: utd_total(case, phi, soft, tracer_coefficient(case, phi, soft, "p526")),
            METHODS[3]: utd_total(case, phi, soft, tracer_coefficient(case, phi, soft, "sionna")),
        }
        if case.material == "metal":
            fields["exact series"] = exact_pec(case, phi, soft)
        rows = {}
        for region, mask in regions(case).items():
            rows[region] = {}
            for name, f in fields.items():
                err = np.abs(_db(f) - ref)[mask]
                err = err[np.isfinite(err)]
                rows[region][name] = {
                    "median": float(np.median(err)),
                    "p90": float(np.quantile(err, 0.9)),
                    "points": int(err.size),
                }
        out["pols"]["soft" if soft else "hard"] = {
            "rows": rows,
            "fdfd_db": ref.tolist(),
            "fields_db": {k: _db(v).tolist() for k, v in fields.items()},
            "fdfd_s": solve_s,
        }
    return out


def figure(path: Path, result: dict, name: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(12, 4.2), layout="constrained", sharey=True)
    for ax, pol in zip(axes, ("soft", "hard"), strict=True):
        r = result["pols"][pol]
        ax.plot(PHI_DEG, r["fdfd_db"], "k", lw=2.5, label="full wave (FDFD, ceviche)")
        styles = ("C0--", "C1-.", "C2:", "C3-", "C4--")
        for (label, v), style in zip(r["fields_db"].items(), styles, strict=False):
            ax.plot(PHI_DEG, v, style, lw=1.3, label=label)
        ax.axvspan(180.0 + result["case"]["phi1_deg"], 270.0, color="0.9", zorder=0)
        ax.set_title(f"{name}, {pol} (field {'along' if pol == 'soft' else 'across'} the edge)")
        ax.set_xlabel("angle from the lit face, degrees (grey: shadow)")
        ax.set_xlim(0, 270)
        ax.set_ylim(-45, 10)
    axes[0].set_ylabel("field re free space, dB")
    axes[0].legend(loc="lower left", fontsize=8)
    fig.suptitle(made_by(f"python experiments/wedge_fullwave.py --figure {path.name}"))
    fig.savefig(path, dpi=80)


def markdown(results: dict[str, dict]) -> str:
    lines = [
        "| case | field | region | P.526 (engine's corners) | P.526, faces at the incident ray "
        "(engine's roof edges) | tracer with P.526 | tracer as released |",
        "|---|---|---|---|---|---|---|",
    ]
    for name, res in results.items():
        for pol, r in res["pols"].items():
            for region, row in r["rows"].items():
                cells = [f"{row[m]['median']:.2f} / {row[m]['p90']:.2f}" for m in METHODS]
                extra = ""
                if "exact series" in row:
                    extra = f" (exact series: {row['exact series']['median']:.2f} / "
                    extra += f"{row['exact series']['p90']:.2f})"
                lines.append(f"| {name}{extra} | {pol} | {region} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", nargs="+", default=list(CASES), choices=list(CASES))
    ap.add_argument("--markdown", action="store_true")
    ap.add_argument("--json", type=Path)
    ap.add_argument("--figure", type=Path)
    ap.add_argument("--from-json", type=Path, help="the results of an earlier --json run")
    args = ap.parse_args()
    results = {}
    if args.from_json:
        results = json.loads(args.from_json.read_text())
        args.cases = []
    for name in args.cases:
        t0 = time.perf_counter()
        results[name] = run_case(CASES[name])
        print(f"{name}: {time.perf_counter() - t0:.0f} s", flush=True)
        for pol, r in results[name]["pols"].items():
            for region, row in r["rows"].items():
                cells = "  ".join(f"{m} {v['median']:.2f}/{v['p90']:.2f}" for m, v in row.items())
                print(f"  {pol:4s} {region:15s} {cells}", flush=True)
    if args.markdown:
        print(markdown(results))
    if args.json:
        args.json.write_text(json.dumps(results, indent=1))
    if args.figure:
        first = next(iter(results))
        figure(args.figure, results[first], first)


if __name__ == "__main__":
    main()
