"""The parabolic equation against the analytic Gaussian beam.

A Gaussian beam of 2 m waist at 4.9 GHz (Rayleigh range 205 m) marched 750 m by the split-step
parabolic equation (``rainuav.pwe.march``, narrow-angle propagator, 0.25 m grid, 5 m steps),
against the closed-form beam of the paraxial equation (the physics reference, section 4): the
on-axis amplitude along the march and the cross-section at the end, and in homogeneous rain of
100 mm/h the on-axis power against the clear-air beam times the medium's exact loss. A second.
"""

import sys

import numpy as np
from _common import out_dir, stamp
from matplotlib.figure import Figure
from rainuav import medium, pwe

out = out_dir(__doc__, sys.argv[1:])
f_hz, d, n, w0, dz, steps = 4.9e9, 0.25, 256, 2.0, 5.0, 150
k0 = 2 * np.pi * f_hz / 299_792_458.0
zr = k0 * w0**2 / 2
x = (np.arange(n) - n // 2) * d
xx, yy = np.meshgrid(x, x, indexing="ij")
u0 = np.exp(-(xx**2 + yy**2) / w0**2)
row = n // 2  # the axis: x = 0 (column n // 2) in the recorded row y = 0
clear = pwe.march(u0, dx_m=d, dy_m=d, dz_m=dz, steps=steps, freq_hz=f_hz, propagator="narrow",
                  record_rows=[row])  # fmt: skip
n_rain = medium.effective_index(f_hz, 100.0)
rain = pwe.march(u0, dx_m=d, dy_m=d, dz_m=dz, steps=steps, freq_hz=f_hz, propagator="narrow",
                 record_rows=[row], n=n_rain)  # fmt: skip
z = dz * np.arange(1, steps + 1)
q = 1 - 1j * z / zr
axis_exact = np.abs(1 / q)
axis_pe = np.abs(clear.rows[0, :, n // 2])
loss_exact = np.exp(-k0 * abs((n_rain**2).imag) * z)  # power, against clear air
loss_pe = np.abs(rain.rows[0, :, n // 2]) ** 2 / axis_pe**2
end = np.abs(np.exp(-(x**2) / (w0**2 * q[-1])) / q[-1])
err = np.max(np.abs(axis_pe - axis_exact))
db_pe, db_exact = 10 * np.log10(loss_pe[-1]), 10 * np.log10(loss_exact[-1])
print(f"on-axis amplitude: largest difference from the closed form {err:.1e} over {z[-1]:g} m;"
      f" rain loss {db_pe:.3f} dB against {db_exact:.3f}")  # fmt: skip
fig = Figure(figsize=(11, 3.6), layout="constrained")
a, b, c = fig.subplots(1, 3)
a.plot(z, axis_exact, "k-", lw=3, alpha=0.3, label="closed form")
a.plot(z, axis_pe, "C0--", label="split-step PE")
a.set(xlabel="range z [m]", ylabel="on-axis amplitude |u|", title="the beam's axis")
a.legend(fontsize="small")
b.plot(x, end, "k-", lw=3, alpha=0.3, label="closed form")
b.plot(x, np.abs(clear.field[:, row]), "C0--", label="split-step PE")
b.set(
    xlabel="cross-range x [m]",
    ylabel="|u|",
    title=f"cross-section at z = {z[-1]:g} m",
    xlim=(-20, 20),
)
c.plot(z, 10 * np.log10(loss_exact), "k-", lw=3, alpha=0.3, label="exp(-k0 |Im n^2| z)")
c.plot(z, 10 * np.log10(loss_pe), "C1--", label="PE in rain / PE in clear air")
c.set(xlabel="range z [m]", ylabel="on-axis power [dB]", title="100 mm/h of rain")
c.legend(fontsize="small")
stamp(fig, "pe_gaussian_beam.py")
fig.savefig(out / "pe_gaussian_beam.png", dpi=80)
print(f"wrote {out / 'pe_gaussian_beam.png'}")
