"""Measurement logs drawn from a map taken as the truth: what a drive test over that map would have
logged. For checks (a truth the prior does not know: another engine's map, or sites whose tilts
and powers differ from the database's) and for trying the correction before a real log exists.

[`sample_log()`][rainuav.radio.measured.synthetic.sample_log] flies straight east-west lines over
the map, evenly spaced, until a share of the pixels is covered, and logs at each pixel the
``cells`` strongest cells' power with Gaussian noise (the noise of one logged value: fast
fading left after a receiver's averaging, and the receiver's error).
[`write_log()`][rainuav.radio.measured.synthetic.write_log] writes a log as the CSV
[`read_log()`][rainuav.radio.measured.log.read_log] reads;
[`perturbed_sites()`][rainuav.radio.measured.synthetic.perturbed_sites] draws a network that
differs from its database."""

from __future__ import annotations

import csv
import dataclasses
import os
from pathlib import Path

import numpy as np

from rainuav._io import write_atomic
from rainuav.errors import InvalidInputError
from rainuav.radio.measured.log import MeasurementLog
from rainuav.radio.outputs.mapdata import RadioMap
from rainuav.radio.outputs.sinr import RSS_FLOOR_DBM
from rainuav.radio.scene.scenario import Site
from rainuav.radio.scene.terrain import flight_heights_at

__all__ = ["flight_line_pixels", "perturbed_sites", "sample_log", "write_log"]


def perturbed_sites(
    sites: list[Site],
    seed: int,
    power_db: float = 3.0,
    tilt_deg: float = 2.0,
    azimuth_deg: float = 5.0,
) -> tuple[list[Site], list[dict[str, float]]]:
    """Sites as a real network might differ from its database.

    Draws of N(0, `power_db`), N(0, `tilt_deg`) and N(0, `azimuth_deg`) from `seed`, in that order,
    cell after cell.

    Args:
        sites: The database's sites.
        seed: The draws' seed.
        power_db: The transmit power's spread, dB.
        tilt_deg: The tilt's, degrees.
        azimuth_deg: The azimuth's, degrees.

    Returns:
        `(moved sites, each cell's offsets by the calibration's BOUNDS names)`.
    """
    rng = np.random.default_rng(seed)
    moved, offsets = [], []
    for s in sites:
        cells = []
        for c in s.cells:
            e = {"power_db": float(rng.normal(0, power_db)),
                 "tilt_deg": float(rng.normal(0, tilt_deg)),
                 "azimuth_deg": float(rng.normal(0, azimuth_deg))}  # fmt: skip
            offsets.append(e)
            cells.append(dataclasses.replace(
                c, tx_power_dbm=c.tx_power_dbm + e["power_db"],
                tilt_deg=c.tilt_deg + e["tilt_deg"], azimuth_deg=c.azimuth_deg + e["azimuth_deg"],
            ))  # fmt: skip
        moved.append(dataclasses.replace(s, cells=cells))
    return moved, offsets


def flight_line_pixels(shape: tuple[int, int], share: float, offset: float = 0.5) -> np.ndarray:
    """The pixels on east-west lines covering a share of a map, the lines evenly spaced.

    Args:
        shape: The map's (H, W).
        share: The share of the pixels, in (0, 1].
        offset: Where the first line lies from the south edge, in spacings.

    Returns:
        (K, 2) (row, column).

    Raises:
        InvalidInputError: A share outside (0, 1].
    """
    if not 0.0 < share <= 1.0:
        raise InvalidInputError(f"share must lie within (0, 1] (got {share:g})")
    h, w = shape
    lines = max(1, min(h, round(share * h)))
    rows = np.unique(np.clip(((np.arange(lines) + offset) * h / lines).astype(int), 0, h - 1))
    return np.array([(r, c) for r in rows for c in range(w)], dtype=np.int64)


def sample_log(
    truth: RadioMap,
    share: float = 0.02,
    *,
    cells: int = 6,
    noise_db: float = 2.0,
    seed: int = 0,
    offset: float = 0.5,
    flight: int = 0,
    repeat: int = 1,
    k_db: float | None = None,
) -> MeasurementLog:
    """A log flown over a truth map (the module's docstring).

    Args:
        truth: The map measured.
        share: The share of its pixels on flight lines.
        cells: The strongest cells logged at each pixel.
        noise_db: Gaussian noise on each value, dB.
        seed: The draws' seed.
        offset: Where the first line lies, in spacings.
        flight: The rows' flight number.
        repeat: Rows a pixel, each at a point drawn uniformly within it with its own draw (a
            receiver logging several samples a pixel).
        k_db: Each row's power also faded by a Ricean draw of this K-factor (unit mean power); None:
            no fading.

    Returns:
        The [`MeasurementLog`][rainuav.radio.measured.log.MeasurementLog].

    Raises:
        InvalidInputError: `repeat` outside 1..1000, or a share outside (0, 1].
    """
    if not 1 <= repeat <= 1000:
        raise InvalidInputError(f"repeat must lie within 1..1000 (got {repeat})")
    rng = np.random.default_rng(seed)
    px = np.repeat(flight_line_pixels(truth.rss_dbm.shape[1:], share, offset), repeat, axis=0)
    r, c = px[:, 0], px[:, 1]
    power = truth.rss_dbm[:, r, c]  # (M, K)
    k = min(cells, power.shape[0])
    top = np.argsort(-power, axis=0)[:k]  # (k, K)
    cell = top.T.ravel()
    rr, cc = np.repeat(r, k), np.repeat(c, k)
    value = truth.rss_dbm[cell, rr, cc]
    keep = value > RSS_FLOOR_DBM + 1.0
    x, y = truth.x_m[cc[keep]], truth.y_m[rr[keep]]
    n = int(keep.sum())
    if repeat > 1:
        px_m = truth.scenario.area.resolution_m
        x = x + rng.uniform(-px_m / 2, px_m / 2, n) * 0.999
        y = y + rng.uniform(-px_m / 2, px_m / 2, n) * 0.999
    scn = truth.scenario
    z = flight_heights_at(scn, x, y)
    faded = value[keep] + rng.normal(0.0, noise_db, n)
    if k_db is not None:
        k = 10 ** (k_db / 10)
        h = np.sqrt(k / (k + 1)) + np.sqrt(1 / (2 * (k + 1))) * (
            rng.standard_normal(n) + 1j * rng.standard_normal(n)
        )
        faded = faded + 10 * np.log10(np.abs(h) ** 2)
    return MeasurementLog(
        x_m=x, y_m=y, z_m=z, alt_m=np.full(n, float(truth.altitude_m)), cell=cell[keep],
        rss_dbm=faded, flight=np.full(n, flight),
        rows=n, source=f"drawn from the {scn.name} map",
    )  # fmt: skip


def write_log(log: MeasurementLog, path: str | os.PathLike[str]) -> Path:
    """Writes a log as CSV in the scenario's metres (`x_m,y_m,alt_m,cell,rss_dbm,flight`),
    atomically.

    Args:
        log: The log.
        path: The file.

    Returns:
        The path written.
    """

    def write(tmp: Path) -> None:
        with tmp.open("w", newline="") as f:
            out = csv.writer(f)
            out.writerow(["x_m", "y_m", "alt_m", "cell", "rss_dbm", "flight"])
            for row in zip(log.x_m, log.y_m, log.alt_m, log.cell, log.rss_dbm, log.flight,
                           strict=True):  # fmt: skip
                x, y, a, c, v, fl = row
                out.writerow([f"{x:.2f}", f"{y:.2f}", f"{a:.2f}", int(c), f"{v:.2f}", int(fl)])

    return write_atomic(path, write)
