"""The version the site shows is the package's: read from ``pyproject.toml`` when the site is
built, into the footer and wherever a page writes ``{{ version }}``."""

from __future__ import annotations

from pathlib import Path

import tomllib

ROOT = Path(__file__).resolve().parents[2]


def version() -> str:
    """The package's version, as ``pyproject.toml`` gives it."""
    return tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["version"]


def on_config(config):
    """mkdocs' hook: the footer names the version."""
    config.copyright = f"rainuav {version()}, MIT licence"
    return config


def on_page_markdown(markdown: str, page, config, files) -> str:
    """mkdocs' hook: ``{{ version }}`` on a page is the package's version."""
    return markdown.replace("{{ version }}", version())
