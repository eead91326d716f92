"""What every ``python -m rainuav.*`` entry point shares: bad input is one line and exit 2,
Ctrl-C is one line and exit 130 (what was saved stays saved: every file is written beside
and renamed), and warnings are one line each."""

from __future__ import annotations

import argparse
import dataclasses
import difflib
import itertools
import math
import re
import sys
import warnings
from collections.abc import Callable, Sequence
from typing import Any

from rainuav.errors import CacheWarning, InvalidInputError, WriteError

__all__ = [
    "Parser",
    "add_fields",
    "altitude_band",
    "attach_negative_values",
    "field_docs",
    "metre_flags",
    "plain_help",
    "run",
    "show_all",
]


class _HelpAll(argparse.Action):
    """``--help-all``: the help with every option, the ones ``--help`` leaves out too."""

    def __init__(self, option_strings: Sequence[str], dest: str, **_: Any) -> None:
        super().__init__(option_strings, dest, nargs=0, default=argparse.SUPPRESS,
                         help="list every option, with its default, and exit")  # fmt: skip

    def __call__(self, parser: argparse.ArgumentParser, *_: Any) -> None:
        show_all(parser)
        parser.print_help()
        parser.exit()


def show_all(parser: argparse.ArgumentParser) -> argparse.ArgumentParser:
    """Lists in ``parser``'s help the options its ``--help`` leaves out
    ([`Parser.hide()`][rainuav._cli.Parser.hide]).

    Args:
        parser: The command's parser.

    Returns:
        The parser.
    """
    for a in parser._actions:
        if getattr(a, "full_help", None) is not None:
            a.help = a.full_help
    return parser


class Parser(argparse.ArgumentParser):
    """The commands' parser: a flag is its whole name (no abbreviations), and a flag it does not
    know is named with the flags it could have meant (``--episodes``: ``--dqn.episodes``), or
    with what replaced it (``removed``: a flag to the text that says so)."""

    def __init__(self, *args: Any, removed: dict[str, str] | None = None, **kwargs: Any) -> None:
        kwargs.setdefault("allow_abbrev", False)
        super().__init__(*args, **kwargs)
        self.removed = dict(removed or {})

    def hide(self, action: argparse.Action) -> None:
        """Leaves ``action`` out of ``--help`` (an option few runs need); ``--help-all`` lists
        it, and is added with the first option hidden.

        Args:
            action: What ``add_argument`` returned.
        """
        if "--help-all" not in self._option_string_actions:
            self.add_argument("--help-all", action=_HelpAll)
        action.full_help = action.help  # type: ignore[attr-defined]
        action.help = argparse.SUPPRESS

    def error(self, message: str) -> Any:
        """Exits 2 with the usage and one line, the likely flags added to an unknown one's."""
        if message.startswith("unrecognized arguments:"):
            hints = [h for w in message.split(":", 1)[1].split() for h in self._meant(w)]
            if hints:
                message += f" (did you mean {' or '.join(dict.fromkeys(hints))}?)"
        super().error(message)

    def _meant(self, word: str) -> list[str]:
        """The known flags an unknown ``word`` may stand for: the same name in a table
        (``--dqn.NAME``), the name with its unit (``--rain-rate-mm-h``), else the closest."""
        if not word.startswith("--"):
            return []
        bare = word.split("=", 1)[0]
        if bare in self.removed:
            return [self.removed[bare]]
        known = [o for o in self._option_string_actions if o.startswith("--")]
        near = [o for o in known if o.endswith("." + bare[2:]) or o.startswith(bare + "-")]
        return near or difflib.get_close_matches(bare, known, n=2, cutoff=0.75)


_NUMBERS = re.compile(r"^-(\d|\.\d)[\d.eE+\-]*(,\s*[+\-]?(\d|\.\d)[\d.eE+\-]*)*$")
"""A value that starts with a minus sign and is a number or a comma-separated list of them
("-33.8688,151.2093", "-80,-179,80,179", "-1e3")."""


def attach_negative_values(argv: Sequence[str] | None, flags: Sequence[str]) -> list[str]:
    """``argv`` (default ``sys.argv[1:]``) with every ``FLAG VALUE`` pair whose flag is one of
    ``flags`` and whose value is a negative number or list of numbers joined into
    ``FLAG=VALUE``. argparse reads a token that starts with ``-`` as an option, so
    ``--start -33.87,151.21`` (a southern latitude) would otherwise end in "expected one
    argument"; joined, it reads as typed."""
    args = list(sys.argv[1:] if argv is None else argv)
    out: list[str] = []
    i = 0
    while i < len(args):
        a = str(args[i])
        if a in flags and i + 1 < len(args) and _NUMBERS.match(str(args[i + 1])):
            out.append(f"{a}={args[i + 1]}")
            i += 2
        else:
            out.append(a)
            i += 1
    return out


def metre_flags(ap: argparse.ArgumentParser) -> list[str]:
    """The options of ``ap`` that take metres (their names end in ``-m``): a coordinate there may
    be negative, so [`attach_negative_values()`][rainuav._cli.attach_negative_values] joins it."""
    return [s for s in ap._option_string_actions if s.startswith("--") and s.endswith(("-m", "_m"))]


def _one_line(message: Any, category: type[Warning], *_: Any, **__: Any) -> None:
    print(f"warning: {message}", file=sys.stderr)


def run(
    body: Callable[[], int],
    on_interrupt: str | Callable[[], str] = "nothing half-written was kept",
) -> int:
    """Runs a CLI's ``body`` and returns its exit code:
    [`InvalidInputError`][rainuav.errors.InvalidInputError] prints ``error: <message>`` and returns
    2 (a file that cannot be written, [`WriteError`][rainuav.errors.WriteError]: returns 1); Ctrl-C
    prints ``interrupted: <on_interrupt>`` (a string, or a function that says what was kept) and
    returns 130; warnings (the radio-map cache's among them) print as ``warning: <message>``."""
    with warnings.catch_warnings():
        warnings.simplefilter("default", CacheWarning)
        warnings.showwarning = _one_line
        try:
            return body()
        except InvalidInputError as err:
            print(f"error: {err}", file=sys.stderr)
            return 2
        except WriteError as err:  # a full disk: one line, exit 1 (not the input's fault)
            print(f"error: {err}", file=sys.stderr)
            return 1
        except KeyboardInterrupt:
            said = on_interrupt() if callable(on_interrupt) else on_interrupt
            print(f"interrupted: {said}", file=sys.stderr)
            return 130


_ROLE = re.compile(r":[a-z]+:`~?([^`<]*?)(?:\s*<[^>]*>)?`")
_XREF = re.compile(r"\[`?([^`\]]+?)`?\]\[[^\]]*\]")


def plain_help(text: str | None) -> str:
    """A docstring as a terminal shows it: reStructuredText's roles (``:mod:`a.b```,
    ``:func:`~a.b.c```) and MkDocs' cross-references (``[`c`][a.b.c]``) as the names they link,
    ````literals```` as the text, escaped backslashes single, so no
    ``--help`` prints raw markup."""
    if not text:
        return ""

    def role(m: re.Match[str]) -> str:
        name = m.group(1).strip()
        return name.rsplit(".", 1)[-1] if m.group(0)[m.group(0).index("`") + 1] == "~" else name

    out = _XREF.sub(lambda m: m.group(1), _ROLE.sub(role, text))
    out = out.replace("``", "")
    return out.replace("\\\\", "\\")


def altitude_band(text: str, name: str = "--altitudes-m") -> list[float]:
    """``LOW:HIGH:STEP`` (m) as the levels LOW, LOW + STEP, ... up to HIGH (at most 64), else
    one line naming ``name`` (the flag or field)."""
    try:
        lo, hi, step = (float(v) for v in text.split(":"))
    except ValueError:
        raise InvalidInputError(
            f"{name} must be LOW:HIGH:STEP in metres, e.g. 30:120:15 (got {text!r})"
        ) from None
    if not (math.isfinite(lo) and math.isfinite(hi) and step > 0 and hi >= lo):
        raise InvalidInputError(f"{name} must have LOW <= HIGH and STEP > 0 (got {text!r})")
    n = math.floor((hi - lo) / step + 1e-9) + 1
    if n > 64:
        raise InvalidInputError(f"{name} gives {n} levels (at most 64)")
    return [lo + k * step for k in range(n)]


def field_docs(cls: type) -> dict[str, str]:
    """The attribute docstrings of a dataclass and of the dataclasses it extends.

    Args:
        cls: The dataclass.

    Returns:
        Each field's docstring (the string literal after it), its whitespace collapsed.
    """
    import ast
    import inspect
    import textwrap

    docs: dict[str, str] = {}
    for klass in reversed([k for k in cls.__mro__ if dataclasses.is_dataclass(k)]):
        tree = ast.parse(textwrap.dedent(inspect.getsource(klass)))
        body = tree.body[0].body  # type: ignore[attr-defined]
        for a, b in itertools.pairwise(body):
            if (
                isinstance(a, ast.AnnAssign)
                and isinstance(b, ast.Expr)
                and isinstance(b.value, ast.Constant)
            ):
                docs[a.target.id] = " ".join(str(b.value.value).split())  # type: ignore[union-attr]
    return docs


def add_fields(ap: argparse.ArgumentParser, cls: type) -> None:
    """Adds one flag for each field of a dataclass of options, as ``train`` does for its run.

    The flag is ``--name-with-dashes``; its help is the field's docstring and its default (unless
    the docstring says it, or it is None: unset); its type
    is the field's (``int``, ``float``, ``str``, a path); a ``bool`` field that defaults to False is
    a switch; a field's ``metadata["choices"]`` are its allowed values (or a function giving
    them, called when the parser is built), ``metadata["metavar"]`` its value's name,
    ``metadata["type"]`` a parser of its own, ``metadata["required"]`` a flag that must be given
    and ``metadata["more"]`` one that ``--help`` leaves out (``--help-all`` lists it).

    Args:
        ap: The command's parser.
        cls: The dataclass; its defaults are the flags' defaults.
    """
    from pathlib import Path

    from rainuav._checks import field_kind

    kinds: dict[str, Any] = {"int": int, "float": float, "str": str, "Path": Path}
    docs = field_docs(cls)
    for f in dataclasses.fields(cls):
        kind = field_kind(f)[0]
        flag = f"--{f.name.replace('_', '-')}"
        text = plain_help(docs.get(f.name, ""))
        if kind == "bool":
            action = ap.add_argument(flag, dest=f.name, action="store_true", help=text)
        else:
            action = ap.add_argument(
                flag,
                dest=f.name,
                type=f.metadata.get("type", kinds.get(kind, str)),
                default=f.default,
                required=f.metadata.get("required", False),
                choices=choices() if callable(choices := f.metadata.get("choices")) else choices,
                metavar=f.metadata.get("metavar"),
                help=text
                if "default" in text or f.default is None
                else f"{text} (default {f.default})",
            )
        if f.metadata.get("more"):
            if not isinstance(ap, Parser):
                raise TypeError("options left out of --help need a rainuav._cli.Parser")
            ap.hide(action)
