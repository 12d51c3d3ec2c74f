"""`rei watch`'s bad input: a clear one-line error naming what was expected and what was
found, exit 2 (a taken port or a missing back end: 3); never a traceback."""

from __future__ import annotations

import socket
import sys
from pathlib import Path

import pytest

from rei.runtime.presentation.live.foxglove import INSTALL_HINT, FoxgloveView
from rei.runtime.presentation.live.frames import WatchError
from tests.presentation.conftest import rei


def _refused(done: object, status: int, *needles: str) -> None:
    assert done.returncode == status, done.stdout + done.stderr  # type: ignore[attr-defined]
    err = done.stderr  # type: ignore[attr-defined]
    assert "Traceback" not in err
    for needle in needles:
        assert needle in err, err


def test_a_missing_or_damaged_recording_is_invalid_input(
        recorded: dict[str, Path], tmp_path: Path) -> None:
    _refused(rei("watch", "--replay", str(tmp_path / "nope.jsonl"), "--plain"), 2,
             "nope.jsonl: expected a trace.jsonl or recording.mcap file, found nothing")
    _refused(rei("watch", "--replay", str(tmp_path), "--plain"), 2, "found a folder")
    lines = (recorded["pass"] / "trace.jsonl").read_text().splitlines()
    lines[5] = lines[5].replace('"time":', '"time":"soon","was":', 1)
    damaged = tmp_path / "trace.jsonl"
    damaged.write_text("\n".join(lines) + "\n")
    done = rei("watch", "--replay", str(damaged), "--plain", "--speed", "0")
    _refused(done, 2, f"{damaged}:6")


@pytest.mark.parametrize(("args", "needle"), [
    (("--speed", "nan"), "expected a finite number >= 0, found 'nan'"),
    (("--speed", "-2"), "expected a finite number >= 0, found '-2'"),
    (("--speed", "fast"), "expected a number, found 'fast'"),
    (("--foxglove", "70000"), "expected a port number 0-65535, found '70000'"),
    (("--wait",), "--wait waits for a Foxglove client: give --foxglove PORT too"),
])
def test_bad_options_are_refused(recorded: dict[str, Path], args: tuple[str, ...],
                                 needle: str) -> None:
    _refused(rei("watch", "--replay", str(recorded["pass"] / "trace.jsonl"), *args), 2, needle)


def test_replay_and_bus_are_one_or_the_other(recorded: dict[str, Path]) -> None:
    _refused(rei("watch", "--plain"), 2, "expected a stream to watch: --replay TRACE or "
             "--bus URL (one of them), found neither")
    _refused(rei("watch", "--replay", str(recorded["pass"] / "trace.jsonl"), "--bus",
                 "tcp/127.0.0.1:1"), 2, "found both")


def test_a_taken_port_is_a_run_error_naming_it(recorded: dict[str, Path]) -> None:
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        done = rei("watch", "--replay", str(recorded["pass"] / "trace.jsonl"), "--plain",
                   "--foxglove", str(port))
    _refused(done, 3, f"cannot start the Foxglove server on 127.0.0.1:{port}")


def test_without_foxglove_sdk_the_error_says_how_to_install_it(
        monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "foxglove", None)  # as if not installed
    with pytest.raises(WatchError) as refused:
        FoxgloveView(0)
    assert str(refused.value) == INSTALL_HINT
    assert "pip install 'rei-testbed[watch]'" in INSTALL_HINT
