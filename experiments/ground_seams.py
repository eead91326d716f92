"""Seams in a map over a real DEM: the ground reflection against no ground, in one run.

    python experiments/ground_seams.py [--ground medium-dry] [--freq-ghz 28] [--out DIR]

The Jacksboro fault sample that matplotlib ships (a 3 arc-second DEM of rough, wooded hills in
Tennessee, about 90 m cells) written as a GeoTIFF; the ``uma`` network's 21 cells at 28 GHz over a
2 km x 2 km area of it at 10 m, the UAV 100 m above the ground, ray engine, clear air. The map is
made twice: with a ground reflection (``--ground``, a P.527 soil or ``pec``) and with none. For
each cell's power (dB, pixels where it is above -200 dBm), the jumps between neighbouring pixels
(east and north): their 90th percentile and the share over 6 dB, for both maps. A ground
reflection off the DEM's planar facets, mirror-like, shows as straight seams: jumps far beyond
those of the map without it. With the reflection weighted by the roughness of the terrain within
its first Fresnel zone (docs/physics.md section 8), the two stay close: the targets are the 90th
percentile within 0.5 dB of the map without ground and the share over 6 dB within 1.15 times it.
``--out``: also writes both maps of the strongest cell as a PNG.
"""

from __future__ import annotations

import argparse
import dataclasses
import platform
import tempfile
import time
from pathlib import Path

import numpy as np
from rainuav.radio.outputs.maps import build_radio_map
from rainuav.radio.scene.area import Area
from rainuav.radio.scene.presets import uma
from rainuav.radio.scene.scenario import Origin, TerrainFile


def jacksboro_tif(path: Path) -> Path:
    """matplotlib's Jacksboro DEM as a GeoTIFF in EPSG:4326 (rows north to south)."""
    import matplotlib.cbook as cbook
    import rasterio
    from rasterio.transform import from_origin

    d = cbook.get_sample_data("jacksboro_fault_dem.npz")
    z = np.asarray(d["elevation"], dtype="float32")
    west, north = float(d["xmin"]), float(d["ymin"])  # the sample's ymin is its north edge
    transform = from_origin(west, north, float(d["dx"]), float(d["dy"]))
    profile = {"driver": "GTiff", "height": z.shape[0], "width": z.shape[1], "count": 1,
               "dtype": "float32", "crs": "EPSG:4326", "transform": transform}  # fmt: skip
    with rasterio.open(path, "w", **profile) as dst:
        dst.write(z, 1)
    return path


def jumps(rss_dbm: np.ndarray) -> tuple[float, float]:
    """The 90th percentile (dB) of the jumps between neighbouring pixels of every cell's map and
    the share over 6 dB, over pixels where both neighbours are above -200 dBm."""
    out = []
    for m in rss_dbm:
        for d in (np.diff(m, axis=0), np.diff(m, axis=1)):
            ok = np.isfinite(d) & (np.abs(d) < 150)
            out.append(np.abs(d[ok]))
    j = np.concatenate(out)
    return float(np.percentile(j, 90)), float(np.mean(j > 6.0))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ground", default="medium-dry")
    ap.add_argument("--freq-ghz", type=float, default=28.0)
    ap.add_argument("--out", type=Path, default=None)
    ap.add_argument(
        "--roughness-m", type=float, default=None,
        help="the DEM's unresolved roughness (terrain.roughness_m; default its default)",
    )  # fmt: skip
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        dem = jacksboro_tif(Path(tmp) / "jacksboro.tif")
        base = uma(0.0, args.freq_ghz * 1e9)
        scn = dataclasses.replace(
            base,
            engine="ray",
            origin=Origin(lat_deg=36.59, lon_deg=-84.25),
            terrain=TerrainFile(str(dem))
            if args.roughness_m is None
            else TerrainFile(str(dem), roughness_m=args.roughness_m),
            area=Area(0.0, 2000.0, 0.0, 2000.0, altitude_m=100.0, resolution_m=10.0),
        )
        stats = {}
        maps = {}
        for ground in (args.ground, "none"):
            t = time.perf_counter()
            rm = build_radio_map(dataclasses.replace(scn, ground=ground), cache=False)
            maps[ground] = rm.rss_dbm
            p90, share = jumps(rm.rss_dbm)
            stats[ground] = (p90, share, time.perf_counter() - t)
    rough = getattr(scn.terrain, "roughness_m", 0.0)
    print(f"# {platform.processor() or platform.machine()}, Jacksboro DEM, uma, "
          f"{args.freq_ghz:g} GHz, 100 m, 200 x 200 pixels, roughness {rough:g} m")  # fmt: skip
    for g, (p90, share, sec) in stats.items():
        print(
            f"ground {g:>11}: jumps p90 {p90:5.2f} dB, over 6 dB {100 * share:5.2f}% ({sec:.1f} s)"
        )
    (p_g, s_g, _), (p_n, s_n, _) = stats[args.ground], stats["none"]
    print(f"p90 difference {p_g - p_n:+.2f} dB (target within 0.5), "
          f"share ratio {s_g / max(s_n, 1e-12):.2f} (target within 1.15)")  # fmt: skip
    if args.out is not None:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        args.out.mkdir(parents=True, exist_ok=True)
        m = int(np.argmax(np.nanmean(maps["none"], axis=(1, 2))))
        fig, ax = plt.subplots(1, 2, figsize=(11, 4.8), layout="constrained")
        for a, g in zip(ax, (args.ground, "none"), strict=True):
            im = a.imshow(maps[g][m], origin="lower", extent=(0, 2000, 0, 2000), cmap="viridis")
            a.set_title(f"cell {m}, ground {g}")
            fig.colorbar(im, ax=a, label="dBm")
        fig.savefig(args.out / "ground_seams.png", dpi=90)


if __name__ == "__main__":
    main()
