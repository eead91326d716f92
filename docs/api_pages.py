"""Writes the API reference: one page a public module under docs/api/, and its navigation in
mkdocs.yml (between the ``# api-nav`` markers). ``python docs/api_pages.py`` after adding or
removing a module; ``tests/test_docs.py`` checks that the pages and the navigation match the
package."""

from __future__ import annotations

import pkgutil
import re
import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
GROUPS = {
    "": "The package",
    "ground": "The ground",
    "radio": "Radio maps",
    "radio.scene": "Radio maps, the scene",
    "radio.engines": "Radio maps, the engines",
    "radio.outputs": "Radio maps, the outputs",
    "radio.measured": "Radio maps from measurements",
    "radio.reference": "Radio maps, the reference tracer",
    "nav": "Navigation",
    "world": "Worlds",
    "rl": "Learning",
    "studies": "Studies",
    "fly": "The fly command",
}
"""The API's sections, by subpackage (top-level modules go in "The package")."""
ENTRY_POINTS = ("evaluate", "fly", "radiomap", "study", "train", "validate")
"""The ``python -m rainuav.*`` commands: documented by their ``--help`` and the guide."""


def public_modules() -> list[str]:
    """Every public module of the package (no part starting with an underscore)."""
    sys.path.insert(0, str(ROOT / "python"))
    import rainuav

    names = ["rainuav"]
    for m in pkgutil.walk_packages(rainuav.__path__, "rainuav."):
        parts = m.name.split(".")[1:]
        if any(p.startswith("_") for p in parts) or (len(parts) == 1 and parts[0] in ENTRY_POINTS):
            continue
        names.append(m.name)
    return sorted(names)


def group(name: str) -> str:
    parts = name.split(".")
    if len(parts) > 2 and f"{parts[1]}.{parts[2]}" in GROUPS:  # rainuav.radio's parts
        return f"{parts[1]}.{parts[2]}"
    return parts[1] if len(parts) > 2 or (len(parts) == 2 and parts[1] in GROUPS) else ""


def page(name: str) -> str:
    # The module's own heading is the page's title (and the anchor references to it use).
    return f"::: {name}\n    options:\n      show_root_heading: true\n      heading_level: 1\n"


def nav(names: list[str]) -> str:
    lines = ["  - API reference:", "      - Overview: api.md"]
    for key, title in GROUPS.items():
        members = [n for n in names if group(n) == key]
        if members:
            lines.append(f"      - {title}:")
            lines += [f"          - {n}: api/{n}.md" for n in members]
    return "\n".join(lines) + "\n"


def main() -> int:
    names = public_modules()
    out = DOCS / "api"
    out.mkdir(exist_ok=True)
    for old in out.glob("*.md"):
        if old.stem not in names:
            old.unlink()
    for n in names:
        (out / f"{n}.md").write_text(page(n))
    yml = ROOT / "mkdocs.yml"
    text = yml.read_text()
    new = re.sub(r"(  # api-nav\n).*?(  # api-nav end\n)", lambda m: m[1] + nav(names) + m[2],
                 text, flags=re.S)  # fmt: skip
    yml.write_text(new)
    print(f"{len(names)} module pages in {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
