"""Preset scenarios (``rainuav.radio.presets``).

``paper``: the design paper's setting (section VI): a 2 km x 2 km airspace, the UAV at 100 m,
4.9 GHz, seven sites on a hexagon of radius 667 m around (1, 1) km, antennas at 25 m, one
Gaussian beam per site with the paper's source (elevation 5 degrees, half-power beamwidth
4.333 degrees). Choices the paper leaves open, made here: horizontal polarisation over a PEC
ground; 46 dBm per cell; noise -95 dBm (10 MHz, 9 dB noise figure: the scenario defaults);
beam azimuths (below) chosen so that the 100 m map has both good and weak regions;
Marshall-Palmer rain at 20 C, forward-scattering model.

``urban``: the same sites with three cells each (azimuths 30, 150, 270 degrees) and a block of
buildings south-west of the centre, tall enough to cast shadows at the flight altitude.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any

from rainuav.radio.scenario import Area, Building, Cell, Medium, Scenario, Site

__all__ = ["PRESETS", "paper", "urban", "with_rain"]

#: The paper's seven sites, km.
PAPER_SITES_KM = [
    (1.0, 1.0),
    (1.5774, 1.3333),
    (1.0, 1.6667),
    (0.4226, 1.3333),
    (0.4226, 0.6667),
    (1.0, 0.3333),
    (1.5774, 0.6667),
]
#: Beam azimuths (degrees counter-clockwise from east) of the paper preset, one per site.
PAPER_AZIMUTHS_DEG = [0.0, 120.0, 180.0, 240.0, 300.0, 0.0, 60.0]


def _medium(rain_rate_mm_h: float) -> Medium:
    if rain_rate_mm_h == 0:
        return Medium(kind="clear", rain_rate_mm_h=0.0)
    return Medium(kind="homogeneous", rain_rate_mm_h=rain_rate_mm_h)


def with_rain(scn: Scenario, rain_rate_mm_h: float) -> Scenario:
    """``scn`` with homogeneous rain at ``rain_rate_mm_h`` (0: clear air) in place of its
    weather. Only the rain field changes: the scenario's rain model, drop-size distribution,
    drop shape, temperature and wind stay as they were."""
    kind = "clear" if rain_rate_mm_h == 0 else "homogeneous"
    weather = dataclasses.replace(
        scn.medium, kind=kind, rain_rate_mm_h=rain_rate_mm_h, cells=[], rate_map_mm_h=None
    )
    return dataclasses.replace(scn, medium=weather)


def paper(rain_rate_mm_h: float = 25.0, **overrides: Any) -> Scenario:
    """The paper's scenario; ``rain_rate_mm_h=0`` is clear air; keyword overrides replace
    top-level Scenario fields."""
    sites = [
        Site(x_m=1000 * x, y_m=1000 * y, height_m=25.0, cells=[Cell(azimuth_deg=az)])
        for (x, y), az in zip(PAPER_SITES_KM, PAPER_AZIMUTHS_DEG, strict=True)
    ]
    fields: dict[str, Any] = {
        "name": "paper",
        "freq_hz": 4.9e9,
        "area": Area(),
        "sites": sites,
        "medium": _medium(rain_rate_mm_h),
    }
    fields.update(overrides)
    return Scenario(**fields)


def urban(rain_rate_mm_h: float = 25.0, **overrides: Any) -> Scenario:
    """Three-cell sites and a block of buildings (shadows at the flight altitude)."""
    sites = [
        Site(
            x_m=1000 * x,
            y_m=1000 * y,
            height_m=25.0,
            cells=[Cell(azimuth_deg=a) for a in (30.0, 150.0, 270.0)],
        )
        for x, y in PAPER_SITES_KM
    ]
    buildings = [
        Building(x0_m=x0, x1_m=x0 + 60.0, y0_m=y0, y1_m=y0 + 60.0, height_m=60.0)
        for x0 in (640.0, 740.0, 840.0)
        for y0 in (640.0, 740.0, 840.0)
    ]
    fields: dict[str, Any] = {
        "name": "urban",
        "freq_hz": 4.9e9,
        "area": Area(),
        "sites": sites,
        "medium": _medium(rain_rate_mm_h),
        "buildings": buildings,
    }
    fields.update(overrides)
    return Scenario(**fields)


PRESETS: dict[str, Callable[..., Scenario]] = {"paper": paper, "urban": urban}
