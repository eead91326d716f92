"""Writes ``examples/buildings.geojson``: building footprints in the form OpenStreetMap exports
them (GeoJSON, longitude/latitude on WGS 84, ``height``, ``building:levels``, ``roof:height``,
``building:material`` tags), for ``python -m rainuav.fly --footprints examples/buildings.geojson``.

Synthetic buildings over the shipped place (the sites of ``examples/sites.csv``): a district of
blocks 100 m square between streets 20 m wide, each block a perimeter building round a
courtyard, a row of houses sharing their walls (different heights, as a terrace), a tower
(60-150 m), or a park. A block within 60 m of a site stays a park (the masts stand free).
Not Zurich's real buildings: an example that shows what a city does.

    python examples/make_footprints.py

:func:`district` makes any number of such blocks anywhere (the benchmarks use it).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

CENTER = (47.3725, 8.5460)
HALF_SIZE_M = 1100.0
SEED = 3


def _rect(x0: float, y0: float, x1: float, y1: float) -> list[tuple[float, float]]:
    return [(x0, y0), (x1, y0), (x1, y1), (x0, y1)]


def _block(rng: np.random.Generator, x0: float, y0: float, size: float) -> list[dict]:
    """The buildings of one block (local metres) as (rings, tags)."""
    kind = rng.choice(["perimeter", "row", "tower", "park"], p=[0.35, 0.35, 0.12, 0.18])
    out = []
    if kind == "perimeter":
        depth = rng.uniform(12.0, 18.0)
        outer = _rect(x0, y0, x0 + size, y0 + size)
        inner = _rect(x0 + depth, y0 + depth, x0 + size - depth, y0 + size - depth)
        tags = {
            "building": "apartments",
            "building:levels": str(int(rng.integers(4, 8))),
            "roof:height": "3",
            "building:material": str(rng.choice(["brick", "concrete", "plaster"])),
        }
        out.append(([outer, inner[::-1]], tags))
    elif kind == "row":
        n = int(rng.integers(3, 7))
        edges = np.linspace(x0, x0 + size, n + 1)
        depth = rng.uniform(14.0, 25.0)
        for k in range(n):
            levels = int(rng.integers(2, 6))
            tags = {"building": "house", "height": f"{3.0 * levels + 1.5:.1f} m"}
            if rng.random() < 0.3:
                tags = {"building": "house", "building:levels": str(levels)}
            out.append(([_rect(edges[k], y0, edges[k + 1], y0 + depth)], tags))
    elif kind == "tower":
        side = rng.uniform(22.0, 34.0)
        ang = rng.uniform(0.0, math.pi / 2)
        cx, cy = x0 + size / 2, y0 + size / 2
        c, s = math.cos(ang), math.sin(ang)
        ring = [
            (cx + c * u - s * v, cy + s * u + c * v)
            for u, v in ((-side / 2, -side / 2), (side / 2, -side / 2),
                         (side / 2, side / 2), (-side / 2, side / 2))
        ]  # fmt: skip
        tags = {
            "building": "office",
            "height": str(round(float(rng.uniform(60.0, 150.0)))),
            "building:material": str(rng.choice(["glass", "concrete", "steel"])),
        }
        out.append(([ring], tags))
    return out


def district(
    lat: float,
    lon: float,
    half_size_m: float,
    seed: int,
    avoid_m: list[tuple[float, float]] = (),
    block_m: float = 100.0,
) -> dict:
    """A FeatureCollection of blocks ``block_m`` square (20 m streets) over a square
    ``half_size_m`` round (lat, lon); no building within 60 m of a point of ``avoid_m``
    (local metres)."""
    from rainuav.geo import Georef

    geo = Georef(lat, lon)
    rng = np.random.default_rng(seed)
    size, street = block_m, 20.0
    n = int(2 * half_size_m // (size + street))
    feats = []
    for i in range(n):
        for j in range(n):
            x0 = -half_size_m + j * (size + street) + street / 2
            y0 = -half_size_m + i * (size + street) + street / 2
            near = any(
                x0 - 60 <= ax <= x0 + size + 60 and y0 - 60 <= ay <= y0 + size + 60
                for ax, ay in avoid_m
            )
            if near:
                continue
            for rings, tags in _block(rng, x0, y0, size):
                coords = []
                for ring in rings:
                    xs, ys = np.array(ring).T
                    la, lo = geo.to_latlon(xs, ys)
                    pts = [
                        [round(float(a), 7), round(float(b), 7)]
                        for a, b in zip(lo, la, strict=True)
                    ]
                    coords.append([*pts, pts[0]])
                feats.append({
                    "type": "Feature",
                    "id": f"way/{len(feats) + 1}",
                    "properties": tags,
                    "geometry": {"type": "Polygon", "coordinates": coords},
                })  # fmt: skip
    return {"type": "FeatureCollection", "features": feats}


def main() -> Path:
    import csv

    from rainuav.geo import Georef

    here = Path(__file__).resolve().parent
    geo = Georef(*CENTER)
    with open(here / "sites.csv", encoding="utf-8") as f:
        rows = list(csv.DictReader(f))
    sites = [geo.to_local(float(r["lat"]), float(r["lon"])) for r in rows]
    avoid = [(float(x), float(y)) for x, y in sites]
    fc = district(*CENTER, HALF_SIZE_M, SEED, avoid)
    out = here / "buildings.geojson"
    tmp = out.with_suffix(".tmp")
    tmp.write_text(json.dumps(fc, separators=(",", ":")) + "\n", encoding="utf-8")
    tmp.replace(out)
    print(f"wrote {out} ({len(fc['features'])} buildings)")
    return out


if __name__ == "__main__":
    main()
