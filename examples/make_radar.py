"""Writes ``examples/radar.nc``: a synthetic weather-radar product in the form real ones take
(CF NetCDF, reflectivity in dBZ on a latitude/longitude grid, a time axis of dates), for
``python -m rainuav.fly --weather examples/radar.nc``.

A convective cell over Zurich: 52 dBZ at its core (about 90 mm/h by Marshall-Palmer), 400 m
radius (1/e), moving east-north-east at 12 m/s, over 15 dBZ stratiform rain (0.3 mm/h), scanned
every 30 s for 6 minutes on a 0.0005 degree grid (about 38 x 56 m).

    python examples/make_radar.py
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import xarray as xr

LAT = np.arange(47.350, 47.395, 0.0005)
LON = np.arange(8.520, 8.575, 0.0005)
TIMES = np.datetime64("2026-06-01T14:00:00") + np.arange(13) * np.timedelta64(30, "s")
M_PER_DEG_LAT, M_PER_DEG_LON = 111_200.0, 75_400.0  # near 47.37 N


def main() -> Path:
    glat, glon = np.meshgrid(LAT, LON, indexing="ij")
    y = (glat - 47.365) * M_PER_DEG_LAT
    x = (glon - 8.535) * M_PER_DEG_LON
    frames = []
    for k in range(len(TIMES)):
        cx, cy = 12.0 * 0.92 * 30.0 * k, 12.0 * 0.39 * 30.0 * k
        core = 37.0 * np.exp(-((x - cx) ** 2 + (y - cy) ** 2) / (2 * 400.0**2))
        frames.append(15.0 + core)
    da = xr.DataArray(
        np.array(frames, dtype=np.float32),
        dims=("time", "lat", "lon"),
        coords={"time": TIMES, "lat": LAT, "lon": LON},
        name="reflectivity",
        attrs={"units": "dBZ", "long_name": "equivalent radar reflectivity factor"},
    )
    da["lat"].attrs = {"units": "degrees_north", "standard_name": "latitude"}
    da["lon"].attrs = {"units": "degrees_east", "standard_name": "longitude"}
    out = Path(__file__).with_name("radar.nc")
    da.to_dataset().to_netcdf(out, engine="h5netcdf")
    return out


if __name__ == "__main__":
    print(main())
