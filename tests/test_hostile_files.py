"""Every command reads its input files as the checker does: regular files only, bounded
(issue 13, point 4). A FIFO used to block `rei campaign` and `rei-gen show` for ever, and
/dev/zero grew `rei replay` to gigabytes; each is now one located line and exit 2."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from tests.conftest import REPO

SAFETY_LIMIT = 300.0
"""Seconds after which a stuck test fails instead of hanging CI (not a performance limit)."""


def command(module: str, *args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", module, *args], cwd=REPO, capture_output=True,
                          text=True, timeout=SAFETY_LIMIT, check=False)


@pytest.mark.parametrize(("module", "argv", "said"), [
    ("rei.runtime.commands.cli", ["campaign", "{input}", "-o", "{out}"],
     "rei: error: {input}: cannot read the suite index: expected a regular file, found {kind}"),
    ("rei.lang.cli", ["show", "{input}", "-o", "{out}.png"],
     "rei-gen: error: cannot read the index '{input}': expected a regular file, found {kind}"),
    ("rei.runtime.commands.cli", ["replay", "{input}", "-o", "{out}"],
     "rei: error: cannot read the trace '{input}': expected a regular file, found {kind}"),
    ("rei.runtime.commands.cli", ["run", "--config", "{input}", "-o", "{out}"],
     "rei: error: {input}: cannot read the run configuration: expected a regular file, "
     "found {kind}"),
])
@pytest.mark.parametrize("kind", ["fifo", "device"])
def test_a_fifo_or_a_device_is_refused_unread(tmp_path: Path, module: str, argv: list[str],
                                              said: str, kind: str) -> None:
    if kind == "fifo":
        target = tmp_path / "index.csv"
        os.mkfifo(target)
        shown = "a FIFO (named pipe)"
    else:
        target = tmp_path / "index.csv"
        target.symlink_to("/dev/zero")
        shown = "a character device"
    fill = {"input": str(target), "out": str(tmp_path / "out"), "kind": shown}
    done = command(module, *(a.format(**fill) for a in argv))
    assert done.returncode == 2, done.stderr
    assert done.stderr.strip().splitlines() == [said.format(**fill)]


def test_control_characters_from_the_input_are_shown_not_interpreted(tmp_path: Path) -> None:
    # An ESC sequence in a controller name reached the terminal raw (it can recolour or
    # clear it, or hide a line of a CI log).
    done = command("rei.runtime.commands.cli", "run", "examples/simple_wall/simple_wall.mission",
                   "-o", str(tmp_path / "out"), "--controller", "\x1b[2Jevil:X")
    assert done.returncode == 2
    assert "\x1b" not in done.stderr and "\\x1b[2Jevil" in done.stderr


def test_a_recordings_texts_are_shown_not_interpreted(tmp_path: Path) -> None:
    from rei.runtime.runs.session import run_into

    run = tmp_path / "run"
    run_into(REPO / "examples/simple_wall/simple_wall.mission", run, controller="teleop",
             duration=2.0)
    lines = (run / "trace.jsonl").read_text(encoding="utf-8").splitlines()
    lines[-1] = lines[-1].replace('"reason":"', '"reason":"\\u001b[31m', 1)
    assert "\\u001b[31m" in lines[-1]
    trace = tmp_path / "trace.jsonl"
    trace.write_text("\n".join(lines) + "\n", encoding="utf-8")
    done = command("rei.runtime.commands.cli", "replay", str(trace), "-o", str(tmp_path / "replay"))
    assert done.returncode in (0, 1), done.stderr
    assert "\x1b" not in done.stdout and "\\x1b[31m" in done.stdout
