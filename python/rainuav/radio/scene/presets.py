"""Preset scenarios (``rainuav.radio.scene.presets``); each takes ``rain_rate_mm_h`` (0: clear
air), ``freq_hz``, and keyword overrides of top-level Scenario fields.

``paper``: the design paper's setting (section VI): a 2 km x 2 km airspace, the UAV at 100 m,
4.9 GHz, seven sites on a hexagon of radius 667 m around (1, 1) km, antennas at 25 m, one
Gaussian beam per site with the paper's source (elevation 5 degrees, half-power beamwidth
4.333 degrees). Choices the paper leaves open, made here: horizontal polarisation over a PEC
ground; 46 dBm per cell; noise -95 dBm (10 MHz, 9 dB noise figure: the scenario defaults);
beam azimuths (below) chosen so that the 100 m map has both good and weak regions;
Marshall-Palmer rain at 20 C, forward-scattering model; and a sidelobe floor 40 dB below the
33 dBi peak (-7 dBi: the level of a large reflector's far sidelobes), without which every
pixel outside the seven beams would receive nothing at all.

``uma``: a 3GPP-style urban-macro layout: the same seven sites with three sectors each
(azimuths 30, 150, 270 degrees), masts at 25 m, each sector the TR 38.901 element in an
8-row vertical array at half a wavelength, 10 degrees electrical downtilt, 46 dBm; 20 MHz
bandwidth and a 7 dB noise figure (-94 dBm); PEC ground, horizontal polarisation; 4.9 GHz by
default, 28 GHz supported; a PE budget of 0.25 per cell (``UMA_PE_BUDGET_GPOINTS``).

``rain_cell``: ``uma`` at 28 GHz in light widespread rain (``rain_rate_mm_h``, default
5 mm/h) with a convective cell (Gaussian, peak 100 mm/h, 1/e radius 500 m) centred at
(1200, 1300) m, midway along the straight path from the area's centre to the navigation
task's default destination (1400, 1600) m.

``urban``: the ``uma`` sectors (4.9 GHz) and a block of buildings south-west of the centre,
tall enough to cast shadows at the flight altitude.

``SINR_THRESHOLDS_DB`` names, per preset, the SINR (dB) its navigation task counts as
outage by default, chosen so that between 20% and 80% of its clear-air area falls below
(the shares measured are in the README): 10 dB would put every pixel of ``uma`` in outage.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any

from rainuav.radio.scene.scenario import (
    Area,
    Building,
    Cell,
    Medium,
    PESettings,
    RainCell,
    Scenario,
    Site,
)
from rainuav.radio.scene.storms import draw_storm

__all__ = [
    "DEFAULT_MIN_DB",
    "PRESETS",
    "SINR_THRESHOLDS_DB",
    "paper",
    "rain_cell",
    "storm",
    "uma",
    "urban",
    "with_rain",
]

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
    """A scenario with homogeneous rain in place of its weather.

    Only the rain field changes: the scenario's rain model, drop-size distribution, drop
    shape, temperature and wind stay as they were.

    Args:
        scn: The scenario.
        rain_rate_mm_h: The rain rate, mm/h (0: clear air).

    Returns:
        The scenario in that rain.
    """
    kind = "clear" if rain_rate_mm_h == 0 else "homogeneous"
    weather = dataclasses.replace(
        scn.medium,
        kind=kind,
        rain_rate_mm_h=rain_rate_mm_h,
        cells=[],
        rate_map_mm_h=None,
        rate_times_s=None,
        field=None,
    )
    return dataclasses.replace(scn, medium=weather)


#: Sector azimuths of the three-sector presets, degrees.
SECTOR_AZIMUTHS_DEG = (30.0, 150.0, 270.0)
PAPER_FLOOR_DB = 40.0
"""The paper preset's sidelobe floor below the beams' peak, dB."""


def paper(rain_rate_mm_h: float = 25.0, freq_hz: float = 4.9e9, **overrides: Any) -> Scenario:
    """The design paper's scenario: its sites, Gaussian beams, area and altitude.

    The module docstring gives the layout.

    Args:
        rain_rate_mm_h: Homogeneous rain, mm/h (the paper's 25 by default; 0: clear air).
        freq_hz: The carrier, Hz.
        **overrides: Fields of the [`Scenario`][rainuav.radio.Scenario] in place of the
            preset's.

    Returns:
        The [`Scenario`][rainuav.radio.Scenario].
    """
    sites = [
        Site(
            x_m=1000 * x,
            y_m=1000 * y,
            height_m=25.0,
            cells=[Cell(azimuth_deg=az, floor_db=PAPER_FLOOR_DB)],
        )
        for (x, y), az in zip(PAPER_SITES_KM, PAPER_AZIMUTHS_DEG, strict=True)
    ]
    fields: dict[str, Any] = {
        "name": "paper",
        "freq_hz": freq_hz,
        "area": Area(),
        "sites": sites,
        "medium": _medium(rain_rate_mm_h),
    }
    fields.update(overrides)
    return Scenario(**fields)


def _sector(azimuth_deg: float) -> Cell:
    return Cell(
        azimuth_deg=azimuth_deg,
        tilt_deg=0.0,
        antenna="array",
        rows=8,
        spacing=0.5,
        electrical_tilt_deg=-10.0,
        tx_power_dbm=46.0,
    )


def _uma_sites() -> list[Site]:
    return [
        Site(
            x_m=1000 * x,
            y_m=1000 * y,
            height_m=25.0,
            cells=[_sector(a) for a in SECTOR_AZIMUTHS_DEG],
        )
        for x, y in PAPER_SITES_KM
    ]


UMA_PE_BUDGET_GPOINTS = 0.25
"""The ``uma`` preset's PE budget per cell (1e9 grid-point steps; the scenario default is 1).
Measured at 4.9 GHz in clear air (BENCHMARKS, "What the PE cone costs and buys"): at 0.25 the
hybrid marches 15 of the 21 sectors in 5.6 degree cones, carries 0.23% of the power by PE and
builds in 33 s; at 1.0 it marches all 21 in 10.8 degree cones (2.4%) in 199 s and moves SINR
by 0.28 dB at the 95th percentile (2.9% of the pixels by over 0.5 dB). Over flat open ground
the PE and the rays compute the same physics, so the wider cone buys little; ``urban``, whose
buildings are what the PE is for, keeps the default."""


def uma(rain_rate_mm_h: float = 0.0, freq_hz: float = 4.9e9, **overrides: Any) -> Scenario:
    """The urban macro network: seven sites, three TR 38.901 array sectors each.

    The module docstring gives the layout, the antennas and the area.

    Args:
        rain_rate_mm_h: Homogeneous rain, mm/h (0: clear air).
        freq_hz: The carrier, Hz.
        **overrides: Fields of the [`Scenario`][rainuav.radio.Scenario] in place of the
            preset's (``engine="ray"``, ``ground=...``, ...).

    Returns:
        The [`Scenario`][rainuav.radio.Scenario].

    Examples:
        ```python
        from rainuav.radio import build_radio_map, presets

        rm = build_radio_map(presets.uma(rain_rate_mm_h=25.0, freq_hz=28e9, engine="ray"))
        ```
    """
    fields: dict[str, Any] = {
        "name": "uma",
        "freq_hz": freq_hz,
        "bandwidth_hz": 20e6,
        "noise_figure_db": 7.0,
        "area": Area(),
        "sites": _uma_sites(),
        "medium": _medium(rain_rate_mm_h),
        "pe": PESettings(budget_gpoints=UMA_PE_BUDGET_GPOINTS),
    }
    fields.update(overrides)
    return Scenario(**fields)


RAIN_CELL = RainCell(x_m=1200.0, y_m=1300.0, radius_m=500.0, peak_rate_mm_h=100.0)
"""The convective cell of the ``rain_cell`` preset."""


def rain_cell(rain_rate_mm_h: float = 5.0, freq_hz: float = 28e9, **overrides: Any) -> Scenario:
    """`uma` at 28 GHz with a 100 mm/h rain cell in light rain (the module's docstring).

    Args:
        rain_rate_mm_h: The widespread rain around the cell, mm/h.
        freq_hz: The carrier, Hz.
        **overrides: Fields of the [`Scenario`][rainuav.radio.Scenario] in place of the preset's.

    Returns:
        The [`Scenario`][rainuav.radio.Scenario].
    """
    weather = Medium(kind="cells", rain_rate_mm_h=rain_rate_mm_h, cells=[RAIN_CELL])
    fields: dict[str, Any] = {"name": "rain_cell", "medium": weather}
    fields.update(overrides)
    return uma(0.0, freq_hz, **fields)


def urban(rain_rate_mm_h: float = 25.0, freq_hz: float = 4.9e9, **overrides: Any) -> Scenario:
    """The `uma` sectors and a block of buildings, whose shadows reach the flight altitude.

    Args:
        rain_rate_mm_h: Homogeneous rain, mm/h.
        freq_hz: The carrier, Hz.
        **overrides: Fields of the [`Scenario`][rainuav.radio.Scenario] in place of the preset's.

    Returns:
        The [`Scenario`][rainuav.radio.Scenario].
    """
    buildings = [
        Building(x0_m=x0, x1_m=x0 + 60.0, y0_m=y0, y1_m=y0 + 60.0, height_m=60.0)
        for x0 in (640.0, 740.0, 840.0)
        for y0 in (640.0, 740.0, 840.0)
    ]
    fields: dict[str, Any] = {"name": "urban", "buildings": buildings, "pe": PESettings()}
    fields.update(overrides)
    return uma(rain_rate_mm_h, freq_hz, **fields)


def storm(
    rain_rate_mm_h: float | None = None,
    freq_hz: float = 28e9,
    *,
    seed: int = 0,
    speed_m_s: float | None = None,
    **overrides: Any,
) -> Scenario:
    """`uma` at 28 GHz under a random storm of moving, growing and decaying rain cells.

    The storm of `seed` ([`draw_storm()`][rainuav.radio.scene.storms.draw_storm]: Gaussian cells
    over a uniform background); its `medium.at(t_s)` is the weather `t_s` seconds into the storm.
    Seeds from 1 000 000 are the evaluation storms.

    Args:
        rain_rate_mm_h: The background rate, mm/h, in place of the drawn one.
        freq_hz: The carrier, Hz.
        seed: The storm.
        speed_m_s: The storm's speed, m/s, in place of the drawn one (every cell's velocity scaled
            by one factor, each cell still at its drawn place at mid-storm; 0: cells that stay where
            they are and only grow or decay).
        **overrides: Fields of the [`Scenario`][rainuav.radio.Scenario] in place of the preset's.

    Returns:
        The [`Scenario`][rainuav.radio.Scenario].
    """
    weather = draw_storm(seed, (0.0, 2000.0, 0.0, 2000.0), speed_m_s)
    if rain_rate_mm_h is not None:
        weather = dataclasses.replace(weather, rain_rate_mm_h=float(rain_rate_mm_h))
    fields: dict[str, Any] = {"name": "storm", "medium": weather}
    fields.update(overrides)
    return uma(0.0, freq_hz, **fields)


PRESETS: dict[str, Callable[..., Scenario]] = {
    "paper": paper,
    "uma": uma,
    "rain_cell": rain_cell,
    "urban": urban,
    "storm": storm,
}

DEFAULT_MIN_DB = 10.0
"""The outage threshold for SIR and for scenarios of no preset: the paper's minimum SIR, dB."""

SINR_THRESHOLDS_DB: dict[str, float] = {
    "paper": 0.0, "uma": -2.0, "rain_cell": -2.0, "urban": -1.0, "storm": -2.0,
}  # fmt: skip
"""Default outage threshold of each preset's navigation task, SINR in dB (module docstring)."""
