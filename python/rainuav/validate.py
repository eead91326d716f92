"""Validation runs that write figures and tables.

``python -m rainuav.validate rain [--out DIR]``: the paper's rain validation figure
(specific attenuation against frequency at 12.5 mm/h for both effective-medium models and
ITU-R P.838-3, H and V) as PNG and CSV, a printed table, and the worst-case ratio of the
default model to P.838-3 over 5-100 GHz and 12.5-150 mm/h.
"""

from __future__ import annotations

import argparse
import csv
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rainuav import _cli, medium
from rainuav._io import check_out_dir, write_atomic


@dataclass
class RainValidationOptions:
    """What ``python -m rainuav.validate rain`` takes (one docstring line per field = one flag,
    generated as ``train``'s are)."""

    out: Path = Path("validation")
    """The output directory."""


RAIN_RATE_MM_H = 12.5
TABLE_FREQS_GHZ = (1.0, 2.0, 4.9, 10.0, 20.0, 28.0, 40.0, 60.0, 100.0)


def rain_curves(freq_hz: np.ndarray, rain_rate_mm_h: float) -> dict[str, np.ndarray]:
    """Specific attenuation (dB/km) per curve name, on ``freq_hz``."""
    out: dict[str, np.ndarray] = {}
    for pol in ("h", "v"):
        for model in medium.MODELS:
            out[f"{model} {pol.upper()}"] = medium.specific_attenuation(
                freq_hz, rain_rate_mm_h, model=model, polarization=pol
            )
        out[f"ITU-R P.838-3 {pol.upper()}"] = medium.itu_p838(
            freq_hz, rain_rate_mm_h, polarization=pol
        )
    return out


def worst_cases() -> list[tuple[str, float, float, float]]:
    """(polarization, ratio, freq_GHz, rate) of the lowest and highest default/P.838 ratio
    on 5-100 GHz x 12.5-150 mm/h."""
    f = np.geomspace(5e9, 100e9, 81)[:, None]
    r = np.array([12.5, 25.0, 50.0, 100.0, 150.0])[None, :]
    rows = []
    for pol in ("h", "v"):
        ratio = medium.specific_attenuation(f, r, polarization=pol) / medium.itu_p838(
            f, r, polarization=pol
        )
        for idx in (np.argmin(ratio), np.argmax(ratio)):
            i, j = np.unravel_index(idx, ratio.shape)
            rows.append((pol.upper(), float(ratio[i, j]), f[i, 0] / 1e9, float(r[0, j])))
    return rows


def run_rain(out_dir: Path) -> dict[str, Path]:
    """Writes ``rain_attenuation.csv`` and ``rain_attenuation.png`` into ``out_dir``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    freq_hz = np.geomspace(1e9, 100e9, 200)
    curves = rain_curves(freq_hz, RAIN_RATE_MM_H)

    def write_csv(tmp: Path) -> None:
        with tmp.open("w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(["freq_ghz", *[f"{k} [dB/km]" for k in curves]])
            for i, f in enumerate(freq_hz):
                w.writerow([f"{f / 1e9:.12g}", *[f"{v[i]:.6e}" for v in curves.values()]])

    csv_path = write_atomic(out_dir / "rain_attenuation.csv", write_csv)

    fig, ax = plt.subplots(figsize=(7, 5))
    styles = {"forward-scattering": "-", "quasi-static": ":", "ITU-R P.838-3": "--"}
    colors = {"H": "tab:blue", "V": "tab:red"}
    for name, values in curves.items():
        kind, pol = name.rsplit(" ", 1)
        ax.loglog(freq_hz / 1e9, values, styles[kind], color=colors[pol], label=name)
    ax.set_xlabel("frequency [GHz]")
    ax.set_ylabel("specific attenuation [dB/km]")
    ax.set_title(f"Rain attenuation, Marshall-Palmer, {RAIN_RATE_MM_H} mm/h, 20 C")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    png_path = write_atomic(
        out_dir / "rain_attenuation.png", lambda tmp: fig.savefig(tmp, dpi=120, format="png")
    )
    plt.close(fig)

    table_f = np.array(TABLE_FREQS_GHZ) * 1e9
    table = rain_curves(table_f, RAIN_RATE_MM_H)
    names = list(table)
    print(f"Specific attenuation [dB/km] at {RAIN_RATE_MM_H} mm/h (Marshall-Palmer, 20 C)")
    print(f"{'GHz':>6} " + " ".join(f"{n:>24}" for n in names))
    for i, f in enumerate(TABLE_FREQS_GHZ):
        print(f"{f:>6g} " + " ".join(f"{table[n][i]:>24.4g}" for n in names))
    print("\nDefault model / ITU-R P.838-3 over 5-100 GHz x 12.5-150 mm/h (worst cases):")
    for pol, ratio, f_ghz, rate in worst_cases():
        print(f"  {pol}: {ratio:.3f} at {f_ghz:.1f} GHz, {rate:g} mm/h")
    print(f"\nwrote {csv_path} and {png_path}")
    return {"csv": csv_path, "png": png_path}


def build_parser() -> argparse.ArgumentParser:
    """The command line: one sub-command a validation, a flag for each field of its options
    ([`RainValidationOptions`][rainuav.validate.RainValidationOptions]).

    Returns:
        The parser.
    """
    parser = _cli.Parser(
        prog="python -m rainuav.validate",
        description=_cli.plain_help(__doc__),
    )
    sub = parser.add_subparsers(dest="what", required=True)
    rain = sub.add_parser("rain", help="rain attenuation against ITU-R P.838-3")
    _cli.add_fields(rain, RainValidationOptions)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)

    def body() -> int:
        check_out_dir(args.out)  # before any work
        run_rain(args.out)
        return 0

    return _cli.run(body, "the validation stopped; nothing half-written was kept")


if __name__ == "__main__":
    sys.exit(main())
