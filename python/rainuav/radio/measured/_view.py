"""A cell seen from a set of points, as the calibration moves its parameters: its pattern
tabulated once in its own frame, and the geometry no offset changes (shared by the calibration,
the receive patterns and the prior's geometry)."""

from __future__ import annotations

import dataclasses
import functools
from typing import Any

import numpy as np

from rainuav.radio.scene.cell import Cell, pattern_by_key
from rainuav.radio.scene.scenario import Scenario, Site
from rainuav.radio.scene.terrain import surface_at

TABLE_STEP_DEG = 0.25
"""The step of a cell's tabulated pattern in azimuth and elevation, degrees."""
GAIN_FLOOR_DB = -80.0
"""The lowest gain a tabulated pattern holds, dBi (its nulls stay finite)."""


def _site_z(scn: Scenario, site: Site) -> float:
    return float(surface_at(scn, np.array([site.x_m]), np.array([site.y_m]))[0]) + site.height_m


@functools.lru_cache(maxsize=16)
def _pattern_table(key: tuple[Any, ...]) -> np.ndarray:
    """The pattern of cells with ``key`` in its own frame, dBi floored at ``GAIN_FLOOR_DB``,
    every ``TABLE_STEP_DEG`` in azimuth (-180..180) and elevation (-90..90)."""
    az = np.arange(-180.0, 180.0 + TABLE_STEP_DEG / 2, TABLE_STEP_DEG)
    el = np.arange(-90.0, 90.0 + TABLE_STEP_DEG / 2, TABLE_STEP_DEG)
    g = pattern_by_key(key).gain_dbi(*np.meshgrid(az, el, indexing="ij"))
    return np.maximum(np.asarray(g, dtype=float), GAIN_FLOOR_DB)


def _bilinear_table(t: np.ndarray, az: np.ndarray, el: np.ndarray) -> np.ndarray:
    fa = (az + 180.0) / TABLE_STEP_DEG
    fe = (el + 90.0) / TABLE_STEP_DEG
    ia = np.clip(np.floor(fa).astype(np.int64), 0, t.shape[0] - 2)
    ie = np.clip(np.floor(fe).astype(np.int64), 0, t.shape[1] - 2)
    wa, we = fa - ia, fe - ie
    return ((1 - wa) * ((1 - we) * t[ia, ie] + we * t[ia, ie + 1])
            + wa * ((1 - we) * t[ia + 1, ie] + we * t[ia + 1, ie + 1]))  # fmt: skip


class _View:
    """One cell seen from a set of points: what the gain change needs that no offset changes."""

    def __init__(
        self, scn: Scenario, site: Site, cell: Cell, x: Any, y: Any, z: Any, table: bool = False
    ) -> None:
        x, y, z = (np.asarray(v, dtype=float) for v in (x, y, z))
        self.cell, self.table = cell, table
        self.rho = np.hypot(x - site.x_m, y - site.y_m)
        self.az = np.degrees(np.arctan2(y - site.y_m, x - site.x_m))
        self.dz = z - _site_z(scn, site)
        self.g0 = self._gain(cell, self.dz)

    def _gain(self, cell: Cell, dz: np.ndarray) -> np.ndarray:
        el = np.clip(np.degrees(np.arctan2(dz, self.rho)) - cell.tilt_deg, -90.0, 90.0)
        az = (self.az - cell.azimuth_deg + 180.0) % 360.0 - 180.0
        if not self.table:
            g = pattern_by_key(cell.key()).gain_dbi(az, el)
            return np.maximum(np.asarray(g, dtype=float), GAIN_FLOOR_DB)
        return _bilinear_table(_pattern_table(cell.key()), az, el)

    def change_many(self, offsets: dict[str, np.ndarray]) -> np.ndarray:
        """``change()`` of a tabulated view for S sets of offsets at once (each (S,)), (S, N)."""
        s = len(next(iter(offsets.values())))

        def off(name: str) -> np.ndarray:
            return np.asarray(offsets.get(name, np.zeros(s)), dtype=float)[:, None]

        dz1 = self.dz[None, :] - off("height_m")
        el = np.clip(
            np.degrees(np.arctan2(dz1, self.rho)) - (self.cell.tilt_deg + off("tilt_deg")),
            -90.0, 90.0,
        )  # fmt: skip
        az = (self.az - (self.cell.azimuth_deg + off("azimuth_deg")) + 180.0) % 360.0 - 180.0
        g = _bilinear_table(_pattern_table(self.cell.key()), az, el)
        spread = 10 * np.log10((self.rho**2 + self.dz**2 + 1e-6) / (self.rho**2 + dz1**2 + 1e-6))
        return off("power_db") + g - self.g0 + spread

    def change(self, offsets: dict[str, float]) -> np.ndarray:
        dh = offsets.get("height_m", 0.0)
        moved = dataclasses.replace(
            self.cell,
            azimuth_deg=self.cell.azimuth_deg + offsets.get("azimuth_deg", 0.0),
            tilt_deg=self.cell.tilt_deg + offsets.get("tilt_deg", 0.0),
        )
        dz1 = self.dz - dh
        spread = 10 * np.log10((self.rho**2 + self.dz**2 + 1e-6) / (self.rho**2 + dz1**2 + 1e-6))
        return offsets.get("power_db", 0.0) + self._gain(moved, dz1) - self.g0 + spread


def _cells(scn: Scenario) -> list[tuple[Site, Cell]]:
    return [(s, c) for s in scn.sites for c in s.cells]
