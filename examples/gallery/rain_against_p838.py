"""The rain medium against ITU-R P.838-3.

Specific attenuation of Marshall-Palmer rain at 25 and 100 mm/h from 1 to 100 GHz:
rainuav's forward-scattering medium (van de Hulst with Mie amplitudes, spheroidal drops) for
horizontal and vertical polarisation, beside the ITU's fitted coefficients. A second or two.
"""

import sys

import numpy as np
from _common import out_dir, stamp
from matplotlib.figure import Figure
from rainuav import medium

out = out_dir(__doc__, sys.argv[1:])
f_hz = np.geomspace(1e9, 100e9, 60)
fig = Figure(figsize=(6.4, 4.4), layout="constrained")
ax = fig.subplots()
for rate, colour in ((25.0, "C0"), (100.0, "C3")):
    for pol, style in (("h", "-"), ("v", "--")):
        ours = medium.specific_attenuation(f_hz, rate, polarization=pol)
        itu = medium.itu_p838(f_hz, rate, polarization=pol)
        ax.loglog(f_hz / 1e9, ours, style, color=colour, label=f"rainuav {pol.upper()}, {rate:g}")
        ax.loglog(
            f_hz / 1e9,
            itu,
            ":",
            color=colour,
            lw=2.5,
            alpha=0.5,
            label=f"P.838-3 {pol.upper()}, {rate:g}" if pol == "h" else None,
        )
        ratio = ours / itu
        span = f"{ratio.min():.2f} to {ratio.max():.2f}"
        print(f"{rate:5g} mm/h {pol.upper()}: rainuav / P.838-3 from {span}")
ax.set_xlabel("frequency [GHz]")
ax.set_ylabel("specific attenuation [dB/km]")
ax.set_title("rain rates in mm/h", fontsize=9)
ax.grid(True, which="both", alpha=0.3)
ax.legend(fontsize="small", ncols=2)
stamp(fig, "rain_against_p838.py")
fig.savefig(out / "rain_against_p838.png", dpi=90)
print(f"wrote {out / 'rain_against_p838.png'}")
