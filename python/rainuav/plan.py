"""Deprecated: the planners moved to :mod:`rainuav.nav.planner` (this path goes in 0.3)."""

from __future__ import annotations

from rainuav._deprecated import moved, names

__getattr__ = moved(
    __name__, names("rainuav.nav.planner", "Plan", "optimal", "optimal_many", "straight_line")
)
