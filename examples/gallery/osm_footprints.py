"""Building footprints as OpenStreetMap exports them.

The shipped district (``examples/buildings.geojson``) read onto the place round Zurich's
example sites: each building coloured by its roof height, those standing at the default
height hatched (their file gives neither a height nor storeys: their clearance is a guess),
and the summary line ``fly`` prints. Under a second.
"""

import sys
from pathlib import Path

from _common import out_dir, stamp
from matplotlib.cm import ScalarMappable
from matplotlib.colors import Normalize
from matplotlib.figure import Figure
from matplotlib.patches import Polygon
from rainuav.geo import Georef
from rainuav.ground.footprints import read_footprints

out = out_dir(__doc__, sys.argv[1:])
EXAMPLES = Path(__file__).resolve().parents[1]
geo = Georef(47.3730, 8.5470)
fp = read_footprints(EXAMPLES / "buildings.geojson", geo, (-1500.0, 1500.0, -1500.0, 1500.0))
print(fp.summary())
norm = Normalize(0.0, max(b.height_m for b in fp.buildings))
fig = Figure(figsize=(6.4, 5.6), layout="constrained")
ax = fig.subplots()
for b in fp.buildings:
    ring = list(b.polygon.exterior.coords)
    ax.add_patch(
        Polygon(
            ring,
            facecolor=ScalarMappable(norm, "viridis").to_rgba(b.height_m),
            edgecolor="0.2",
            lw=0.4,
            hatch="////" if b.guessed else None,
        )
    )
ax.autoscale_view()
ax.set_aspect("equal")
ax.set_xlabel("east of the origin [m]")
ax.set_ylabel("north of the origin [m]")
ax.set_title(
    f"{len(fp.buildings)} buildings; hatched: at the default height "
    f"{fp.default_height_m:g} m ({fp.default_height})",
    fontsize=9,
)
fig.colorbar(ScalarMappable(norm, "viridis"), ax=ax, label="roof above the ground [m]")
stamp(fig, "osm_footprints.py")
fig.savefig(out / "osm_footprints.png", dpi=90)
print(f"wrote {out / 'osm_footprints.png'}")
