"""The gallery: runs every example of ``examples/gallery/`` (``make docs`` does, before the
site is built), its figure into ``docs/gallery/`` (built, not kept in the repository), and
writes ``docs/gallery.md``: each example's title, what it shows, its figure, the command and
the code.

    python docs/gallery.py            # run the examples and write the page
    python docs/gallery.py --page     # the page alone (tests/test_docs.py checks it is current)
"""

from __future__ import annotations

import ast
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples" / "gallery"
FIGURES = ROOT / "docs" / "gallery"
PAGE = ROOT / "docs" / "gallery.md"
ORDER = ("rain_against_p838", "map_in_rain", "exact_plan", "osm_footprints",
         "mission_over_terrain")  # fmt: skip
"""The examples, in the order the page shows them (every script of the folder, checked)."""


def scripts() -> list[Path]:
    found = {p.stem for p in EXAMPLES.glob("*.py") if not p.stem.startswith("_")}
    if found != set(ORDER):
        raise SystemExit(f"docs/gallery.py: ORDER {sorted(ORDER)} != the examples {sorted(found)}")
    return [EXAMPLES / f"{name}.py" for name in ORDER]


def page() -> str:
    parts = [
        "# Gallery\n",
        "Short examples that run as they are, each with the figure it draws (made by "
        "`make docs`). Run one from the clone's root; it writes into `gallery/` under the "
        "current folder (`--out` elsewhere), never into `docs/`.\n",
    ]
    for path in scripts():
        doc = ast.get_docstring(ast.parse(path.read_text())) or path.stem
        title, _, body = doc.partition("\n")
        rel = path.relative_to(ROOT).as_posix()
        parts += [
            f"## {title.rstrip('.')}\n",
            body.strip() + "\n",
            f"![{title.rstrip('.')}](gallery/{path.stem}.png)\n",
            f"```sh\npython {rel}\n```\n",
            f'??? example "The code: `{rel}`"\n\n    ```python\n    --8<-- "{rel}"\n    ```\n',
        ]
    return "\n".join(parts)


def main(argv: list[str]) -> int:
    PAGE.write_text(page())
    if "--page" in argv:
        return 0
    FIGURES.mkdir(exist_ok=True)
    for path in scripts():
        t0 = time.perf_counter()
        res = subprocess.run([sys.executable, str(path), "--out", str(FIGURES)], cwd=ROOT,
                             capture_output=True, text=True, timeout=600)  # fmt: skip
        if res.returncode != 0:
            sys.stderr.write(res.stdout + res.stderr)
            raise SystemExit(f"docs/gallery.py: {path.name} failed (exit {res.returncode})")
        print(f"gallery: {path.name} in {time.perf_counter() - t0:.1f} s")
    # The page "Plan a flight at your place": its command, run here, gives its figure and table.
    res = subprocess.run([sys.executable, str(ROOT / "docs" / "tutorials" / "your_place.py"),
                          "--out", str(FIGURES)], cwd=ROOT, timeout=600)  # fmt: skip
    if res.returncode != 0:
        raise SystemExit(f"docs/gallery.py: your_place.py failed (exit {res.returncode})")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
