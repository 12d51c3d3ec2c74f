"""`rei search` refuses bad input with exit status 2 and one line naming the option, what was
expected and what was found, before any folder or run exists; and it never writes into a
folder that holds something else (another search, or files that are not a search)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from rei.lang.cli_support import EXIT_BAD_INPUT
from rei.runtime.campaigns.search import SearchConfig
from rei.runtime.commands.cli import main

ONE_ROOM = ["--shape", "rect", "--size", "5x3", "--objects", "0", "--mix", "furniture",
            "--humans", "0", "--goals", "2", "--spacing", "2", "--cycles", "1",
            "--behaviour", "yielding", "--heading", "no", "--max-speed", "none",
            "--layout", "1"]
"""Every factor of the small preset at one level and the layout fixed: nothing left to search
until a test adds a range."""


def _refused(capsys: pytest.CaptureFixture[str], out: Path, *argv: str) -> str:
    code = main(["search", "-o", str(out), *argv])
    err = capsys.readouterr().err.strip()
    assert code == EXIT_BAD_INPUT, err
    assert "Traceback" not in err and len(err.splitlines()) == 1, err
    assert not out.exists(), "a refused search must not create its folder"
    return err


@pytest.mark.parametrize(("argv", "expected"), [
    (["--max-speed", "nan:0.3"], "--max-speed: expected a finite number in (0, 10], found 'nan'"),
    (["--max-speed", "0.05:inf"], "--max-speed: expected a finite number in (0, 10], found 'inf'"),
    (["--speed", "1.3:0.6"], "--speed: expected a range LOW:HIGH with LOW below HIGH"),
    (["--size", "5x3:6x4"], "--size: expected levels without ':'"),
    (["--max-speed", "0.05:0.3", "--budget", "0"],
     "--budget: expected a number of simulations of at least 1, found 0"),
    (["--max-speed", "0.05:0.3", "--batch", "0"], "--batch: expected at least 1, found 0"),
    (["--max-speed", "0.05:0.3", "--requirement", "SPEED_LIMT"],
     "--requirement: expected a requirement with a margin"),
    (["--max-speed", "0.05:0.3", "--measures", "tortuosity"],
     "--measures: expected two descriptor names"),
    (["--max-speed", "0.05:0.3", "--measures", "tortuosity,colour"],
     "--measures: expected two of"),
    ([], "nothing to search"),
    (["--max-speed", "0.05:0.3", "--strategy", "cmaes"], "--strategy cmaes: expected at least two"),
    (["--max-speed", "0.05:0.3", "--vepl", "missing.vepl"], "--vepl: file 'missing.vepl'"),
    (["--max-speed", "0.05:0.3", "--engine", "dask"], "--engine dask: expected --scheduler"),
    (["--max-speed", "0.05:0.3", "--scheduler", "tcp://127.0.0.1:1"],
     "--scheduler is only used with --engine dask"),
    # Every level given is checked up front, as `rei-gen rooms` does, not found later as a
    # candidate 'not built' after part of the budget ran.
    (["--max-speed", "0.05:0.3", "--humans", "0,abc"],
     "--humans: expected a whole number from 0 to 20, found 'abc'"),
    (["--max-speed", "0.05:0.3", "--mix", "furniture,sofa+lamp"], "--mix: expected a named mix"),
    (["--max-speed", "0.05:0.3", "--behaviour", "yielding,rude"], "--behaviour: expected one of"),
    (["--max-speed", "0.05:0.3", "--size", "5x3,5x"], "--size: expected a whole number"),
    (["--max-speed", "0.0001:0.0004"], "--max-speed: expected a range LOW:HIGH with LOW below "
                                       "HIGH once both are rounded inwards to 3 decimals"),
    (["--max-speed", "0.05:0.3", "--layout", "100000000000000000000000"],
     "--layout: expected a construction seed from 0 to 2147483647, found "
     "100000000000000000000000"),
    (["--max-speed", "0.05:0.3", "--layout", "-1"],
     "--layout: expected a construction seed from 0 to 2147483647, found -1"),
    # The scenario's dimensions (generators/rooms/scenario.py): each names its own flag.
    (["--phase", "0:700"], "--phase: expected a finite number in [0, 600], found '700'"),
    (["--phase=-1:5"], "--phase: expected a finite number in [0, 600], found '-1'"),
    (["--phase", "nan:5"], "--phase: expected a finite number in [0, 600], found 'nan'"),
    (["--phase", "5"], "--phase: expected a range LOW:HIGH"),
    (["--stress-shift=-100:0"],
     "--stress-shift: expected a finite number in [-60, 60], found '-100'"),
    (["--stress-shift", "3:1"], "--stress-shift: expected a range LOW:HIGH with LOW below"),
    (["--object-shift", "0:0.8"],
     "--object-shift: expected a finite number in [-0.5, 0.5], found '0.8'"),
    (["--goal-shift=-inf:0.2"],
     "--goal-shift: expected a finite number in [-0.5, 0.5], found '-inf'"),
    (["--path-shift", "0.3:0.1"], "--path-shift: expected a range LOW:HIGH with LOW below"),
    (["--path-shift", "0.2"], "--path-shift: expected a range LOW:HIGH"),
    (["--object-shift", "0.0001:0.0009"],
     "--object-shift: expected a range LOW:HIGH with LOW below HIGH once both are rounded"),
    (["--fault-range", "laser_noise.sigma=0:0.1"],
     "--fault-range: expected a finite number in (0, 10], found '0'"),
    (["--fault-range", "laser_dropout.share=0.1:inf"],
     "--fault-range: expected a finite number in (0, 1], found 'inf'"),
    (["--fault-range", "laser_nosie.sigma=0.1:0.2"],
     "--fault-range: expected a fault kind (laser_poisson,"),
    (["--fault-range", "laser_noise.sigm=0.1:0.2"],
     "--fault-range: expected a parameter of laser_noise (sigma), found 'sigm'"),
    (["--fault-range", "laser_noise=0.1:0.2"], "--fault-range: expected KIND.PARAM=LOW:HIGH"),
    (["--fault-range", "laser_noise.sigma:0.1:0.2"], "--fault-range: expected KIND.PARAM="),
    (["--fault-range", "laser_poisson.rate=1:20"],
     "--fault-range: expected a range for every required parameter of laser_poisson (also "
     "gain), found only rate"),
    (["--fault-range", "cmd_delay.seconds=0.1:0.2", "--fault-range",
      "cmd_delay.seconds=0.3:0.4"], "--fault-range: expected each scenario parameter once"),
])
def test_bad_options_exit_2_with_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                          argv: list[str], expected: str) -> None:
    err = _refused(capsys, tmp_path / "out", *ONE_ROOM, *argv)
    assert expected in err


def test_a_misspelt_requirement_gets_a_suggestion(tmp_path: Path,
                                                  capsys: pytest.CaptureFixture[str]) -> None:
    err = _refused(capsys, tmp_path / "out", *ONE_ROOM, "--max-speed", "0.05:0.3",
                   "--requirement", "SPEED_LIMT")
    assert "SPEED_LIMIT" in err.split("found")[-1]


def test_unknown_strategy_and_factor_are_refused_by_the_parser(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    for argv in (["--strategy", "annealing"], ["--colour", "red"]):
        with pytest.raises(SystemExit) as stop:
            main(["search", "-o", str(tmp_path / "out"), *argv])
        assert stop.value.code == EXIT_BAD_INPUT
        err = capsys.readouterr().err
        assert ("invalid choice: 'annealing'" in err) or ("unrecognized arguments: --colour"
                                                           in err)
    assert not (tmp_path / "out").exists()


def test_a_folder_of_another_search_or_of_other_files_is_refused(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    other = tmp_path / "other"
    other.mkdir()
    (other / "search.json").write_text(json.dumps(SearchConfig(seed=99).to_json()))
    code = main(["search", "-o", str(other), *ONE_ROOM, "--max-speed", "0.05:0.3"])
    err = capsys.readouterr().err
    assert code == EXIT_BAD_INPUT and "holds a different search" in err
    assert sorted(p.name for p in other.iterdir()) == ["search.json"]

    files = tmp_path / "files"
    files.mkdir()
    (files / "notes.txt").write_text("mine")
    code = main(["search", "-o", str(files), *ONE_ROOM, "--max-speed", "0.05:0.3"])
    err = capsys.readouterr().err
    assert code == EXIT_BAD_INPUT and "not a REI search folder" in err
    assert sorted(p.name for p in files.iterdir()) == ["notes.txt"]


def test_rei_campaign_refuses_the_same_engine_options(tmp_path: Path,
                                                      capsys: pytest.CaptureFixture[str]
                                                      ) -> None:
    """`rei campaign` and `rei search` share the engine options and their checks."""
    examples = Path(__file__).resolve().parents[2] / "examples"
    for extra, expected in ((["--engine", "dask"], "--engine dask: expected --scheduler"),
                            (["--scheduler", "tcp://127.0.0.1:1"], "--scheduler is only")):
        code = main(["campaign", str(examples), "-o", str(tmp_path / "out"), *extra])
        assert code == EXIT_BAD_INPUT and expected in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_an_impossible_combination_of_good_levels_is_not_refused_up_front() -> None:
    # An L shape needs 4x4 tiles: 3x3 with L is a combination the generator refuses per
    # candidate ('not built'), while each level alone is good, so the search may start.
    from rei.runtime.campaigns.search.driver import check_config  # noqa: PLC0415

    check_config(SearchConfig(levels=(("shape", "rect,L"), ("size", "3x3,5x4"))))
