"""`rei run --config run.json`: the launch target's run.json is the same run as the command
line; explicit flags win over the file; a bad file is a located error (exit 2)."""

from __future__ import annotations

import argparse
import json
import re
from pathlib import Path

import pytest

from rei.generators.pipeline import generate
from rei.lang.cli_support import build_parser
from rei.lang.vepl_parameters import parameter_values
from rei.runtime.commands.cli import DESCRIPTION, main
from rei.runtime.errors import RunError
from rei.runtime.runs.config import apply_run_config
from tests.conftest import EXAMPLES

NAVIGATION = EXAMPLES / "navigation"


def parsed(*argv: str) -> argparse.Namespace:
    args = build_parser("rei", DESCRIPTION, "rei.runtime.commands").parse_args(["run", *argv])
    return apply_run_config(args)


def write_config(tmp_path: Path, **fields: object) -> Path:
    path = tmp_path / "cfg" / "run.json"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps({"format": "rei-run/1", "mission": "m/x.mission", **fields}))
    return path


@pytest.mark.slow
def test_run_json_reproduces_the_command_lines_run(tmp_path: Path) -> None:
    generate(NAVIGATION / "navigation.mission", "launch", tmp_path / "launch",
             {"monitor": "human_safety.vepl", "seed": "3"})
    config = tmp_path / "launch" / "run.json"
    # --duration given explicitly overrides the file's null (the mission's long time limit).
    assert main(["run", "--config", str(config), "-o", str(tmp_path / "a"), "--duration", "4",
                 "--quiet"]) == main([
        "run", str(NAVIGATION / "navigation.mission"), "--vepl",
        str(NAVIGATION / "human_safety.vepl"), "--seed", "3", "-o", str(tmp_path / "b"),
        "--duration", "4", "--quiet"])
    for name in ("summary.json", "trace.jsonl", "events.csv", "run.log"):
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes(), name


def test_fields_fill_what_the_command_line_leaves_out(tmp_path: Path) -> None:
    config = write_config(tmp_path, seed=5, controller="teleop", duration=12, physics_rate=200,
                          odom_drift=0.01, laser_noise=0, variation=False, monitor=False,
                          vepl="specs/s.vepl")
    args = parsed("--config", str(config))
    assert args.mission == config.parent / "m" / "x.mission"
    assert args.vepl == config.parent / "specs" / "s.vepl"
    assert (args.seed, args.controller, args.duration, args.physics_rate) == (
        5, "teleop", 12.0, 200.0)
    assert (args.odom_drift, args.laser_noise, args.no_variation, args.no_monitor) == (
        0.01, 0.0, True, True)
    assert args.output == config.parent / "run"


def test_explicit_flags_override_the_file_even_with_default_values(tmp_path: Path) -> None:
    config = write_config(tmp_path, seed=5, controller="teleop", variation=False)
    args = parsed("--config", str(config), "--seed", "0", "--controller", "reference",
                  "-o", str(tmp_path / "out"), str(tmp_path / "other.mission"))
    assert (args.seed, args.controller, args.no_variation) == (0, "reference", True)
    assert args.mission == tmp_path / "other.mission" and args.output == tmp_path / "out"


def test_parameters_are_added_to_and_overridden_name_by_name(tmp_path: Path) -> None:
    config = write_config(tmp_path, parameters={"react_zone": 0.7, "slow_zone": 0.4})
    assert parsed("--config", str(config)).param == [("react_zone", 0.7), ("slow_zone", 0.4)]
    # --param for the same name wins (given last); other names are added
    args = parsed("--config", str(config), "--param", "slow_zone=0.3", "--param", "moving=0.1")
    assert parameter_values(args.param) == (("moving", 0.1), ("react_zone", 0.7),
                                            ("slow_zone", 0.3))
    assert parsed("a.mission", "-o", "out").param == []


def test_without_a_config_the_defaults_are_rei_runs() -> None:
    args = parsed("a.mission", "-o", "out")
    assert (args.seed, args.controller, args.duration, args.physics_rate, args.vepl) == (
        0, "reference", None, 100.0, None)
    with pytest.raises(RunError, match="expected a MISSION file or --config"):
        parsed("-o", "out")
    with pytest.raises(RunError, match=r"expected an output folder \(-o DIR\)"):
        parsed("a.mission")


@pytest.mark.parametrize("fields,message", [
    ({"sed": 1}, "field 'sed': expected one of format, mission.*did you mean 'seed'"),
    ({"seed": -1}, "field 'seed': expected a whole number >= 0, found -1"),
    ({"seed": True}, "field 'seed': expected a whole number >= 0, found true"),
    ({"duration": 0}, "field 'duration': expected null or a finite number of seconds > 0"),
    ({"laser_noise": 2}, "field 'laser_noise': expected null or metres from 0 to 1, found 2"),
    ({"variation": "yes"}, "field 'variation': expected true or false, found 'yes'"),
    ({"mission": "x.room"}, "field 'mission': expected a path to a .mission file"),
    ({"controller": ""}, "field 'controller': expected a controller name"),
    ({"format": "rei-run/2"}, "field 'format': expected 'rei-run/1', found 'rei-run/2'"),
    ({"parameters": [0.7]}, "field 'parameters': expected an object of parameter names and "
                            "finite numbers"),
    ({"parameters": {"react_zone": "0.7"}}, "field 'parameters.react_zone': expected a finite "
                                            "number, found '0.7'"),
    ({"parameters": {"react_zone": True}}, "field 'parameters.react_zone': expected a finite "
                                           "number, found true"),
    ({"parameters": {"react zone": 1}}, "field 'parameters': expected parameter names"),
    ({"parameters": {"react_zone": 1e10}}, "field 'parameters': react_zone: expected a number "
                                           ">= -1e.09 and <= 1e.09"),
])
def test_bad_fields_name_the_file_the_field_and_what_was_found(
    tmp_path: Path, fields: dict[str, object], message: str,
) -> None:
    config = write_config(tmp_path, **fields)
    with pytest.raises(RunError, match=message) as caught:
        parsed("--config", str(config))
    assert str(caught.value).startswith(f"{config}: ")


@pytest.mark.parametrize("text,message", [
    ('{"format": "rei-run/1",', r"run.json:1:24: expected JSON"),
    ('{"format": "rei-run/1", "mission": "a.mission", "duration": NaN}',
     "expected finite numbers, found NaN"),
    ("[1, 2]", "expected a JSON object of run fields, found list"),
    ('{"format": "rei-run/1"}', "field 'mission': expected a path to a .mission file, found "
                                "nothing"),
    # found by an attacker: a repeated field (JSON keeps the last) and deep nesting
    ('{"format": "rei-run/1", "seed": 0, "seed": 5}', "field 'seed': expected once, found 2 "
                                                      "times"),
    ("[" * 100_000 + "]" * 100_000, "found JSON nested too deep to read"),
    ('{"format": "rei-run/1", "mission": "a.mission", "parameters": {"react_zone": 1e999}}',
     "field 'parameters': react_zone: expected a finite number, found 'inf'"),
])
def test_broken_files_are_located_errors(tmp_path: Path, text: str, message: str) -> None:
    config = tmp_path / "run.json"
    config.write_text(text)
    with pytest.raises(RunError, match=message):
        parsed("--config", str(config))


def test_bad_config_exits_2_with_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]
                                          ) -> None:
    assert main(["run", "--config", str(tmp_path / "missing.json")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"rei: error: {tmp_path / 'missing.json'}: --config: expected a run.json "
                   f"file, found none"]


@pytest.mark.parametrize("kind", ["fifo", "zero"])
def test_only_a_small_regular_file_is_read_as_a_config(tmp_path: Path, kind: str) -> None:
    # /dev/zero grew `rei run --config` to 4.6 GB; a FIFO blocked it for ever
    import os

    config = Path("/dev/zero")
    if kind == "fifo":
        config = tmp_path / "run.json"
        os.mkfifo(config)
    found = "a FIFO (named pipe)" if kind == "fifo" else "a character device"
    with pytest.raises(RunError, match=re.escape(f"expected a regular file, found {found}")):
        parsed("--config", str(config))
