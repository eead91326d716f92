"""The API reference's docstrings: each main entry point's has an Args / Returns / Raises section
and an ``Examples`` section whose Python block runs and prints, and everything a public module
exports names its parameters and its return (the reference's pages render them:
``docstring_style: google``)."""

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


def _public_modules() -> list[str]:
    """Every public module of the package, as the API reference lists them (docs/api_pages.py)."""
    from test_docs import _load

    return _load("api_pages").public_modules()


def _front_door() -> dict[str, object]:
    """Every function, and every method a class of the package defines (its own and its mixins'
    in the package, not Gymnasium's or torch's), named in a public module's ``__all__``."""
    import dataclasses
    import importlib

    found: dict[str, object] = {}
    for pkg in _public_modules():
        mod = importlib.import_module(pkg)
        for name in getattr(mod, "__all__", ()):
            obj = getattr(mod, name)
            if inspect.isfunction(obj):
                found[f"{pkg}.{name}"] = obj
            elif inspect.isclass(obj) and not issubclass(obj, BaseException):
                for klass in obj.__mro__:
                    if not klass.__module__.startswith("rainuav"):
                        continue
                    for key, member in vars(klass).items():
                        fn = getattr(member, "__func__", member)  # class and static methods
                        init = (  # a class's own constructor (not a dataclass's or Protocol's)
                            key == "__init__"
                            and not dataclasses.is_dataclass(klass)
                            and getattr(fn, "__qualname__", "").startswith(klass.__name__)
                        )
                        if inspect.isfunction(fn) and (not key.startswith("_") or init):
                            found.setdefault(f"{pkg}.{name}.{key}", fn)
    return found


def test_the_api_documents_every_parameter_and_return() -> None:
    """Google-style sections on everything a public module's ``__all__`` exports: an ``Args``
    section naming each parameter where there are any, and a ``Returns`` (or ``Yields``) section
    where the annotation returns something. Tolerance: none (ruff's D417 then checks each Args
    section against its signature across the whole package). A subclass's override of a
    documented method (a callback's ``on_episode``) is read with the docstring it overrides, as
    ``inspect.getdoc`` reads it."""
    missing = []
    members = _front_door()
    assert len(members) > 400  # the walk found the package's classes and their methods
    for where, fn in members.items():
        sig = inspect.signature(fn)
        params = [p for p in sig.parameters if p not in ("self", "cls")]
        doc = inspect.getdoc(fn) or ""
        returns = sig.return_annotation not in (None, "None", inspect.Signature.empty)
        if params and "Args:" not in doc:
            missing.append(f"{where}: Args")
        for p in params:
            if "Args:" in doc and not re.search(rf"^\s+\*{{0,2}}{p}:", doc, flags=re.M):
                missing.append(f"{where}: Args lacks {p}")
        if returns and "Returns:" not in doc and "Yields:" not in doc:
            missing.append(f"{where}: Returns")
    assert not missing, missing
