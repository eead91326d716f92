"""How the field gets there: the propagation engines and their registry. The modules: the PE
grid and march per cell, the rays (direct, ground, buildings and terrain along each path, walls
and corners) and the hybrid of the two. Depends on [`rainuav.radio.scene`][rainuav.radio.scene]
only.

The engines, by what they do (this is the one place that knows them by name):

- ``ray``: rays alone (the direct ray, the ground's reflection, buildings and terrain along each
  path, the walls' and corners' rays;
  [`rainuav.radio.engines.ray_engine`][rainuav.radio.engines.ray_engine]).
- ``pe``: the 3-D split-step parabolic equation alone, marched from each cell over its cone
  ([`rainuav.radio.engines.pe_engine`][rainuav.radio.engines.pe_engine]); its ground is a perfect
  conductor (or none), and it does not map in time (a march per cell and instant).
- ``hybrid``: the PE inside each cell's cone and the rays outside it
  ([`rainuav.radio.engines.hybrid`][rainuav.radio.engines.hybrid]); over a dielectric soil it is the
  rays.

Code asks an [`Engine`][rainuav.radio.engines.Engine] what it does
([`engine_of()`][rainuav.radio.engines.engine_of]), never its name."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

__all__ = ["ENGINES", "Engine", "engine_of", "for_time"]


@dataclass(frozen=True)
class Engine:
    """One propagation engine, by what it does."""

    name: str
    marches: bool
    """The parabolic equation carries (part of) each cell's pattern."""
    traces: bool
    """Rays carry (the rest of) each pattern: the engine maps over a dielectric soil and in
    time."""

    @property
    def combines(self) -> bool:
        """The march inside each cone and the rays outside it (the march in clear air can be
        shared: by the levels of a map, by the instants of a weather that moves)."""
        return self.marches and self.traces

    @property
    def in_time(self) -> str:
        """The engine that maps this one's requests in time: itself where it traces, else the
        hybrid (a march per cell and instant is not offered)."""
        return self.name if self.traces else "hybrid"


ENGINES: dict[str, Engine] = {
    e.name: e
    for e in (
        Engine("hybrid", marches=True, traces=True),
        Engine("ray", marches=False, traces=True),
        Engine("pe", marches=True, traces=False),
    )
}
"""The engines by name, the default first."""


def engine_of(scn: Any) -> Engine:
    """The [`Engine`][rainuav.radio.engines.Engine] of a scenario.

    Args:
        scn: Anything with an `engine` name, or a name itself.

    Returns:
        The engine.
    """
    return ENGINES[scn if isinstance(scn, str) else scn.engine]


def for_time(scn: Any) -> Any:
    """A scenario as it is mapped in time.

    Args:
        scn: The scenario.

    Returns:
        Itself where its engine traces rays, else with the engine that maps its requests in time
        ([`Engine.in_time`][rainuav.radio.engines.Engine.in_time]).
    """
    e = engine_of(scn)
    return scn if e.traces else dataclasses.replace(scn, engine=e.in_time)
