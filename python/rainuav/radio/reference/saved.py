"""The tracer's maps saved and read back: a reference traced once, kept as data (an ``.npz``
of float32 arrays, no pickles), so that a check of today's engine against it need not trace it
again. A saved reference is the tracer's output as released; a test that reads one is paired
with one that traces a case again and holds the file to it."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from rainuav._io import write_atomic
from rainuav.radio.reference.tracer import TracerMap

__all__ = ["load_tracer_maps", "save_tracer_maps"]


def save_tracer_maps(path: Path, maps: dict[str, TracerMap]) -> None:
    """Writes tracer maps by name, as float32 (1e-7 relative: far below 0.01 dB).

    Written to a temporary file and renamed (``rainuav._io.write_atomic``), so a file is whole
    or absent.

    Args:
        path: The ``.npz`` file.
        maps: The maps by name (letters, digits, ``-`` and ``_``).

    Raises:
        ValueError: A name the file cannot hold.
    """
    arrays = {}
    for name, tm in maps.items():
        plain = name.replace("-", "").replace("_", "").isalnum()
        if not plain or name.endswith(("_a", "_b", "_w")):
            raise ValueError(f"a saved map's name is letters, digits, - and _ (got {name!r})")
        arrays[f"{name}_a"] = np.asarray(tm.half_a, dtype=np.float32)
        arrays[f"{name}_b"] = np.asarray(tm.half_b, dtype=np.float32)
        if tm.whole is not None:
            arrays[f"{name}_w"] = np.asarray(tm.whole, dtype=np.float32)

    def write(tmp: Path) -> None:
        with tmp.open("wb") as fh:
            np.savez_compressed(fh, **arrays)

    write_atomic(path, write)


def load_tracer_maps(path: Path) -> dict[str, TracerMap]:
    """The tracer maps a saved file holds, by name (float64).

    The file is one [`save_tracer_maps()`][rainuav.radio.reference.saved.save_tracer_maps]
    wrote.

    Args:
        path: The ``.npz`` file.

    Returns:
        The maps by name.
    """
    with np.load(path, allow_pickle=False) as f:
        names = [k[:-2] for k in f.files if k.endswith("_a")]
        return {
            n: TracerMap(
                f[f"{n}_a"].astype(float),
                f[f"{n}_b"].astype(float),
                f[f"{n}_w"].astype(float) if f"{n}_w" in f.files else None,
            )
            for n in names
        }
