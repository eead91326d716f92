"""What every ``python -m rainuav.*`` entry point shares: bad input is one line and exit 2,
Ctrl-C is one line and exit 130 (what was saved stays saved: every file is written beside
and renamed), and warnings are one line each."""

from __future__ import annotations

import sys
import warnings
from collections.abc import Callable
from typing import Any

from rainuav.errors import CacheWarning, InvalidInputError

__all__ = ["run"]


def _one_line(message: Any, category: type[Warning], *_: Any, **__: Any) -> None:
    print(f"warning: {message}", file=sys.stderr)


def run(
    body: Callable[[], int],
    on_interrupt: str | Callable[[], str] = "nothing half-written was kept",
) -> int:
    """Runs a CLI's ``body`` and returns its exit code: :class:`InvalidInputError` prints
    ``error: <message>`` and returns 2; Ctrl-C prints ``interrupted: <on_interrupt>`` (a
    string, or a function that says what was kept) and returns 130; warnings (the radio-map
    cache's among them) print as ``warning: <message>``."""
    with warnings.catch_warnings():
        warnings.simplefilter("default", CacheWarning)
        warnings.showwarning = _one_line
        try:
            return body()
        except InvalidInputError as err:
            print(f"error: {err}", file=sys.stderr)
            return 2
        except KeyboardInterrupt:
            said = on_interrupt() if callable(on_interrupt) else on_interrupt
            print(f"interrupted: {said}", file=sys.stderr)
            return 130
