"""The ground under the radio maps ([physics reference, section
12][12-terrain-buildings-diffraction-and-reflections]): the terrain read from a digital elevation
model ([`rainuav.ground.dem`][rainuav.ground.dem]), on which obstacles stand. Below the radio layer:
the engines read heights and profiles from it, never the other way round."""

from rainuav.ground.dem import (
    HEIGHT_RANGE_M,
    Terrain,
    file_digest,
    read_dem,
    terrain_nodes,
)

__all__ = ["HEIGHT_RANGE_M", "Terrain", "file_digest", "read_dem", "terrain_nodes"]
