"""`rei watch --bus`: a viewer of a run on a real Zenoh router on loopback (`rei bus`'s
router, with its generated credentials and access rules). A simulation-role session
publishes a recorded run's trace on rei/v1/trace as `rei run --bus` does; the watch shows
the run's own signals and ends with its verdict, also when it joined while another run was
under way, and a viewer refused by the router says so in one line."""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from rei.runtime.evaluator.signal_log import read_csv
from tests.conftest import REPO
from tests.views.conftest import SAFETY_LIMIT

pytest.importorskip("zenoh", reason="the bus extra (eclipse-zenoh) is in the test extra")

from rei.runtime.bus import connect  # noqa: E402
from rei.runtime.bus.router import Router, start  # noqa: E402
from rei.runtime.bus.schema import TRACE  # noqa: E402


@pytest.fixture(scope="module")
def router(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Router]:
    with start(tmp_path_factory.mktemp("watch-bus") / "creds") as running:
        yield running


def watch_bus(router: Router, *args: str) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, "-m", "rei.runtime.cli", "watch", "--bus", router.bus.endpoint,
         "--plain", "--exit", *args],
        cwd=REPO, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
        text=True)


@pytest.mark.parametrize("name", ["pass", "fail"])
def test_a_viewer_on_the_bus_shows_the_runs_signals_and_verdict(
        recorded: dict[str, Path], router: Router, name: str) -> None:
    run = recorded[name]
    watch = watch_bus(router, "--credentials", str(router.bus.path))
    lines = (run / "trace.jsonl").read_bytes().splitlines()
    with connect(router.bus.endpoint, role="simulation", credentials=router.bus.path) as sim:
        assert sim.await_readers(TRACE, SAFETY_LIMIT), "the viewer never subscribed"
        # the end of a run that was under way when the viewer joined: skipped
        for line in lines[-4:-1]:
            sim.put(TRACE, line)
        for line in lines:
            sim.put(TRACE, line)
        out, err = watch.communicate(timeout=SAFETY_LIMIT)
    assert watch.returncode == {"pass": 0, "fail": 1}[name], err
    shown = [line.split() for line in out.splitlines() if " s  SIG_" in line]
    events = read_csv(run / "events.csv")
    assert [(float(s[0]), s[2], float(s[3]), float(s[5])) for s in shown] == [
        (round(r.time, 2), r.signal, r.utility, r.total_utility) for r in events]
    assert f"verdict: {name.upper()}" in out


def test_a_viewer_with_wrong_credentials_is_refused_in_one_line(
        router: Router, tmp_path: Path) -> None:
    forged = tmp_path / "viewer.json"
    text = (router.bus.path / "viewer.json").read_text()
    forged.write_text(text.replace('"password": "', '"password": "x'))
    forged.chmod(0o600)
    watch = watch_bus(router, "--credentials", str(forged))
    out, err = watch.communicate(timeout=SAFETY_LIMIT)
    assert watch.returncode == 3
    assert err.strip().splitlines()[-1].startswith("rei watch: error: the bus at ")
    assert "refused the viewer role's credentials" in err and "Traceback" not in err
