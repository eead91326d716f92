"""Which kinds of path carry the power where the ray engine and the tracer's path solver part
(issue of the real city: what the engine misses or overdoes, found from the paths by kind).

    python experiments/tracer_path_kinds.py [--scene helsinki_b] [--sites 0 1 2] [--step 4]
        [--freq-ghz 3.5] [--altitude 20] [--pol v] [--samples 1e6] [--json FILE]

On one scene (``rainuav.radio.reference.tracer_scenes``; isotropic antennas, no ground, the
wedge coefficient of ITU-R P.526-15 section 6), the building effect (with the buildings less
without, dB) of the ray engine against the tracer's path solver at every ``--step``-th pixel's
centre (``rainuav.radio.reference.tracer_paths.path_gain_by_kind``: exact paths, split by the
interactions along each). The pixels the path solver reaches are grouped by their distance from
the site (within and beyond 400 m), and within each into the path solver's light (effect above
-6 dB) and shadow, and the shadow into the pixels where the engine is more than 6 dB darker
than the path solver, more than 6 dB brighter, and the rest. For each group: the pixels, the
median engine - path solver difference, and the share of the path solver's power that each kind
of path carries there (the groups' power summed). A diagnosis: no setting of the engine is
chosen by it. About a minute a site on 2 cores at ``--step 4``.
"""

from __future__ import annotations

import argparse
import json
import platform
import time
from pathlib import Path

import numpy as np
from rainuav.radio.reference.tracer import engine_gain, inside_buildings, isotropic_scenario
from rainuav.radio.reference.tracer_paths import PATH_KINDS, path_gain_by_kind
from rainuav.radio.reference.tracer_scenes import SCENES, scene

SHADOW_DB = -6.0
PART_DB = 6.0
FAR_M = 400.0


def groups(effect_engine: np.ndarray, effect_paths: np.ndarray, far: np.ndarray) -> dict:
    """The pixel groups of one site (the module's docstring), as boolean masks."""
    d = effect_engine - effect_paths
    out = {}
    for where, m in (("near", ~far), ("far", far)):
        lit = m & (effect_paths >= SHADOW_DB)
        shadow = m & (effect_paths < SHADOW_DB)
        out[f"{where}, light"] = lit
        out[f"{where}, shadow, engine > 6 dB darker"] = shadow & (d < -PART_DB)
        out[f"{where}, shadow, engine > 6 dB brighter"] = shadow & (d > PART_DB)
        out[f"{where}, shadow, within 6 dB"] = shadow & (np.abs(d) <= PART_DB)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scene", default="helsinki_b", choices=sorted(SCENES))
    ap.add_argument("--sites", type=int, nargs="+", default=None, help="site indices (all)")
    ap.add_argument("--step", type=int, default=4)
    ap.add_argument("--freq-ghz", type=float, default=3.5)
    ap.add_argument("--altitude", type=float, default=20.0)
    ap.add_argument("--pol", default="v", choices=["v", "h"])
    ap.add_argument("--samples", type=float, default=1e6)
    ap.add_argument("--json", type=Path, default=None)
    args = ap.parse_args()
    t0 = time.perf_counter()
    base = scene(args.scene, args.freq_ghz * 1e9, args.altitude, args.pol)
    keep = range(len(base.sites)) if args.sites is None else args.sites
    base = base.replace(sites=[base.sites[k] for k in keep])
    with_b, without = isotropic_scenario(base), isotropic_scenario(base, buildings=False)
    kw = {"samples": int(args.samples), "step": args.step}
    kinds = path_gain_by_kind(with_b, **kw)
    free = sum(path_gain_by_kind(without, **kw).values())
    paths = sum(kinds.values())
    ours_b, ours_free = engine_gain(with_b), engine_gain(without)
    inside = inside_buildings(with_b)
    x, y = base.area.centres()
    gx, gy = np.meshgrid(x, y)
    rows = []
    print(f"{args.scene}, {args.freq_ghz:g} GHz, {args.pol.upper()}, UAV at {args.altitude:g} m, "
          f"every {args.step}th pixel, {int(args.samples):,} candidate rays a site")  # fmt: skip
    print(f"{'site':>4} {'group':<40} {'pixels':>6} {'eng-paths':>9}  "
          + "  ".join(f"{k[:14]:>14}" for k in PATH_KINDS))  # fmt: skip
    for s, site in enumerate(base.sites):
        ok = (paths[s] > 0) & (free[s] > 0) & (ours_b[s] > 0) & ~inside
        with np.errstate(divide="ignore", invalid="ignore"):
            e_paths = 10 * np.log10(paths[s] / free[s])
            e_ours = 10 * np.log10(ours_b[s] / ours_free[s])
        far = np.hypot(gx - site.x_m, gy - site.y_m) > FAR_M
        for name, m in groups(e_ours, e_paths, far).items():
            m = m & ok
            n = int(m.sum())
            share = {k: float(kinds[k][s][m].sum() / max(paths[s][m].sum(), 1e-300))
                     for k in PATH_KINDS}  # fmt: skip
            med = float(np.median((e_ours - e_paths)[m])) if n else float("nan")
            rows.append({"site": int(keep[s]), "group": name, "pixels": n,
                         "median_engine_minus_paths_db": med, "power_share": share})  # fmt: skip
            print(f"{keep[s]:>4} {name:<40} {n:>6} {med:>9.2f}  "
                  + "  ".join(f"{100 * share[k]:>13.1f}%" for k in PATH_KINDS))  # fmt: skip
    seconds = time.perf_counter() - t0
    print(f"{seconds:.0f} s ({platform.processor() or platform.machine()})")
    if args.json:
        args.json.write_text(json.dumps({"args": vars(args) | {"json": str(args.json)},
                                         "rows": rows, "seconds": seconds}, indent=1))  # fmt: skip


if __name__ == "__main__":
    main()
