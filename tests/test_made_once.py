"""tests/conftest.py's made_once: a folder the suite's workers share is made exactly once per
session, by whichever worker asks first, even when several ask at the same moment; a failed
making is not taken for a made folder."""

from __future__ import annotations

import multiprocessing
import os
import time
from pathlib import Path

import pytest

from tests.conftest import made_once


class Base:
    """The one method of pytest's TempPathFactory that made_once uses."""

    def __init__(self, path: Path) -> None:
        self.path = path

    def getbasetemp(self) -> Path:
        return self.path


def _ask(session: str, worker: str, started: multiprocessing.synchronize.Barrier) -> None:
    """One worker's request, as a separate process (xdist workers are processes)."""
    os.environ["PYTEST_XDIST_WORKER"] = worker
    base = Path(session) / f"popen-{worker}"
    base.mkdir()

    def make(folder: Path) -> None:
        with (Path(session) / "makings").open("a") as log:
            log.write(f"{worker}\n")
        time.sleep(0.5)  # a making that takes a while: the others ask meanwhile
        (folder / "data").write_text("made")

    started.wait()  # all ask together
    folder = made_once(Base(base), "runs", make)  # type: ignore[arg-type]
    (Path(session) / f"seen-{worker}").write_text((folder / "data").read_text() + str(folder))


def test_workers_asking_together_make_the_folder_once(tmp_path: Path) -> None:
    context = multiprocessing.get_context("spawn")
    workers = [f"gw{i}" for i in range(4)]
    started = context.Barrier(len(workers))
    processes = [context.Process(target=_ask, args=(str(tmp_path), w, started))
                 for w in workers]
    for process in processes:
        process.start()
    for process in processes:
        process.join()
    assert [p.exitcode for p in processes] == [0] * len(workers)
    assert len((tmp_path / "makings").read_text().split()) == 1
    seen = {(tmp_path / f"seen-{w}").read_text() for w in workers}
    assert seen == {"made" + str(tmp_path / "made-once-runs")}


def test_without_workers_the_folder_is_under_the_sessions_own_base(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("PYTEST_XDIST_WORKER", raising=False)
    folder = made_once(Base(tmp_path), "x", lambda f: (f / "a").write_text("1"))  # type: ignore[arg-type]
    assert folder == tmp_path / "made-once-x" and (folder / "a").read_text() == "1"
    again = made_once(Base(tmp_path), "x", lambda f: pytest.fail("made twice"))  # type: ignore[arg-type]
    assert again == folder


def test_a_failed_making_is_made_again_by_the_next_request(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("PYTEST_XDIST_WORKER", raising=False)

    def broken(folder: Path) -> None:
        (folder / "half").write_text("half")
        raise AssertionError("the run failed")

    with pytest.raises(AssertionError, match="the run failed"):
        made_once(Base(tmp_path), "x", broken)  # type: ignore[arg-type]
    folder = made_once(Base(tmp_path), "x", lambda f: (f / "a").write_text("1"))  # type: ignore[arg-type]
    assert sorted(p.name for p in folder.iterdir()) == [".made", "a"]  # nothing half-made left
