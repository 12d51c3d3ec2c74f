"""An input REI cannot use is refused at the edge; an internal error is reported, never a
traceback on the terminal (issue 13: "never a traceback").

A negative seed used to reach numpy inside the simulation process and print a traceback;
any other exception that escapes the simulation process is now saved beside the outputs
(internal-error.txt) and the run ends as an error with a summary saying so.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from rei.runtime.runs import supervisor
from rei.runtime.runs.supervisor import INTERNAL_ERROR_LOG, RunRequest, child_main
from tests.conftest import EXAMPLES, REPO

SIMPLE_WALL = EXAMPLES / "simple_wall" / "simple_wall.mission"
SAFETY_LIMIT = 600.0
"""Seconds after which a stuck test fails instead of hanging CI (not a performance limit)."""


@pytest.mark.parametrize("seed", ["-1", str(2**64)])
def test_a_seed_numpy_cannot_take_is_refused_before_anything_runs(tmp_path: Path,
                                                                   seed: str) -> None:
    out = tmp_path / "out"
    done = subprocess.run([sys.executable, "-m", "rei.runtime.commands", "run", str(SIMPLE_WALL),
                           "-o", str(out), "--duration", "1", "--seed", seed], cwd=REPO,
                          capture_output=True, text=True, timeout=SAFETY_LIMIT, check=False)
    assert done.returncode == 2, done.stderr
    assert done.stderr.strip().splitlines() == [
        f"rei: error: --seed: expected a whole number from 0 to 2**64-1, found {seed}"]
    assert "Traceback" not in done.stderr and done.stdout == ""
    assert not (out / "summary.json").exists()


def test_an_internal_error_is_saved_and_reported_not_printed_as_a_traceback(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    def broken(request: RunRequest, probe: object) -> tuple[int, dict[str, object]]:
        raise ZeroDivisionError("a bug in REI")

    read, write = os.pipe()
    request = RunRequest(str(SIMPLE_WALL), str(tmp_path))
    try:
        status = child_main([str(write), request.to_json()], broken)  # the child's work raises
    finally:
        os.close(write)
    with os.fdopen(read, encoding="utf-8") as pipe:
        reports = [json.loads(line) for line in pipe]
    assert status == supervisor.EXIT_RUN_ERROR
    assert reports == [{"crash": "ZeroDivisionError: a bug in REI"}]
    err = capsys.readouterr().err
    assert "Traceback" not in err
    assert err.strip() == (f"rei run: internal error: ZeroDivisionError: a bug in REI; please "
                           f"report it with {tmp_path / INTERNAL_ERROR_LOG} and the command line")
    saved = (tmp_path / INTERNAL_ERROR_LOG).read_text(encoding="utf-8")
    assert saved.startswith("Traceback") and "ZeroDivisionError: a bug in REI" in saved
