"""The examples in the API reference run as written: each main entry point's docstring has an
Args / Returns / Raises section and an ``Examples`` section whose Python block runs and prints
(the reference's pages render them: ``docstring_style: google``)."""

from __future__ import annotations

import contextlib
import inspect
import io
import re

import pytest
from rainuav.nav import UAVNavEnv, planner
from rainuav.radio import build_radio_map
from rainuav.radio.measured import correct_map
from rainuav.rl import train

pytestmark = [pytest.mark.timeout(300), pytest.mark.slow]

ENTRY_POINTS = {
    "build_radio_map": build_radio_map,
    "UAVNavEnv": UAVNavEnv,
    "correct_map": correct_map,
    "optimal": planner.optimal,
    "train": train,
}


def _example(obj) -> str:
    doc = inspect.getdoc(obj) or ""
    section = doc.split("Examples:", 1)
    assert len(section) == 2, "no Examples section"
    block = re.search(r"```python\n(.*?)```", section[1], flags=re.S)
    assert block, "no Python block in the Examples section"
    return inspect.cleandoc(block.group(1))


@pytest.mark.parametrize("name", list(ENTRY_POINTS))
def test_the_entry_points_example_runs_and_prints(name: str, tmp_path, monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(_example(ENTRY_POINTS[name]), f"<{name} example>", "exec"), {})
    assert out.getvalue().strip(), "the example printed nothing"


@pytest.mark.parametrize("name", list(ENTRY_POINTS))
def test_the_entry_points_docstring_has_its_sections(name: str) -> None:
    obj = ENTRY_POINTS[name]
    doc = inspect.getdoc(obj.__init__ if inspect.isclass(obj) else obj) or ""
    assert "Args:" in doc and "Raises:" in doc, name
    if not inspect.isclass(obj):
        assert "Returns:" in doc, name
        # Every parameter is described in Args (ruff's D417 checks the same across the package).
        for p in inspect.signature(obj).parameters:
            assert re.search(rf"^\s+\*{{0,2}}{p}:", doc, flags=re.M), (name, p)
