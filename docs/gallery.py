"""The gallery: runs every example of ``examples/gallery/`` (``make docs`` does, before the
site is built), its figure into ``docs/gallery/`` (built, not kept in the repository) with the
script and a notebook of it to download, and writes ``docs/gallery.md``: a grid of the figures,
then each example's title, what it shows, its figure, the command, the downloads and the code.

    python docs/gallery.py            # run the examples and write the page
    python docs/gallery.py --page     # the page alone (tests/test_docs.py checks it is current)
"""

from __future__ import annotations

import ast
import json
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples" / "gallery"
FIGURES = ROOT / "docs" / "gallery"
PAGE = ROOT / "docs" / "gallery.md"
ORDER = ("rain_against_p838", "pe_gaussian_beam", "map_in_rain", "outage_by_height",
         "storm_that_moves", "exact_plan", "study_rain_sweep", "osm_footprints",
         "mission_over_terrain", "handed_over_run")  # fmt: skip
"""The examples, in the order the page shows them (every script of the folder, checked)."""


def scripts() -> list[Path]:
    found = {p.stem for p in EXAMPLES.glob("*.py") if not p.stem.startswith("_")}
    if found != set(ORDER):
        raise SystemExit(f"docs/gallery.py: ORDER {sorted(ORDER)} != the examples {sorted(found)}")
    return [EXAMPLES / f"{name}.py" for name in ORDER]


def _anchor(title: str) -> str:
    """The heading's id, as the site's table of contents makes it (Python-Markdown's own)."""
    from markdown.extensions.toc import slugify

    return slugify(title, "-")


def page() -> str:
    titles = []
    for path in scripts():
        doc = ast.get_docstring(ast.parse(path.read_text())) or path.stem
        titles.append((path, *doc.partition("\n")[::2]))
    parts = [
        "# Gallery\n",
        "Short examples that run as they are, each with the figure it draws (made by "
        "`make docs`). Run one from the clone's root; it writes into `gallery/` under the "
        "current folder (`--out` elsewhere), never into `docs/`. Each can be downloaded as a "
        "script or as a notebook (run it from the clone's root too).\n",
        '<div class="grid cards" markdown>\n',
        *(
            f"-   [![{t.rstrip('.')}](gallery/{p.stem}.png)](#{_anchor(t.rstrip('.'))})\n\n"
            f"    [{t.rstrip('.')}](#{_anchor(t.rstrip('.'))})\n"
            for p, t, _ in titles
        ),
        "</div>\n",
    ]
    for path, title, body in titles:
        rel = path.relative_to(ROOT).as_posix()
        parts += [
            f"## {title.rstrip('.')}\n",
            body.strip() + "\n",
            f"![{title.rstrip('.')}](gallery/{path.stem}.png)\n",
            f"```sh\npython {rel}\n```\n",
            f"Download: [the script](gallery/{path.stem}.py), "
            f"[the notebook](gallery/{path.stem}.ipynb).\n",
            f'??? example "The code: `{rel}`"\n\n    ```python\n    --8<-- "{rel}"\n    ```\n',
        ]
    return "\n".join(parts)


def notebook(path: Path) -> dict:
    """The example at ``path`` as a notebook (nbformat 4): its title and text, a cell that sets
    it up as the script would be run from the clone's root, and the script itself."""
    source = path.read_text()
    doc = ast.get_docstring(ast.parse(source)) or path.stem
    rel = path.relative_to(ROOT).as_posix()
    setup = (
        "# Run from the clone's root: the example reads examples/ and writes into gallery/.\n"
        f"import sys\n\n__file__ = {rel!r}\nsys.argv = [__file__]\n"
        f"sys.path.insert(0, {path.parent.relative_to(ROOT).as_posix()!r})"
    )

    def cell(kind: str, text: str) -> dict:
        lines = text.splitlines(keepends=True)
        extra = {} if kind == "markdown" else {"execution_count": None, "outputs": []}
        return {"cell_type": kind, "metadata": {}, "source": lines, **extra}

    title, _, body = doc.partition("\n")
    return {
        "nbformat": 4, "nbformat_minor": 5,
        "metadata": {"kernelspec": {"name": "python3", "display_name": "Python 3",
                                    "language": "python"},
                     "language_info": {"name": "python"}},
        "cells": [cell("markdown", f"# {title.rstrip('.')}\n\n{body.strip()}\n"),
                  cell("code", setup), cell("code", source.rstrip("\n"))],
    }  # fmt: skip


def downloads() -> None:
    """Each example's script and notebook into ``FIGURES``, beside its figure."""
    FIGURES.mkdir(exist_ok=True)
    for path in scripts():
        (FIGURES / path.name).write_text(path.read_text())
        (FIGURES / f"{path.stem}.ipynb").write_text(json.dumps(notebook(path), indent=1) + "\n")


def main(argv: list[str]) -> int:
    PAGE.write_text(page())
    if "--page" in argv:
        return 0
    downloads()
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
