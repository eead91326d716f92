"""Old module paths that keep working for one release (0.2) with a DeprecationWarning."""

from __future__ import annotations

import importlib
import warnings
from collections.abc import Callable
from typing import Any


def moved(old: str, new: dict[str, str]) -> Callable[[str], Any]:
    """A module ``__getattr__`` for the old module ``old``: each name in ``new`` (name -> its
    new module) is taken from its new home with a DeprecationWarning naming it."""

    def __getattr__(name: str) -> Any:
        if name not in new:
            raise AttributeError(f"module {old!r} has no attribute {name!r}")
        home = new[name]
        warnings.warn(
            f"{old}.{name} moved to {home}.{name}; the old path goes in rainuav 0.3",
            DeprecationWarning,
            stacklevel=2,
        )
        return getattr(importlib.import_module(home), name)

    return __getattr__


def names(module: str, *which: str) -> dict[str, str]:
    """``{name: module}`` for each name."""
    return dict.fromkeys(which, module)
