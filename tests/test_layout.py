"""The package's shape: every import arrow points down a layer, no import cycle, no module over
450 lines, and the old module paths still work (with a DeprecationWarning naming the new one).

Read from the source with ``ast`` (every import statement, also inside functions, except under
``if TYPE_CHECKING:``), so a lazy import cannot hide an upward arrow or a cycle."""

from __future__ import annotations

import ast
import importlib
import re
import subprocess
import sys
import warnings
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1] / "python" / "rainuav"
MAX_LINES = 450

# Layers, bottom up. A module may import a lower layer, or its own group; never a group of the
# same or a higher layer (so radio and nav do not know each other).
BASE = {"errors", "_io", "_checks", "_sampling", "_core", "_cli", "_threads"}
LAYERS = {
    "base": 0,
    "medium": 1,
    "cellpowers": 1,
    "signals": 2,
    "antenna": 1,
    "geo": 1,
    "missions": 2,
    "pwe": 2,
    "pwe_sources": 1,
    "cml": 2,
    "ground": 2,
    "radio": 3,
    "nav": 3,
    "world": 4,
    "rl": 5,
    "studies": 6,
    "entry": 7,
}
ENTRY = {
    "__init__",
    "envs",
    "study",
    "train",
    "evaluate",
    "radiomap",
    "validate",
    "fly",
}
# Third-party packages a group must not import.
FORBIDDEN = {
    "medium": {"torch", "gymnasium"},
    "antenna": {"torch", "gymnasium"},
    "geo": {"torch", "gymnasium"},
    "missions": {"torch", "gymnasium"},
    "cml": {"torch", "gymnasium"},
    "pwe": {"torch", "gymnasium"},
    "pwe_sources": {"torch", "gymnasium"},
    "signals": {"torch", "gymnasium"},
    "cellpowers": {"torch", "gymnasium"},
    "ground": {"torch", "gymnasium"},
    "radio": {"torch", "gymnasium"},
    "nav": {"torch"},
    "world": {"torch"},
}


def module_name(path: Path) -> str:
    parts = path.relative_to(ROOT.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def modules() -> dict[str, Path]:
    return {module_name(p): p for p in sorted(ROOT.rglob("*.py"))}


def group(name: str) -> str:
    parts = name.split(".")
    if len(parts) == 1:
        return "entry"  # the package's own __init__
    head = parts[1]
    if head in ("radio", "nav", "rl", "world", "ground"):
        return head
    if head in BASE:
        return "base"
    if head in ENTRY:
        return "entry"
    return head  # medium, antenna, pwe


def _type_checking(node: ast.If) -> bool:
    t = node.test
    return (isinstance(t, ast.Name) and t.id == "TYPE_CHECKING") or (
        isinstance(t, ast.Attribute) and t.attr == "TYPE_CHECKING"
    )


def imports(path: Path, known: set[str]) -> tuple[set[str], set[str]]:
    """(rainuav modules, top-level third-party packages) that ``path`` imports."""
    tree = ast.parse(path.read_text())
    ours: set[str] = set()
    theirs: set[str] = set()

    def add(name: str) -> None:
        if name == "rainuav" or name.startswith("rainuav."):
            # `from rainuav.radio import presets` names the module rainuav.radio.scene.presets.
            while name not in known and "." in name:
                name = name.rsplit(".", 1)[0]
            ours.add(name)
        else:
            theirs.add(name.split(".")[0])

    def visit(node: ast.AST) -> None:
        if isinstance(node, ast.If) and _type_checking(node):
            for child in node.orelse:
                visit(child)
            return
        if isinstance(node, ast.Import):
            for a in node.names:
                add(a.name)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            for a in node.names:
                full = f"{node.module}.{a.name}"
                add(full if full in known else node.module)
        for child in ast.iter_child_nodes(node):
            visit(child)

    visit(tree)
    return ours, theirs


def graph() -> tuple[dict[str, set[str]], dict[str, set[str]]]:
    mods = modules()
    known = {*mods, "rainuav._core"}  # the extension module has no .py source
    ours, theirs = {}, {}
    for name, path in mods.items():
        ours[name], theirs[name] = imports(path, known)
        ours[name].discard(name)
    return ours, theirs


def test_the_walker_sees_the_packages_modules() -> None:
    ours, theirs = graph()
    # A check on the checker: known arrows, including a function-level import.
    assert "rainuav.radio.scene.scenario" in ours["rainuav.radio.scene.presets"]
    assert "rainuav.nav.env" in ours["rainuav.nav.planner"]
    assert "rainuav.rl.loop" in ours["rainuav.train"]  # imported inside main()
    assert "torch" in theirs["rainuav.rl.dqn"]
    assert {"rainuav.radio", "rainuav.nav", "rainuav.rl"} <= set(ours)


RADIO_PARTS = ("scene", "engines", "outputs", "measured", "reference")
"""``rainuav.radio``'s sub-packages, bottom up: what is there, how the field gets there, what
comes out, what comes out corrected by measurements, and what the engines are measured
against."""


def test_radio_is_scene_engines_outputs_measured_and_reference() -> None:
    """Every module of ``rainuav.radio`` lives in one of its five parts, and a part imports only
    the parts below it (the scene may read the engines' registry, the package itself, to know
    the names a scenario may give)."""
    ours, _ = graph()
    radio = [m for m in ours if m.startswith("rainuav.radio.")]
    loose = [m for m in radio if m.split(".")[2] not in RADIO_PARTS]
    assert not loose, f"modules outside rainuav.radio's parts: {loose}"
    upward = []
    for src in radio:
        rank = RADIO_PARTS.index(src.split(".")[2])
        for dst in ours[src]:
            if not dst.startswith("rainuav.radio.") or dst == "rainuav.radio.engines":
                continue
            if RADIO_PARTS.index(dst.split(".")[2]) > rank:
                upward.append(f"{src} -> {dst}")
    assert not upward, f"rainuav.radio's parts import upward: {upward}"


def test_every_arrow_points_down() -> None:
    ours, _ = graph()
    upward = []
    for src, targets in ours.items():
        gs = group(src)
        for dst in targets:
            gd = group(dst)
            if gd != gs and LAYERS[gd] >= LAYERS[gs]:
                upward.append(f"{src} ({gs}) -> {dst} ({gd})")
    assert not upward, "imports that do not point down:\n" + "\n".join(sorted(upward))


def test_layers_keep_off_heavy_dependencies() -> None:
    _, theirs = graph()
    bad = [
        f"{name} imports {pkg}"
        for name, pkgs in theirs.items()
        for pkg in sorted(pkgs & FORBIDDEN.get(group(name), set()))
    ]
    assert not bad, "\n".join(bad)


def test_no_import_cycle() -> None:
    ours, _ = graph()
    state: dict[str, int] = {}  # 1: on the current path, 2: done
    stack: list[str] = []
    cycles: list[list[str]] = []

    def dfs(n: str) -> None:
        state[n] = 1
        stack.append(n)
        for m in sorted(ours.get(n, ())):
            if state.get(m) == 1:
                cycles.append([*stack[stack.index(m) :], m])
            elif m not in state:
                dfs(m)
        stack.pop()
        state[n] = 2

    for n in sorted(ours):
        if n not in state:
            dfs(n)
    assert not cycles, "import cycles:\n" + "\n".join(" -> ".join(c) for c in cycles)


def test_no_module_over_450_lines() -> None:
    long = {
        name: n
        for name, path in modules().items()
        if (n := len(path.read_text().splitlines())) > MAX_LINES
    }
    assert not long, long


def test_new_paths_and_entry_points_do_not_warn() -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for name in ("rainuav.radiomap", "rainuav.train", "rainuav.evaluate", "rainuav.validate"):
            assert callable(importlib.import_module(name).main)
        import rainuav

        assert rainuav.radio.Scenario is rainuav.radio.scene.scenario.Scenario
        assert rainuav.nav.UAVNavEnv is rainuav.nav.env.UAVNavEnv
    for old in ("env", "plan", "agent", "scenario", "scenarios", "_deprecated"):
        with pytest.raises(ModuleNotFoundError):  # the 0.1 shims are gone
            importlib.import_module(f"rainuav.{old}")


def test_importing_the_physics_does_not_import_gymnasium_or_torch() -> None:
    code = (
        "import sys, rainuav.medium, rainuav.radio; "
        "print(sorted(m for m in ('gymnasium', 'torch') if m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "[]"
    # and gym.make still finds the environment when Gymnasium is imported after rainuav
    code = "import rainuav, gymnasium as gym; print('rainuav/UAVNav-v0' in gym.registry)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.stdout.strip() == "True", out.stderr


# The physics' tests: the rain medium, propagation, maps and the ground (no learner).
PHYSICS_TESTS = (
    "test_antenna.py",
    "test_buildings.py",
    "test_engines.py",
    "test_geotiff.py",
    "test_ground_roughness.py",
    "test_cml_links.py",
    "test_medium_errors.py",
    "test_medium_properties.py",
    "test_medium_reference.py",
    "test_osm_exports.py",
    "test_pwe.py",
    "test_pwe_errors.py",
    "test_radiomap.py",
    "test_rategrid.py",
    "test_sampling.py",
    "test_terrain.py",
    "test_timemap.py",
    "test_tracer.py",
    "test_wedge_exact.py",
)


@pytest.mark.slow
def test_the_physics_tests_do_not_need_torch() -> None:
    """With torch unimportable, the physics' test modules (and the shared conftest) import and
    collect: a checkout without the learner's dependency can run them."""
    tests = Path(__file__).resolve().parent
    files = [str(tests / f) for f in PHYSICS_TESTS]
    code = (
        "import sys; sys.modules['torch'] = None; import pytest; "
        f"sys.exit(pytest.main(['--collect-only', '-q', '-p', 'no:cacheprovider', *{files!r}]))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=240, cwd=tests.parent
    )
    # 0: every module collected (a module that imports torch is a collection error, exit 2).
    assert out.returncode == 0, out.stdout[-3000:] + out.stderr[-3000:]
    assert "tests collected" in out.stdout, out.stdout[-3000:]


REPO = ROOT.parents[1]
PAGES = ["README.md", "BENCHMARKS.md", "CONTRIBUTING.md", "docs/**/*.md"]


def test_every_benchmark_and_experiment_is_cited_and_every_cited_one_exists() -> None:
    """``benches/`` holds speed (the pytest-benchmark comparisons ``make bench`` runs, and timing
    scripts), ``experiments/`` the runs behind published figures: a script that no page names is
    removed, and a command a page gives names a script that exists."""
    text = "\n".join(
        p.read_text() for pattern in PAGES for p in REPO.glob(pattern) if "api" not in p.parts
    )
    scripts = [
        p
        for folder in ("benches", "experiments")
        for p in sorted((REPO / folder).glob("*"))
        if p.suffix in (".py", ".sh") and p.name != "conftest.py"
        and not p.name.startswith("test_")  # pytest-benchmark files: `make bench` runs them
    ]  # fmt: skip
    assert len(scripts) >= 20
    uncited = [str(p.relative_to(REPO)) for p in scripts if p.name not in text]
    assert not uncited, f"no page cites {uncited}: remove them or cite them with their command"
    import re

    cited = set(re.findall(r"\b((?:benches|experiments)/[A-Za-z0-9_]+\.(?:py|sh))\b", text))
    missing = sorted(c for c in cited if not (REPO / c).exists())
    assert not missing, f"pages cite scripts that do not exist: {missing}"


RUST_OVER: dict[str, int] = {}
"""The Rust files allowed over the Python modules' 450 lines, each at most its length here (none:
a long module is split into its own folder of parts, its unit tests in ``<module>/tests.rs``)."""


def test_rust_files_keep_the_size_discipline() -> None:
    sizes = {
        str(p.relative_to(REPO)): len(p.read_text().splitlines())
        for p in (REPO / "crates").rglob("*.rs")
        if "target" not in p.parts
    }
    over = {f: n for f, n in sizes.items() if n > RUST_OVER.get(f, MAX_LINES)}
    assert not over, f"Rust files over {MAX_LINES} lines (or past their cap): {over}"
    stale = {f: (RUST_OVER[f], sizes.get(f)) for f in RUST_OVER if sizes.get(f, 0) <= MAX_LINES}
    assert not stale, f"take these off RUST_OVER (split, or gone): {stale}"


def test_the_rust_core_is_three_layers_that_do_not_import_one_another() -> None:
    # crates/rainuav-core/src: the rain medium, propagation and planning, each a module with
    # its folder; at the root only the shared error type and memory check. The bindings
    # (crates/rainuav-py) join the layers; no layer reaches into another.
    src = REPO / "crates" / "rainuav-core" / "src"
    layers = ("medium", "propagation", "planning")
    roots = {p.stem for p in src.glob("*.rs")}
    assert roots == {"lib", "error", "memory", *layers}, roots
    for layer in layers:
        files = [src / f"{layer}.rs", *(src / layer).rglob("*.rs")]
        for other in (x for x in layers if x != layer):
            hits = [str(f.relative_to(src)) for f in files if f"crate::{other}" in f.read_text()]
            assert not hits, f"{layer} imports {other}: {hits}"


def test_engines_are_asked_what_they_do_not_their_names() -> None:
    """The propagation engines are known by name in one place
    ([`rainuav.radio.engines`][rainuav.radio.engines]); elsewhere code asks an engine what it
    does (``engine_of(scn).traces``), never compares its name."""
    import re

    from rainuav.radio.engines import ENGINES, engine_of
    from rainuav.radio.scene.scenario import ENGINES as SCENARIO_ENGINES

    named = re.compile(r"""engine\w*\s*(==|!=|not in|in)\s*[("']+(hybrid|ray|pe)\b""")
    hits = [
        f"{name}:{i + 1}"
        for name, path in modules().items()
        if name != "rainuav.radio.engines"
        for i, line in enumerate(path.read_text().splitlines())
        if named.search(line)
    ]
    assert not hits, f"engine names compared at {hits}: ask rainuav.radio.engines.engine_of()"
    assert tuple(ENGINES) == SCENARIO_ENGINES == ("hybrid", "ray", "pe")
    # What each does: the hybrid both, the rays no march, the PE no rays (so no soil and no maps
    # in time: a request in time goes to the hybrid).
    assert [(e.marches, e.traces, e.in_time) for e in ENGINES.values()] == [
        (True, True, "hybrid"), (False, True, "ray"), (True, False, "hybrid"),
    ]  # fmt: skip
    from rainuav.radio.scene.presets import paper

    assert engine_of("ray") is ENGINES["ray"] and engine_of(paper()) is ENGINES["hybrid"]
    from rainuav.radio.engines import for_time

    scn = paper()
    assert for_time(scn) is scn and for_time(scn.replace(engine="pe")).engine == "hybrid"


def test_the_learner_never_tests_environment_classes() -> None:
    """Outside the environments' own package (``rainuav.nav``), code flies an environment through
    the interface both share (``observe_batch``, ``step_batch``, ``exploration_moves``,
    ``start_level_at``, ``altitudes_m``, the spaces), never by testing its class."""
    import re

    tested = re.compile(r"isinstance\([^)]*\b(UAVNavEnv|UAVLevelsEnv|UAVNavVectorEnv)\b")
    hits = [
        f"{name}:{i + 1}"
        for name, path in modules().items()
        if not name.startswith("rainuav.nav")
        for i, line in enumerate(path.read_text().splitlines())
        if tested.search(line)
    ]
    assert not hits, f"environment classes tested at {hits}"


def test_no_map_class_is_tested_outside_its_module() -> None:
    """Every map kind says how it is one signal (its ``as_signal()``): outside the module that
    defines a map class, code reads maps through that and through what they carry, never by
    testing their class (an ``isinstance`` chain grows a branch for every new kind)."""
    import re

    classes = {"RadioMap": "mapdata", "RadioMapSeries": "timemap", "RadioLevels": "levelmaps",
               "RadioLevelSeries": "levelmaps", "LevelStack": "levelmaps"}  # fmt: skip
    tested = re.compile(r"isinstance\(.*?\b(" + "|".join(classes) + r")\b")
    hits = [
        f"{name}:{i + 1}"
        for name, path in modules().items()
        for i, line in enumerate(path.read_text().splitlines())
        if (m := tested.search(line)) and not name.endswith("." + classes[m.group(1)])
    ]
    assert not hits, f"map classes tested at {hits}"


def test_no_class_goes_by_a_second_name() -> None:
    """One name per thing: no module binds a class of the package, or one of its makers, to a
    second name (``SirField = SignalField``, ``SignalSeries = SignalField.series``: such aliases
    of old names were removed, and the changelog lists each with its replacement)."""
    trees = {name: ast.parse(path.read_text()) for name, path in modules().items()}
    classes = {n.name for t in trees.values() for n in ast.walk(t) if isinstance(n, ast.ClassDef)}
    hits = []
    for name, tree in trees.items():
        for node in tree.body:
            if not (isinstance(node, ast.Assign) and len(node.targets) == 1):
                continue
            target, value = node.targets[0], node.value
            root = value
            while isinstance(root, ast.Attribute):
                root = root.value
            if (isinstance(target, ast.Name) and target.id[:1].isupper() and not target.id.isupper()
                    and isinstance(root, ast.Name) and root.id in classes):  # fmt: skip
                hits.append(f"{name}:{node.lineno} {target.id}")
    assert not hits, f"second names of classes: {hits}"


def test_one_environment_class() -> None:
    """One environment flies one level and several: ``UAVLevelsEnv`` is ``UAVNavEnv``'s
    constructor with the arguments it has always taken, with no behaviour of its own."""
    from rainuav.nav.env import UAVNavEnv
    from rainuav.nav.levels import UAVLevelsEnv

    assert issubclass(UAVLevelsEnv, UAVNavEnv)
    own = {k for k in vars(UAVLevelsEnv) if not (k.startswith("__") and k.endswith("__"))}
    assert not own and set(vars(UAVLevelsEnv)) & {"__init__"} == {"__init__"}, own


HAND_WRITTEN_COMMANDS: set[str] = set()
"""The commands whose options are still written by hand (none: this set may only shrink)."""


def test_generated_commands_take_every_option_from_their_dataclasses() -> None:
    """``train``, ``evaluate``, ``radiomap`` and ``fly`` generate their options from dataclasses:
    every option a user sees is a field (``train``: its run, task and learner; the others their
    ``...Options``), with the field's docstring as its help; the other commands are the listed
    hand-written ones."""
    import argparse
    import dataclasses

    from rainuav import _cli, evaluate, fly, radiomap, study, train, validate
    from rainuav.radio.engines import ENGINES
    from rainuav.rl.config import SECTIONS, TrainConfig

    commands = {p.stem for p in ROOT.glob("*.py") if "def main(" in p.read_text()}
    commands |= {p.parent.name for p in ROOT.glob("*/__main__.py")}
    generated = {"train", "evaluate", "radiomap", "fly", "study", "validate"}
    assert commands - generated == HAND_WRITTEN_COMMANDS, commands

    def shown(ap: argparse.ArgumentParser) -> set[str]:
        return {
            a.dest
            for a in ap._actions
            if a.option_strings and a.help != argparse.SUPPRESS and a.dest != "help"
        }

    for command, options in ((evaluate, evaluate.EvaluateOptions),
                             (radiomap, radiomap.RadiomapOptions),
                             (fly, fly.FlyOptions),
                             (study, study.StudyOptions)):  # fmt: skip
        every = {f.name for f in dataclasses.fields(options)}
        more = {f.name for f in dataclasses.fields(options) if f.metadata.get("more")}
        # --help lists the common options, --help-all every one; each is a flag either way.
        assert shown(_cli.show_all(command.build_parser())) - {"help_all"} == every
        assert shown(command.build_parser()) - {"help_all"} == every - more
        assert len(every - more) <= 15, command.__name__
        engine = [a for a in command.build_parser()._actions if a.dest == "engine"]
        assert not engine or tuple(engine[0].choices) == tuple(ENGINES)  # from the registry
    rain = validate.build_parser()._subparsers._group_actions[0].choices["rain"]  # type: ignore[union-attr]
    assert shown(rain) - {"help_all"} == {
        f.name for f in dataclasses.fields(validate.RainValidationOptions)
    }
    run = {f.name for f in dataclasses.fields(TrainConfig) if f.name not in SECTIONS}
    run |= {f"{n}.{f.name}" for n, c in SECTIONS.items() for f in dataclasses.fields(c)}
    assert shown(train.build_parser(show_all=True)) - {"help_all", "config", "resume"} == run
    assert shown(train.build_parser()) - {"help_all", "config", "resume"} == set(train.SHOWN)


def test_help_lists_the_common_options_and_help_all_every_one(
    capsys: pytest.CaptureFixture[str],
) -> None:
    from rainuav import fly

    texts = []
    for flag in ("--help", "--help-all"):
        with pytest.raises(SystemExit) as stop:
            fly.main([flag])
        assert stop.value.code == 0
        texts.append(capsys.readouterr().out)
    short, full = texts
    assert "--help-all" in short and "--sites" in short and "--sites" in full
    assert "--speed-m-s" not in short and "--speed-m-s" in full
    # An option --help leaves out is read all the same.
    needed = ["--sites", "s.csv", "--start", "47.37,8.54", "--goal", "47.38,8.55", "--out", "o"]
    args = fly.build_parser().parse_args([*needed, "--speed-m-s", "5"])
    assert args.speed_m_s == 5.0


def test_the_learner_reads_an_environment_through_the_stated_protocol_alone() -> None:
    """``rl/`` reads an environment (``env.``, ``self.env.``) through
    ``rainuav.nav.batched.PROTOCOL`` alone: the spaces, the random stream, Gymnasium's calls and
    the batched ones with ``terms()`` and ``digest()``, never its field, task or levels (77
    reads of ``env.cfg``, ``env.field`` and ``env.altitudes_m`` when this was first counted)."""
    from rainuav.nav.batched import PROTOCOL

    read = re.compile(r"\benv\.([A-Za-z_]\w*)")
    hits = [
        f"{p.name}:{i + 1}: env.{m.group(1)}"
        for p in sorted((ROOT / "rl").glob("*.py"))
        for i, line in enumerate(p.read_text().splitlines())
        for m in read.finditer(line)
        if m.group(1) not in PROTOCOL
    ]
    assert not hits, hits


MAX_FUNCTION_LINES = 80
"""The most lines a function's code may take (its docstring aside) without a reason above it."""


def _reason_above(lines: list[str], first: int, marks: tuple[str, ...]) -> bool:
    """Whether the comments, doc comments and decorators just above line ``first`` (0-based)
    hold a ``Long:`` reason."""
    k = first - 1
    while k >= 0 and lines[k].strip().startswith(marks):
        if "Long:" in lines[k]:
            return True
        k -= 1
    return False


def _long_python_functions() -> list[str]:
    found = []
    for name, path in modules().items():
        lines = path.read_text().splitlines()
        for node in ast.walk(ast.parse("\n".join(lines))):
            if not isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                continue
            body = node.body
            doc = isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant)
            start = body[1].lineno if doc and len(body) > 1 else body[0].lineno
            first = min([node.lineno, *(d.lineno for d in node.decorator_list)]) - 1
            if node.end_lineno - start + 1 > MAX_FUNCTION_LINES and not _reason_above(
                lines, first, ("#", "@")
            ):
                found.append(f"{name}.{node.name} ({node.end_lineno - start + 1} lines)")
    return found


def _long_rust_functions() -> list[str]:
    import re

    found = []
    fn = re.compile(r"^\s*(pub(\([a-z]+\))?\s+)?(const\s+)?(unsafe\s+)?fn\s+(\w+)")
    for path in sorted((ROOT.parents[1] / "crates").glob("*/src/**/*.rs")):
        lines = path.read_text().splitlines()
        i = 0
        while i < len(lines):
            m = fn.match(lines[i])
            if not m:
                i += 1
                continue
            depth, j, opened = 0, i, False
            while j < len(lines):
                depth += lines[j].count("{") - lines[j].count("}")
                opened = opened or "{" in lines[j]
                if (opened and depth <= 0) or (not opened and lines[j].rstrip().endswith(";")):
                    break
                j += 1
            if j - i + 1 > MAX_FUNCTION_LINES and not _reason_above(lines, i, ("//", "#[")):
                found.append(f"{path.relative_to(ROOT.parents[1])}:{i + 1} {m.group(5)}")
            i = j + 1 if opened else i + 1
    return found


def test_no_function_over_80_lines_without_a_reason_above_it() -> None:
    """A function in either language whose code runs past 80 lines says why, in a ``Long:``
    comment above it (Python: a ``#`` line above its ``def`` or decorators; Rust: a ``//`` line
    among its doc comments and attributes)."""
    assert not _long_python_functions()
    assert not _long_rust_functions()
