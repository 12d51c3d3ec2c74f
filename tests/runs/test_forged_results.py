"""The robot under test cannot turn its own run into a pass (issue 13, point 2).

`rei run` takes neither the simulation process's report nor the summary.json in the output
folder on trust: the report's status must be one `rei run` gives at that point, and the
summary must be the very one the run wrote (its digest travels with the report). The
controllers (tests/runs/forgers.py) drive into the wall of examples/simple_wall, cut
short by --duration: the honest verdict is not a pass (exit 1), a caught forgery is a run
error (exit 3); exit 0 would be a false PASS.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

from tests.conftest import EXAMPLES, REPO

SIMPLE_WALL = EXAMPLES / "simple_wall" / "simple_wall.mission"
SAFETY_LIMIT = 600.0
"""Seconds after which a stuck test fails instead of hanging CI (not a performance limit)."""


def rei_run(out: str | Path, controller: str, cwd: Path = REPO,
            env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    environment = {**os.environ, "PYTHONPATH": str(REPO), **(env or {})}
    return subprocess.run(
        [sys.executable, "-m", "rei.runtime.commands", "run", str(SIMPLE_WALL), "-o", str(out),
         "--duration", "4", "--controller", f"tests.runs.forgers:{controller}"],
        cwd=cwd, env=environment, capture_output=True, text=True, timeout=SAFETY_LIMIT,
        check=False)


def summary(out: Path) -> dict[str, object]:
    data = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    assert isinstance(data, dict)
    return data


def test_a_forged_exit_report_over_the_pipe_is_a_run_error(tmp_path: Path) -> None:
    done = rei_run(tmp_path, "ForgesPipeAndExits")
    assert done.returncode == 3, done.stdout + done.stderr
    assert summary(tmp_path)["verdict"] == "error"
    assert "verdict: ERROR" in done.stdout


def test_a_summary_rewritten_after_the_run_is_a_run_error(tmp_path: Path) -> None:
    done = rei_run(tmp_path, "RewritesSummaryAtExit", env={"REI_FORGE_OUT": str(tmp_path)})
    assert done.returncode in (1, 3), done.stdout + done.stderr  # never the forged pass
    found = summary(tmp_path)
    assert found["verdict"] != "pass"
    if done.returncode == 3:
        assert "summary.json is not the one the run wrote" in str(found["reason"])


def test_the_error_log_line_never_follows_a_link_in_the_output_folder(tmp_path: Path) -> None:
    victim = tmp_path / "victim.txt"
    victim.write_text("precious\n", encoding="utf-8")
    out = tmp_path / "out"
    out.mkdir()
    (out / "run.log").symlink_to(victim)
    done = rei_run(out, "KillsTheSimulationWhenMade")
    assert done.returncode == 3, done.stdout + done.stderr
    assert victim.read_text(encoding="utf-8") == "precious\n"
    log = out / "run.log"
    assert not log.is_symlink() and "error:" in log.read_text(encoding="utf-8")


def test_a_controller_changing_folder_does_not_move_the_outputs(tmp_path: Path) -> None:
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    done = rei_run("relative-out", "ChangesFolder", cwd=tmp_path,
                   env={"REI_FORGE_ELSEWHERE": str(elsewhere)})
    assert done.returncode == 1, done.stdout + done.stderr  # cut short: inconclusive
    out = tmp_path / "relative-out"
    assert summary(out)["verdict"] == "inconclusive"
    assert (out / "trace.jsonl").is_file() and (out / "events.csv").is_file()
    assert list(elsewhere.iterdir()) == []
