"""The README's Python examples run as written."""

from __future__ import annotations

import re
from pathlib import Path

README = Path(__file__).resolve().parents[1] / "README.md"


def test_readme_python_blocks_run() -> None:
    blocks = re.findall(r"```python\n(.*?)```", README.read_text(), flags=re.S)
    assert blocks, "README has no python examples"
    for block in blocks:
        exec(compile(block, str(README), "exec"), {})


def test_readme_quick_start_matches_ci() -> None:
    # .ci/run must call exactly the README's test command.
    text = README.read_text()
    cmds = re.findall(r"```bash\n(.*?)\n```", text, flags=re.S)
    ci = (README.parent / ".ci" / "run").read_text()
    assert len(cmds) == 2
    assert cmds[1] in ci.splitlines()
