"""The prior's local-mean spread by mechanism and distance against Sionna RT's radio map (the
page "How far to trust a map").

    python experiments/prior_spread_tracer.py [--freq-ghz 3.5] [--altitude 20] [--samples 8e6]
        [--json FILE] [--markdown] [--save-truth tests/tracer_truth.npz]

Every tracer scene (no ground, isotropic antennas, the ray engine): the tracer's radio map as
released is the truth of the local mean (a Monte Carlo average over each pixel), the engine's
map the prediction. Each pixel the tracer covers (both halves of its rays, outside the
buildings) is given its mechanism by the engine's excess loss over free space and its distance
from the site (``rainuav.radio.measured.prior``).

The engine's own spreads are measured (``measured_spreads``: per mechanism and distance band,
the error 68.27% of the pixels stay within) on the tuning pixels: every scene but the held-back
ones (``urban``, ``district``: no choice of the engine's methods was made on them) and the
held-back scenes' first site. They are reported, beside the published spreads, on the
held-back scenes' other sites, which no choice saw: per mechanism, the pixels, the engine's
error (median, RMS), the shares within one and two sigma and the CRPS. Each pixel's spread has
the tracer's own standard error added in quadrature (half the difference of its two halves, in
dB), as a local mean's has its own. The tuned table printed first is
``rainuav.radio.measured.prior.MEASURED``.

``--paths-step N`` checks the truth itself: on the held-back sites the tracer's exact path solver
(``rainuav.radio.reference.tracer_paths``: the same mechanisms, each path found solved exactly at
the pixel's centre, powers summed as the engine sums them) at every N-th pixel, and at the pixels
both cover, the engine's error against each truth and the measured table's coverage of both
(about 3 minutes at N = 4 on 2 cores).

``--save-truth`` writes the tracer's maps of the tuning sites (its two halves, linear gain) to a
file: the test suite reads it to check that the shipped table is what today's engine makes of
them, without tracing every scene again (it re-traces two scenes to check the file is the
tracer's).
"""

from __future__ import annotations

import argparse
import itertools
import json
from pathlib import Path

import numpy as np
from rainuav.radio.measured.prior import (
    MEASURED,
    MECHANISMS,
    SPREAD_DISTANCES_M,
    SPREADS,
    excess_at,
    measured_spreads,
    mechanism_of,
    spreads_of,
)
from rainuav.radio.measured.scores import crps_gaussian
from rainuav.radio.reference import tracer
from rainuav.radio.reference.saved import load_tracer_maps, save_tracer_maps
from rainuav.radio.reference.tracer_scenes import HELD_BACK, SPREAD_SCENES, scene
from rainuav.radio.scene.scenario import Scenario
from rainuav.radio.scene.terrain import flight_heights

TUNING_SITES = 1
"""The held-back scenes' sites the spreads are tuned on (their first); the others report."""


def pixels(
    name: str,
    freq_hz: float,
    altitude_m: float,
    samples: int,
    traced: tracer.TracerMap | None = None,
    scn: Scenario | None = None,
) -> dict[str, np.ndarray]:
    """Every pixel the tracer covers (both halves of its rays, outside the buildings), per site:
    the tracer's minus the engine's power (``error_db``), the engine's excess loss over free
    space (``excess_db``), the distance from the site (``distance_m``), the site's index
    (``site``), the tracer's own standard error of its mean in dB, from the difference of its
    two halves (``truth_se_db``: half that difference, the standard error of a mean of two), and
    the pixel's centre (``x_m``, ``y_m``). ``traced``: the tracer's map of the first sites (a
    saved truth, ``truth_maps``); None: traced here. ``scn``: the isotropic scenario (some of
    its sites); None: the scene's."""
    if scn is None:
        scn = tracer.isotropic_scenario(scene(name, freq_hz, altitude_m))
    tm = tracer.tracer_gain(scn, samples=samples) if traced is None else traced
    ours = 10 * np.log10(np.maximum(tracer.engine_gain(scn), 1e-30))[: tm.half_a.shape[0]]
    ok = tm.covered & ~tracer.inside_buildings(scn)[None]
    with np.errstate(divide="ignore", invalid="ignore"):  # uncovered pixels: -inf, NaN
        truth = 10 * np.log10(tm.gain)
        halves = 10 * np.log10(tm.half_a) - 10 * np.log10(tm.half_b)
    a = scn.area
    x = np.linspace(a.x_min_m, a.x_max_m, ours.shape[2], endpoint=False) + a.resolution_m / 2
    y = np.linspace(a.y_min_m, a.y_max_m, ours.shape[1], endpoint=False) + a.resolution_m / 2
    gx, gy = np.meshgrid(x, y)
    gz = np.broadcast_to(flight_heights(scn), gx.shape)
    out: dict[str, list] = {k: [] for k in ("error_db", "excess_db", "distance_m", "site",
                                            "truth_se_db", "x_m", "y_m")}  # fmt: skip
    for s in range(ours.shape[0]):
        site = scn.sites[s]
        ex = excess_at(scn, s, gx.ravel(), gy.ravel(), gz.ravel(), ours[s].ravel())
        sel = ok[s].ravel()
        d = np.hypot(np.hypot(gx - site.x_m, gy - site.y_m), gz - site.height_m).ravel()
        out["error_db"].append((truth[s] - ours[s]).ravel()[sel])
        out["excess_db"].append(ex[sel])
        out["distance_m"].append(d[sel])
        out["site"].append(np.full(int(sel.sum()), s))
        out["truth_se_db"].append(np.abs(halves[s]).ravel()[sel] / 2)
        out["x_m"].append(gx.ravel()[sel])
        out["y_m"].append(gy.ravel()[sel])
    return {k: np.concatenate(v) for k, v in out.items()}


def truth_maps(path: Path) -> dict[str, tracer.TracerMap]:
    """The tracer's maps of the tuning sites a ``--save-truth`` file holds, per scene."""
    return load_tracer_maps(path)


def save_truth(path: Path, maps: dict[str, tracer.TracerMap]) -> None:
    """Writes the tuning sites' tracer maps (float32: 1e-7 relative, far below 0.01 dB)."""
    keep = {n: TUNING_SITES if n in HELD_BACK else tm.half_a.shape[0] for n, tm in maps.items()}
    save_tracer_maps(path, {n: tracer.TracerMap(tm.half_a[: keep[n]], tm.half_b[: keep[n]])
                            for n, tm in maps.items()})  # fmt: skip


def paths_pixels(name: str, freq_hz: float, altitude_m: float, step: int, sites: slice,
                 ) -> tuple[Scenario, dict[str, np.ndarray]]:  # fmt: skip
    """The pixels of the tracer's exact path solver (every ``step``-th) at some sites of a scene,
    as ``pixels`` gives them; with the scenario of those sites."""
    from rainuav.radio.reference.tracer_paths import path_gain

    scn = tracer.isotropic_scenario(scene(name, freq_hz, altitude_m))
    scn = scn.replace(sites=scn.sites[sites])
    paths = path_gain(scn, samples=1_000_000, step=step)
    return scn, pixels(name, freq_hz, altitude_m, 0, paths, scn)


def paths_table(freq_hz: float, altitude_m: float, step: int) -> dict:
    """The engine's spreads measured as ``MEASURED`` is, on the tuning pixels, against the exact
    path solver in place of the radio map."""
    parts = []
    for name in SPREAD_SCENES:
        sites = slice(0, TUNING_SITES) if name in HELD_BACK else slice(None)
        parts.append(paths_pixels(name, freq_hz, altitude_m, step, sites)[1])
    e, ex, d = (np.concatenate([q[k] for q in parts]) for k in ("error_db", "excess_db",
                                                                  "distance_m"))  # fmt: skip
    return measured_spreads(e, ex, d, source="tuning pixels, exact paths")


def against_paths(name: str, freq_hz: float, altitude_m: float, traced: tracer.TracerMap,
                  step: int, tables: dict) -> dict:  # fmt: skip
    """The held-back sites' pixels both the radio map and the path solver cover (every ``step``-th):
    the engine's error against each, and each table's coverage of both."""
    scn, p_paths = paths_pixels(name, freq_hz, altitude_m, step, slice(TUNING_SITES, None))
    rmap = tracer.TracerMap(traced.half_a[TUNING_SITES:], traced.half_b[TUNING_SITES:])
    p_map = pixels(name, freq_hz, altitude_m, 0, rmap, scn)

    def key(q: dict) -> np.ndarray:  # a pixel's site and centre (to half a metre), as one number
        return q["site"] * 10**8 + np.round(2 * q["y_m"]) * 10**4 + np.round(2 * q["x_m"])

    both, i, j = np.intersect1d(key(p_map), key(p_paths), return_indices=True)
    out: dict = {"pixels": len(both), "step": step}
    d = p_map["distance_m"][i]
    for (label, q, k), (tname, table) in itertools.product(
        (("map", p_map, i), ("paths", p_paths, j)), tables.items()
    ):
        local, _ = spreads_of(p_map["excess_db"][i], d, 0.0, table)
        e = q["error_db"][k]
        sd = np.hypot(local, np.nan_to_num(q["truth_se_db"][k]))
        out[f"{label}, {tname} table"] = scores(e, sd) | {
            "abs_error_quantiles_db": {
                f"p{v}": float(np.percentile(np.abs(e), v)) for v in (50, 68, 90, 98)
            },
            "by_distance": {
                f"{lo}-{hi} m": scores(e[(d >= lo) & (d < hi)], sd[(d >= lo) & (d < hi)])
                for lo, hi in ((0, 400), (400, 800), (800, 5000))
            },
        }
    gap = p_map["error_db"][i] - p_paths["error_db"][j]  # the radio map less the exact paths
    out["map_minus_paths_db"] = {"median": float(np.median(gap)),
                                 "share_below_10_db": float(np.mean(gap < -10.0))}  # fmt: skip
    return out


def scores(e: np.ndarray, sd: np.ndarray) -> dict:
    if not e.size:
        return {"pixels": 0}
    return {
        "pixels": int(e.size), "median_db": float(np.median(e)),
        "rms_db": float(np.sqrt(np.mean(e**2))), "spread_db": float(np.median(sd)),
        "within_one_sigma": float(np.mean(np.abs(e) <= sd)),
        "within_two_sigma": float(np.mean(np.abs(e) <= 2 * sd)),
        "crps_db": float(np.mean(crps_gaussian(e, 0.0, sd))),
    }  # fmt: skip


def split(data: dict[str, dict[str, np.ndarray]], tuning: bool) -> dict[str, np.ndarray]:
    """The tuning pixels (every scene but the held-back ones, and the held-back scenes' first
    site) or the evaluation pixels (the held-back scenes' other sites), pooled."""
    parts = []
    for name, p in data.items():
        first = p["site"] < TUNING_SITES
        keep = np.ones(len(first), bool) if name not in HELD_BACK else first
        parts.append({k: v[keep if tuning else ~keep] for k, v in p.items()}
                     if tuning or name in HELD_BACK else None)  # fmt: skip
    got = [q for q in parts if q is not None]
    return {k: np.concatenate([q[k] for q in got]) for k in got[0]}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--freq-ghz", type=float, default=3.5)
    ap.add_argument("--altitude", type=float, default=20.0)
    ap.add_argument("--samples", type=float, default=8e6)
    ap.add_argument("--json", type=Path, default=None)
    ap.add_argument("--markdown", action="store_true", help="print the page's table too")
    ap.add_argument(
        "--save-truth",
        type=Path,
        default=None,
        help="write the tuning sites' tracer maps here (the test suite's file)",
    )
    ap.add_argument(
        "--paths-step",
        type=int,
        default=0,
        help="check the truth against the exact path solver at every N-th pixel",
    )
    args = ap.parse_args()
    f, h, n = args.freq_ghz * 1e9, args.altitude, int(args.samples)
    traced = {}
    for name in SPREAD_SCENES:
        traced[name] = tracer.tracer_gain(tracer.isotropic_scenario(scene(name, f, h)), samples=n)
    if args.save_truth:
        save_truth(args.save_truth, traced)
    data = {name: pixels(name, f, h, n, traced[name]) for name in SPREAD_SCENES}
    tune = split(data, True)
    tuned = measured_spreads(tune["error_db"], tune["excess_db"], tune["distance_m"],
                             source="tuning pixels")  # fmt: skip
    print(
        "measured on the tuning pixels ("
        + ", ".join(
            f"{m}: {'/'.join(f'{v:g}' for v in tuned[m].local_db)} dB"  # type: ignore[union-attr]
            for m in MECHANISMS
        )
        + f" at {'/'.join(f'{d:g}' for d in SPREAD_DISTANCES_M)} m); "
        "shipped: " + ", ".join(f"{m}: {MEASURED[m].local_db}" for m in MECHANISMS),
        flush=True,
    )
    tables = {"published": SPREADS, "measured": tuned}
    report: dict = {"tuned": {m: tuned[m].local_db for m in MECHANISMS},
                    "tuning_pixels": len(tune["error_db"])}  # fmt: skip
    rows = []
    for name in HELD_BACK:
        p = data[name]
        held = p["site"] >= TUNING_SITES
        e, ex, d, se = (p[k][held] for k in ("error_db", "excess_db", "distance_m", "truth_se_db"))
        se = np.nan_to_num(se)
        mech = mechanism_of(ex)
        for label, table in tables.items():
            local, _ = spreads_of(ex, d, 0.0, table)
            sd = np.hypot(local, se)  # the truth's own standard error, as for local means
            for k, m in [*enumerate(MECHANISMS), (None, "all")]:
                sel = np.ones(len(e), bool) if k is None else mech == k
                r = scores(e[sel], sd[sel])
                report.setdefault(name, {}).setdefault(label, {})[m] = r
                if r["pixels"]:
                    print(f"{name} sites {TUNING_SITES}+, {m}: {r['pixels']} pixels, tracer - "
                          f"engine median {r['median_db']:+.1f} dB, RMS {r['rms_db']:.1f} dB; "
                          f"{label} spread (median {r['spread_db']:.1f} dB) holds "
                          f"{100 * r['within_one_sigma']:.0f}% within one sigma, "
                          f"{100 * r['within_two_sigma']:.0f}% within two, CRPS "
                          f"{r['crps_db']:.2f}", flush=True)  # fmt: skip
        for m in (*MECHANISMS, "all"):
            a, b = report[name]["published"][m], report[name]["measured"][m]
            if a["pixels"]:
                rows.append(
                    f"| `{name}`, {m} | {a['pixels']:_} | ".replace("_", " ")
                    + f"{a['median_db']:+.1f} / "
                    f"{a['rms_db']:.1f} dB | {100 * a['within_one_sigma']:.0f}% / "
                    f"{100 * a['within_two_sigma']:.0f}%, {a['crps_db']:.2f} | "
                    f"{100 * b['within_one_sigma']:.0f}% / {100 * b['within_two_sigma']:.0f}%, "
                    f"{b['crps_db']:.2f} |"
                )
    if args.paths_step:
        paths = tables["measured against the paths"] = paths_table(f, h, args.paths_step)
        print("measured on the tuning pixels against the exact paths: " + ", ".join(
            f"{m}: {'/'.join(f'{v:g}' for v in np.atleast_1d(paths[m].local_db))}"
            for m in MECHANISMS), flush=True)  # type: ignore[union-attr]  # fmt: skip
    for name in HELD_BACK if args.paths_step else ():
        r = report.setdefault("against_paths", {})[name] = against_paths(
            name,
            f,
            h,
            traced[name],
            args.paths_step,
            {k: v for k, v in tables.items() if k != "published"},
        )
        for label in (k for k in r if "table" in k):
            q = r[label]
            far = q["by_distance"]
            print(f"{name} sites {TUNING_SITES}+ against the {label}, {r['pixels']} pixels both "
                  f"cover (every {args.paths_step}th): |engine error| p50/p68/p90/p98 "
                  + "/".join(f"{v:.2f}" for v in q["abs_error_quantiles_db"].values())
                  + f" dB; within one / two sigma {100 * q['within_one_sigma']:.0f}"
                  f" / {100 * q['within_two_sigma']:.0f}%; by distance "
                  + ", ".join(f"{k}: {100 * v.get('within_one_sigma', 0):.0f}%"
                              for k, v in far.items()), flush=True)  # fmt: skip
        g = r["map_minus_paths_db"]
        print(f"{name}: radio map less paths median {g['median']:+.2f} dB, "
              f"{100 * g['share_below_10_db']:.0f}% of the pixels more than 10 dB darker",
              flush=True)  # fmt: skip
    if args.markdown:
        print(
            "| scene, mechanism | pixels | tracer - engine, median / RMS | published: within "
            "one / two sigma, CRPS | measured: the same |\n|---|---|---|---|---|"
        )
        print("\n".join(rows))
    if args.json:
        args.json.write_text(json.dumps(report, indent=1) + "\n")


if __name__ == "__main__":
    main()
