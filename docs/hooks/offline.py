"""The site works offline: a built page that would load a script, a style sheet or a font from
the network fails the build, naming the page and the address (links to other sites are fine:
they are followed only when clicked)."""

from __future__ import annotations

import re

_FETCHED = re.compile(
    r"<(?:script[^>]*\bsrc|link[^>]*\brel=\"?(?:stylesheet|preconnect|preload)\"?[^>]*\bhref)"
    r"=\"?(https?:)?//([^\"' >]+)",
    re.I,
)


def network_fetches(page_html: str) -> list[str]:
    """The addresses on the network that ``page_html`` loads as it opens."""
    return [m.group(2) for m in _FETCHED.finditer(page_html)]


def on_post_page(output: str, page, config) -> str:
    """mkdocs' hook: refuse a page that needs the network to open."""
    fetched = network_fetches(output)
    if fetched:
        raise ValueError(
            f"{page.file.src_path}: the page loads {fetched[0]} from the network "
            "(the site must open offline: ship the file in docs/)"
        )
    return output
