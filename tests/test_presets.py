"""Presets are files: the TOML presets shipped with the package hold the configurations the
training command set in code before (``--preset paper-learner``, ``--preset storms`` and
``--preset storm-levels``), one function lays a preset, a run file and flags over each other, and
the same configuration gives the same run bit for bit however it was reached."""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from rainuav.errors import InvalidInputError
from rainuav.nav.task import NavConfig
from rainuav.rl.config import (
    DQNConfig,
    TrainConfig,
    check_config,
    load_config,
    preset_fields,
    preset_names,
    resolve_config,
)
from rainuav.train import build_parser, config_from_args, main

# What the training command set in code before the presets were files (its PAPER_LEARNER,
# STORM_LEARNER, STORM_LEVELS and budget constants), copied here as the configurations the
# files must reproduce.
PAPER_BEFORE: dict[str, Any] = {
    "target_sync_episodes": 5, "eps0": 0.5, "eps_decay": 0.998, "replay_capacity": 100_000,
    "batch_size": 16, "learning_starts": 16, "train_every": 1, "loss": "mse", "lanes": 1,
    "fourier": 0, "goal_features": 0, "time_aware": False, "goal_starts": 0.0, "shaping": 0.0,
    "sir_weight": 1.0, "reward_scale": 1.0, "grad_clip": 0.0, "average_from": 1.0,
    "shield": False,
}  # fmt: skip
STORM_LEARNER_BEFORE: dict[str, Any] = {
    "episodes": 9000, "batch_size": 64, "lr": 3e-4, "target_sync_episodes": 25, "conv": 8,
    "move_features": True, "goal_maps": True,
}  # fmt: skip
STORMS_BEFORE: dict[str, Any] = {
    "storm_seed": 0, "storm_pool": 16, "observation": "weather", "random_goal": True,
    "time_budget_s": 3300.0, "calm_share": 0.15,
}  # fmt: skip


def _cli(*argv: str) -> TrainConfig:
    return config_from_args(build_parser().parse_args(list(argv)))


def test_the_shipped_presets_are_the_configurations_the_code_set() -> None:
    assert preset_names() == ["paper-learner", "storm-levels", "storms"]
    paper = resolve_config({"preset": "paper-learner"})
    assert {k: getattr(paper.dqn, k) for k in PAPER_BEFORE} == PAPER_BEFORE
    # The rest is the default learner, with a constant learning rate (lr_final 0: lr throughout).
    rest = {f.name for f in dataclasses.fields(DQNConfig)} - set(PAPER_BEFORE) - {"lr_final"}
    assert all(getattr(paper.dqn, k) == getattr(DQNConfig(), k) for k in rest)
    assert paper.dqn.lr_final == 0.0 and paper.preset == "paper-learner"
    storms = resolve_config({"preset": "storms"})
    assert storms.scenario == "storm"
    assert {k: getattr(storms, k) for k in STORMS_BEFORE} == STORMS_BEFORE
    assert {k: getattr(storms.dqn, k) for k in STORM_LEARNER_BEFORE} == STORM_LEARNER_BEFORE
    levels = resolve_config({"preset": "storm-levels"})
    want = {**dataclasses.asdict(storms), "preset": "storm-levels", "altitudes_m": "25:115:15"}
    want.update(storm_pool=8, storm_episodes=48, engine="ray")
    want["dqn"] = {**want["dqn"], "episodes": 4000}
    assert dataclasses.asdict(levels) == want
    for cfg in (paper, storms, levels):
        check_config(cfg)


def test_the_storm_presets_and_flags_win(capsys: pytest.CaptureFixture[str]) -> None:
    cfg = _cli("--preset", "storm-levels", "--engine", "hybrid", "--storm-pool", "4",
               "--dqn.episodes", "100")  # fmt: skip
    assert (cfg.engine, cfg.storm_pool, cfg.dqn.episodes, cfg.storm_episodes) == (
        "hybrid", 4, 100, 48,
    )  # fmt: skip
    cfg = _cli("--preset", "storms", "--random-goal", "false", "--dqn.conv", "4",
               "--calm-share", "0")  # fmt: skip
    assert (cfg.random_goal, cfg.dqn.conv, cfg.dqn.move_features, cfg.calm_share) == (
        False, 4, True, 0.0,
    )  # fmt: skip
    # The storm distribution is a preset: a storm seed is a number, and the error says which
    # preset to use.
    with pytest.raises(SystemExit) as stop:
        _cli("--storm-seed", "random")
    assert stop.value.code == 2
    assert "every storm: --preset storms" in capsys.readouterr().err


def test_a_preset_then_the_run_file_then_the_flags(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    run = tmp_path / "run.toml"
    run.write_text('preset = "paper"\nmax_steps = 70\n[dqn]\nlanes = 2\nlr = 5e-4\n')
    cfg = _cli("--config", str(run), "--dqn.lanes", "3", "--task.max-steps", "80")
    # The flags over the file, the file over the preset, the preset over the defaults.
    assert (cfg.dqn.lanes, cfg.task.max_steps, cfg.dqn.lr, cfg.dqn.loss) == (3, 80, 5e-4, "mse")
    # A task field at the top of a file and the preset's earlier name (a run folder of an
    # earlier release) are the [task] table's and the preset's today.
    assert load_config(run).task.max_steps == 70
    assert load_config(run).preset == "paper-learner"
    # On the command line, the preset's name of today alone.
    assert main(["--preset", "paper", "--out", str(tmp_path / "o")]) == 2
    assert "preset 'paper' is now 'paper-learner'" in capsys.readouterr().err
    assert load_config(run).dqn.lanes == 2 and load_config(run).dqn.loss == "mse"
    # An override of a field the preset sets is said in one line.
    _cli("--preset", "paper-learner", "--dqn.lanes", "4")
    assert "--dqn.lanes 4 in place of the preset 'paper-learner''s 1" in capsys.readouterr().err
    # A preset of one's own: a file, which may start from a shipped one (under its earlier name
    # too).
    mine = tmp_path / "mine.toml"
    mine.write_text('extends = "paper"\nseed = 7\n[dqn]\nhidden = 64\n')
    cfg = _cli("--preset", str(mine))
    assert (cfg.seed, cfg.dqn.hidden, cfg.dqn.loss, cfg.preset) == (7, 64, "mse", str(mine))


def test_bad_presets_are_refused_in_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["--preset", "papr", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "preset must be one of ['paper-learner'" in err
    loop = tmp_path / "loop.toml"
    loop.write_text(f'extends = "{loop}"\n')
    with pytest.raises(InvalidInputError, match="extends must name another preset"):
        preset_fields(loop)
    bad = tmp_path / "bad.toml"
    bad.write_text("[dqn]\nlearning_rate = 1e-4\n")
    with pytest.raises(InvalidInputError, match=r"unknown field\(s\) \['dqn.learning_rate'\]"):
        resolve_config({"preset": str(bad)})
    with pytest.raises(InvalidInputError, match="preset must be ''"):
        check_config(TrainConfig(preset="nothing-here"))


def test_help_lists_the_runs_own_flags_and_help_all_every_field(
    capsys: pytest.CaptureFixture[str],
) -> None:
    with pytest.raises(SystemExit):
        build_parser().parse_args(["--help"])
    short = capsys.readouterr().out
    shown = {w.split()[0] for w in short.split("\n  --")[1:]}
    assert 12 <= len(shown) <= 20, shown
    assert "dqn.lr" not in shown and "--dqn.NAME" in short and "storm-levels" in short
    assert main(["--help-all"]) == 0
    full = capsys.readouterr().out
    fields = [f.name for f in dataclasses.fields(TrainConfig) if f.name not in ("dqn", "task")]
    fields += [f"dqn.{f.name}" for f in dataclasses.fields(DQNConfig)]
    fields += [f"task.{f.name}" for f in dataclasses.fields(NavConfig)]
    assert all(f"--{k.replace('_', '-')} " in full for k in fields)


def test_a_study_case_starts_from_its_preset() -> None:
    from rainuav.studies.spec import train_config

    cfg = train_config({"preset": "paper-learner", "dqn.episodes": 10}, 3, "out")
    assert (cfg.dqn.loss, cfg.dqn.lanes, cfg.dqn.episodes, cfg.seed) == ("mse", 1, 10, 3)


@pytest.mark.slow
def test_same_configuration_same_run_bit_for_bit(tmp_path: Path) -> None:
    """A short run of ``--preset paper-learner`` against the same run configured field by field as
    the code set it before (``lr_final`` then equal to ``lr``): the same metrics and weights."""
    import torch
    from rainuav.rl.loop import train
    from rainuav.world import in_world
    from test_nav_tasks import _map

    run = {"eval_starts": 4, "validate_every": 0, "checkpoint_every": 2}
    task = {"task.goal_m": (300.0, 350.0), "task.max_steps": 40}
    by_preset = resolve_config(
        {"preset": "paper-learner", "out": str(tmp_path / "a"), "dqn.episodes": 3, **run, **task}
    )
    by_hand = TrainConfig(
        out=str(tmp_path / "b"), **run, task=NavConfig(goal_m=(300.0, 350.0), max_steps=40),
        dqn=DQNConfig(episodes=3, lr_final=DQNConfig().lr, **PAPER_BEFORE),
    )  # fmt: skip
    runs = []
    for cfg in (by_preset, by_hand):
        m = train(*in_world(cfg, _map()), progress=False)
        runs.append({k: v for k, v in m.items() if "seconds" not in k and "_s" not in k[-2:]})
    assert runs[0] == runs[1]
    weights = [
        torch.load(Path(c.out) / "policy.pt", weights_only=True) for c in (by_preset, by_hand)
    ]
    a, b = (w["online"] for w in weights)
    assert a.keys() == b.keys() and all(torch.equal(a[k], b[k]) for k in a)
    assert np.isclose(runs[0]["episodes"], 3)


def test_earlier_names_are_read_and_a_field_twice_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # Run files written before the task had its own table, and before rain_rate and altitudes
    # carried their units, load as today's (the old checkpoints' configurations too: the same
    # reader).
    old = tmp_path / "old.toml"
    old.write_text(
        'scenario = "uma"\nrain_rate = 5.0\naltitudes = "25:115:15"\nmax_steps = 70\n'
        "goal_x_m = 300.0\ngoal_y_m = 350.0\n[dqn]\nlanes = 2\n"
    )
    cfg = load_config(old)
    assert (cfg.rain_rate_mm_h, cfg.altitudes_m) == (5.0, "25:115:15")
    assert (cfg.task.max_steps, cfg.task.goal_m, cfg.dqn.lanes) == (70, (300.0, 350.0), 2)
    new = tmp_path / "new.toml"
    new.write_text(
        'scenario = "uma"\nrain_rate_mm_h = 5.0\naltitudes_m = "25:115:15"\n'
        "[task]\nmax_steps = 70\ngoal_m = [300.0, 350.0]\n[dqn]\nlanes = 2\n"
    )
    assert load_config(new) == cfg
    # The flags' earlier names are gone: each is refused in one line naming its replacement.
    replaced = [
        (("--rain-rate", "5"), "--rain-rate-mm-h"),
        (("--altitudes", "25:115:15"), "--altitudes-m"),
        (("--max-steps", "70"), "--task.max-steps"),
        (("--lanes", "2"), "--dqn.lanes"),
        (("--goal-x-m", "300"), "--task.goal-m"),
    ]
    for old, new in replaced:
        with pytest.raises(SystemExit) as stop:
            _cli(*old)
        err = capsys.readouterr().err.strip().splitlines()[-1]
        assert stop.value.code == 2 and f"did you mean {new}" in err, err
    # One field under two names is refused, naming it.
    twice = tmp_path / "twice.toml"
    twice.write_text("max_steps = 70\n[task]\nmax_steps = 80\n")
    with pytest.raises(InvalidInputError, match=r"task\.max_steps is given twice"):
        load_config(twice)
    with pytest.raises(InvalidInputError, match="rain_rate_mm_h is given twice"):
        resolve_config({"rain_rate": 5.0, "rain_rate_mm_h": 6.0})


def test_a_destination_off_the_area_is_refused_before_any_map(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    import rainuav.world as world

    def no_map(*_: Any, **__: Any) -> None:
        raise AssertionError("a map was built for a task that cannot fly on it")

    monkeypatch.setattr(world, "build_source", no_map)
    assert main(["--task.goal-m", "99999,1", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "task.goal_m must lie inside the area" in err, err


def test_a_configuration_as_a_dict_is_the_standard_librarys() -> None:
    # to_dict (rainuav._io.plain, shared with the scenario's) against dataclasses.asdict with
    # unset fields dropped, types included, for the defaults and every shipped preset.
    from rainuav.rl.config import to_dict

    def reference(d: dict[str, Any]) -> dict[str, Any]:
        return {
            k: reference(v) if isinstance(v, dict) else v for k, v in d.items() if v is not None
        }

    for preset in ("", "paper", "storms", "storm-levels"):
        cfg = resolve_config({"preset": preset} if preset else {})
        want = reference(dataclasses.asdict(cfg))
        assert to_dict(cfg) == want and repr(to_dict(cfg)) == repr(want), preset
