"""A study: a base case and the axes to sweep, read from TOML and checked before any work.

.. code-block:: toml

    name = "paper-sweeps"
    sweep = "one_at_a_time"     # or "grid": every combination of the axes
    seeds = [0]
    compute = ["map", "optimal", "learned"]
    eval_starts = 200

    [base]                      # any rainuav.rl.config.TrainConfig field, "task.<field>"
    scenario = "paper"          # (or the task field's name alone), "dqn.<field>", or a
    rain_rate_mm_h = 25.0       # scenario override: freq_ghz, wind_m_s, wind_model, engine

    [axes]                      # each axis: a list of values for one field,
    rain_rate_mm_h = [0.0, 25.0, 50.0, 100.0]
    mu = [0.1, 0.2326, 10.0]    # or, under a name of its own, of tables of fields set together
    paper_wind = [{wind_m_s = 2.0, wind_model = "paper"}, {wind_m_s = 5.0, wind_model = "paper"}]

    [quick]                     # what --quick changes (any field, as in [base])
    "dqn.episodes" = 300

``one_at_a_time`` runs the base case, then each axis value with the other fields at the
base (the change per axis is read against the base); ``grid`` runs every combination. Each
case runs once per seed. Unknown fields, empty axes and values out of range are refused with
the field named ([`load_study()`][rainuav.studies.spec.load_study]), before any work starts.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

from rainuav._io import read_toml
from rainuav.errors import InvalidInputError
from rainuav.radio.scene import presets
from rainuav.radio.scene.scenario import Scenario
from rainuav.rl.config import MAX_STARTS, TrainConfig, check_config, field_name, resolve_config
from rainuav.world import make_scenario

__all__ = ["BUILT_IN", "COMPUTE", "SCENARIO_FIELDS", "Case", "Study", "load_study"]

COMPUTE = ("map", "optimal", "learned", "altitudes")
SCENARIO_FIELDS = ("freq_ghz", "wind_m_s", "wind_model", "engine", "altitudes_m")
"""Fields of a case that change the scenario rather than the run (``altitudes_m``: the levels
its ``altitudes`` figures map and plan among, the case's own map staying at the scenario's
altitude)."""
BUILT_IN = ("paper-sweeps", "mmwave", "storms", "altitude")
MAX_CASES = 10_000
"""The most cases a study may have (axes x seeds): every case is at least a map and a plan."""
_TOP = {"name", "sweep", "seeds", "compute", "eval_starts", "base", "axes", "quick"}


def _label(v: Any) -> str:
    """An axis value as text: numbers in short form, a table of fields as their values."""
    if isinstance(v, dict):
        return "-".join(_label(x) for x in v.values())
    return f"{v:g}" if isinstance(v, float) else str(v)


@dataclass(frozen=True)
class Case:
    """One case: its index, the axis it varies (``"base"`` for the base case, ``"grid"``
    for a grid cell), its fields, its seed and the axis value as text (``value``; for a grid
    cell each axis's value in the axes' order, comma-separated; empty for the base)."""

    index: int
    axis: str
    fields: tuple[tuple[str, Any], ...]
    seed: int
    value: str = ""

    @property
    def id(self) -> str:
        """A folder name: the index, the axis and its value, the seed."""
        value = f"={self.value}" if self.value else ""
        return f"{self.index:03d}_{self.axis}{value}_s{self.seed}".replace("/", "-")


@dataclass
class Study:
    name: str
    base: dict[str, Any]
    axes: dict[str, list[Any]]
    seeds: list[int] = field(default_factory=lambda: [0])
    compute: list[str] = field(default_factory=lambda: list(COMPUTE))
    sweep: str = "one_at_a_time"
    eval_starts: int = 200
    quick: dict[str, Any] = field(default_factory=dict)

    def cases(self) -> list[Case]:
        """Every case of the study, in a fixed order.

        Returns:
            The [`Case`][rainuav.studies.spec.Case]s, the grid of the axes' values crossed with the
            seeds; the index is the row of `results.csv`.
        """
        combos: list[tuple[str, dict[str, Any], str]] = []
        if self.sweep == "grid":
            names = list(self.axes)
            for values in itertools.product(*(self.axes[n] for n in names)):
                change: dict[str, Any] = {}
                for n, v in zip(names, values, strict=True):
                    change.update(v if isinstance(v, dict) else {n: v})
                combos.append(("grid", change, ",".join(_label(v) for v in values)))
        else:
            combos.append(("base", {}, ""))
            for name, values in self.axes.items():
                for v in values:
                    change = dict(v) if isinstance(v, dict) else {name: v}
                    if any(self.base.get(k) != x for k, x in change.items()):
                        combos.append((name, change, _label(v)))
        out = []
        for axis, change, label in combos:
            merged = {**self.base, **change}
            for seed in self.seeds:
                out.append(Case(len(out), axis, tuple(sorted(merged.items())), seed, label))
        return out

    def axis_fields(self, axis: str) -> set[str]:
        """The fields an axis sets.

        Args:
            axis: The axis's name.

        Returns:
            Its own name, or the keys of its tables where its values are tables.
        """
        keys: set[str] = set()
        for v in self.axes.get(axis, []):
            keys |= set(v) if isinstance(v, dict) else {axis}
        return keys

    def with_quick(self) -> Study:
        """The study with its `[quick]` changes applied to the base case.

        An `eval_starts` there sets the study's number of evaluation starts.

        Returns:
            A new [`Study`][rainuav.studies.spec.Study].
        """
        quick = dict(self.quick)
        starts = quick.pop("eval_starts", self.eval_starts)
        return dataclasses.replace(self, base={**self.base, **quick}, eval_starts=starts)


def train_config(fields: dict[str, Any], seed: int, out: str) -> TrainConfig:
    """The training configuration of a case (its scenario's overrides left out).

    Its preset, if it names one, then its fields
    ([`resolve_config()`][rainuav.rl.config.resolve_config]).

    Args:
        fields: The case's fields.
        seed: Its seed.
        out: Its run's folder.

    Returns:
        The [`TrainConfig`][rainuav.rl.config.TrainConfig].
    """
    kept = {k: v for k, v in fields.items() if k not in SCENARIO_FIELDS}
    return resolve_config({**kept, "seed": seed, "out": out})


def case_scenario(fields: dict[str, Any], cfg: TrainConfig) -> Scenario:
    """The scenario of a case: the run's (preset or file, rain rate), then the overrides.

    Args:
        fields: The case's fields (`freq_ghz`, `wind_m_s`, `engine`, ... among them).
        cfg: The case's training configuration.

    Returns:
        The [`Scenario`][rainuav.radio.scene.scenario.Scenario].
    """
    scn = make_scenario(cfg)
    if fields.get("freq_ghz") is not None:
        scn = dataclasses.replace(scn, freq_hz=float(fields["freq_ghz"]) * 1e9)
    if fields.get("engine") is not None:
        scn = dataclasses.replace(scn, engine=fields["engine"])
    if fields.get("altitudes_m") is not None:
        area = dataclasses.replace(scn.area, altitudes_m=list(fields["altitudes_m"]))
        area.check("altitudes_m")
        scn = dataclasses.replace(scn, area=area)
    if fields.get("wind_m_s") is not None:
        medium = dataclasses.replace(scn.medium, wind_speed_m_s=float(fields["wind_m_s"]))
        scn = dataclasses.replace(scn, medium=medium)
    if fields.get("wind_model") is not None:
        medium = dataclasses.replace(scn.medium, wind_model=fields["wind_model"])
        scn = dataclasses.replace(scn, medium=medium)
        scn.medium.check("medium")
    return scn


def _check_fields(where: str, fields: dict[str, Any]) -> None:
    for k in fields:
        if k in SCENARIO_FIELDS:
            continue
        if k in ("seed", "out") or field_name(k) is None:
            raise InvalidInputError(
                f"{where}: unknown field {k!r} (a TrainConfig field, 'task.<field>', "
                f"'dqn.<field>' or one of {list(SCENARIO_FIELDS)})"
            )


def _check_case(where: str, fields: dict[str, Any]) -> None:
    """Builds the case's configuration and scenario (without its map): every range check
    of TrainConfig and Scenario runs, naming the field."""
    try:
        cfg = train_config(fields, 0, "unused")
    except (TypeError, InvalidInputError) as err:
        raise InvalidInputError(f"{where}: {err}") from err
    check_config(cfg)
    f = fields.get("freq_ghz")
    if f is not None and not (isinstance(f, (int, float)) and 0.1 <= f <= 100):
        raise InvalidInputError(f"{where}: freq_ghz must be in [0.1, 100] (got {f!r})")
    if fields.get("scenario_file") in (None, "") and cfg.scenario not in presets.PRESETS:
        raise InvalidInputError(
            f"{where}: scenario must be one of {sorted(presets.PRESETS)} (got {cfg.scenario!r})"
        )
    try:
        case_scenario(fields, cfg)
    except InvalidInputError as err:
        raise InvalidInputError(f"{where}: {err}") from err


def parse_study(data: dict[str, Any], where: str) -> Study:
    """A study from a TOML table, checked (every case's configuration included).

    Args:
        data: The table.
        where: What the errors name (the file).

    Returns:
        The [`Study`][rainuav.studies.spec.Study].

    Raises:
        InvalidInputError: An unknown field, an empty or repeating axis, bad seeds, compute or
            sweep, too many cases, or a case that repeats another (named).
    """
    unknown = sorted(set(data) - _TOP)
    if unknown:
        raise InvalidInputError(f"{where}: unknown field {unknown[0]!r} (allowed: {sorted(_TOP)})")
    base, axes, quick = data.get("base", {}), data.get("axes", {}), data.get("quick", {})
    for name, table in (("base", base), ("axes", axes), ("quick", quick)):
        if not isinstance(table, dict):
            raise InvalidInputError(f"{where}: [{name}] must be a table")
    _check_fields(f"{where} [base]", base)
    _check_fields(f"{where} [quick]", quick)
    # A list value (altitudes_m) is one value of its field: a tuple, so cases compare.
    base = {k: tuple(v) if isinstance(v, list) else v for k, v in base.items()}
    quick = {k: tuple(v) if isinstance(v, list) else v for k, v in quick.items()}
    for k, v in axes.items():
        if not isinstance(v, list) or not v:
            raise InvalidInputError(f"{where} [axes]: {k} must be a non-empty list of values")
        tables = [isinstance(x, dict) for x in v]
        if any(tables) and not all(tables):
            raise InvalidInputError(
                f"{where} [axes]: {k} must hold values of one field or tables of fields, not both"
            )
        if all(tables):
            for x in v:
                if not x:
                    raise InvalidInputError(f"{where} [axes]: {k} holds an empty table")
                _check_fields(f"{where} [axes] {k}", x)
        else:
            _check_fields(f"{where} [axes]", {k: v})
    seeds = data.get("seeds", [0])
    if not (isinstance(seeds, list) and seeds and all(type(s) is int for s in seeds)):
        raise InvalidInputError(f"{where}: seeds must be a non-empty list of integers")
    compute = data.get("compute", list(COMPUTE))
    if not (isinstance(compute, list) and compute and set(compute) <= set(COMPUTE)):
        raise InvalidInputError(f"{where}: compute must be a non-empty subset of {COMPUTE}")
    sweep = data.get("sweep", "one_at_a_time")
    if sweep not in ("one_at_a_time", "grid"):
        raise InvalidInputError(f"{where}: sweep must be 'one_at_a_time' or 'grid'")
    n = data.get("eval_starts", 200)
    if type(n) is not int or not 1 <= n <= MAX_STARTS:
        raise InvalidInputError(f"{where}: eval_starts must be an integer in 1..{MAX_STARTS}")
    name = data.get("name", "study")
    if not isinstance(name, str) or not name:
        raise InvalidInputError(f"{where}: name must be a non-empty string")
    for k, v in axes.items():
        seen: list[Any] = []
        for x in v:
            if x in seen:
                raise InvalidInputError(f"{where} [axes]: {k} repeats the value {_label(x)!r}")
            seen.append(x)
    repeated = sorted({s for s in seeds if seeds.count(s) > 1})
    if repeated:
        raise InvalidInputError(f"{where}: seeds repeats {repeated[0]} (a case runs once a seed)")
    # Count first: a grid of a million cases is refused at once, not after checking each.
    if sweep == "grid":
        n_cases = math.prod(len(v) for v in axes.values()) * len(seeds)
    else:
        n_cases = (1 + sum(len(v) for v in axes.values())) * len(seeds)
    if n_cases > MAX_CASES:
        raise InvalidInputError(
            f"{where}: {n_cases} cases (axes x seeds); a study may have at most {MAX_CASES}"
        )
    study = Study(name, dict(base), {k: list(v) for k, v in axes.items()}, seeds, compute,
                  sweep, n, dict(quick))  # fmt: skip
    for s in (study, study.with_quick()):
        first: dict[tuple[Any, ...], str] = {}
        for case in s.cases():
            _check_case(f"{where} case {case.id}", dict(case.fields))
            key = (case.fields, case.seed)
            if key in first:
                raise InvalidInputError(
                    f"{where}: case {case.id} repeats case {first[key]} (the same fields and "
                    "seed); drop one of the values"
                )
            first[key] = case.id
    return study


def load_study(name_or_path: str | Path) -> Study:
    """A built-in study by name, or a study read from a TOML file.

    Args:
        name_or_path: `paper-sweeps`, `mmwave`, or the path of a study TOML file.

    Returns:
        The [`Study`][rainuav.studies.spec.Study], checked.

    Raises:
        InvalidInputError: An unknown name, an unreadable or malformed file, or a field out of range
            (named).
    """
    if str(name_or_path) == "paper" and not Path("paper").is_file():
        raise InvalidInputError("study 'paper' is now 'paper-sweeps' (the paper's section VI)")
    if str(name_or_path) in BUILT_IN:
        ref = resources.files("rainuav.studies") / f"{name_or_path}.toml"
        with resources.as_file(ref) as path:
            return parse_study(read_toml(path, "study file"), f"study {name_or_path}")
    path = Path(name_or_path)
    return parse_study(read_toml(path, "study file"), str(path))
