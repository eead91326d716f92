"""The README and the documentation: their Python examples run as written, the README stays
short and names every tool, its links resolve, and the quick start is what CI runs."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
PAGES = sorted((ROOT / "docs").rglob("*.md"))
TOOLS = ("train", "evaluate", "radiomap", "study", "fly", "validate")


def _python_blocks(path: Path) -> list[str]:
    blocks = re.findall(r"```python\n(.*?)```", path.read_text(), flags=re.S)
    return [b for b in blocks if "--8<--" not in b]  # a script included whole runs as a test


SLOW_PAGES = {"docs/guide/learning.md"}
"""Pages whose examples train a network (about 10 s): in the full tier only."""


@pytest.mark.parametrize(
    "path",
    [
        pytest.param(p, marks=pytest.mark.slow) if str(p.relative_to(ROOT)) in SLOW_PAGES else p
        for p in [README, *PAGES]
    ],
    ids=lambda p: str(p.relative_to(ROOT)),
)
def test_python_blocks_run(path: Path) -> None:
    for block in _python_blocks(path):
        exec(compile(block, str(path), "exec"), {})


def test_the_examples_are_found() -> None:
    assert _python_blocks(README), "README has no python example"
    assert sum(len(_python_blocks(p)) for p in PAGES) >= 4  # the guide's examples


def test_readme_quick_start_matches_ci() -> None:
    # .ci/run must call exactly the README's test command.
    text = README.read_text()
    cmds = re.findall(r"```bash\n(.*?)\n```", text, flags=re.S)
    ci = (ROOT / ".ci" / "run").read_text()
    assert len(cmds) == 2
    assert cmds[1] in ci.splitlines()


def test_readme_is_short_and_names_every_tool() -> None:
    text = README.read_text()
    assert len(text.splitlines()) <= 250
    for tool in TOOLS:
        assert f"python -m rainuav.{tool}" in text, tool
    for marker in ("summary.json", "radiomap.npz", "evaluation.json", "results.csv"):
        assert marker in text, marker  # the file that says a run is complete


@pytest.mark.parametrize("path", [README, ROOT / "CONTRIBUTING.md", *PAGES],
                         ids=lambda p: str(p.relative_to(ROOT)))  # fmt: skip
def test_relative_links_resolve(path: Path) -> None:
    for target in re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", path.read_text()):
        if "://" in target:
            continue
        if path.name == "gallery.md" and target.startswith("gallery/"):
            # A figure `make docs` draws: the example that draws it exists.
            target = f"../examples/gallery/{Path(target).stem}.py"
        elif target.startswith("../gallery/"):
            # A figure `make docs` draws: by a gallery example, or by a tutorial's script.
            stem = Path(target).stem
            tutorial = ROOT / "docs" / "tutorials" / f"{stem}.py"
            example = ROOT / "examples" / "gallery" / f"{stem}.py"
            target = str(tutorial if tutorial.exists() else example)
        assert (path.parent / target).exists(), (path.name, target)
