"""Deprecated: the presets moved to :mod:`rainuav.radio.presets` (this path goes in 0.3)."""

from __future__ import annotations

from rainuav._deprecated import moved, names

__getattr__ = moved(
    __name__,
    names("rainuav.radio.presets", "PRESETS", "paper", "urban", "with_rain", "PAPER_SITES_KM"),
)
