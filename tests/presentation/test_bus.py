"""`rei watch --bus`: a viewer of a run on a real Zenoh router on loopback (`rei bus`'s
router, with its generated credentials and access rules). A simulation-role session
publishes a recorded run's trace on rei/v1/trace as `rei run --bus` does; the watch shows
the run's own signals and ends with its verdict; one that joins a run under way never passes
it; a viewer refused by the router says so in one line."""

from __future__ import annotations

import json
import os
import shlex
import subprocess
import sys
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from rei.runtime.observation.evaluator.signal_log import read_csv
from tests.conftest import EXAMPLES, REPO
from tests.presentation.conftest import SAFETY_LIMIT, Terminal, rei_watch

pytest.importorskip("zenoh", reason="the bus extra (eclipse-zenoh) is in the test extra")

from rei.runtime.bus import connect  # noqa: E402
from rei.runtime.bus.distributed_run import TracePublisher  # noqa: E402
from rei.runtime.bus.router import Router, start  # noqa: E402
from rei.runtime.bus.schema import TRACE  # noqa: E402
from rei.runtime.trace import read_trace, read_trace_end  # noqa: E402


@pytest.fixture(scope="module")
def router(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Router]:
    with start(tmp_path_factory.mktemp("watch-bus") / "creds") as running:
        yield running


def watch_bus(router: Router, *args: str) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, "-m", "rei.runtime.commands", "watch", "--bus", router.bus.endpoint,
         "--plain", "--exit", *args],
        cwd=REPO, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
        text=True)


def watch_published(router: Router, run: Path, start_at: int = 0
                    ) -> subprocess.CompletedProcess[str]:
    """`rei watch --bus` of a recorded run published as `rei run --bus` publishes it (its
    own ``TracePublisher``: every object's row on every line, the header also answered as
    config/trace); with ``start_at``, the viewer joins when sample ``start_at`` is next."""
    header, samples = read_trace(run / "trace.jsonl")
    end = read_trace_end(run / "trace.jsonl")
    assert end is not None
    with connect(router.bus.endpoint, role="simulation", credentials=router.bus.path) as sim:
        publisher = TracePublisher(sim)
        watch = None
        if start_at == 0:
            watch = watch_bus(router, "--credentials", str(router.bus.path))
            assert sim.await_readers(TRACE, SAFETY_LIMIT), "the viewer never subscribed"
        publisher.start(header)
        for sample in samples:
            if sample.seq == start_at and watch is None:
                watch = watch_bus(router, "--credentials", str(router.bus.path))
                assert sim.await_readers(TRACE, SAFETY_LIMIT), "the viewer never subscribed"
            if watch is not None:
                publisher.feed(sample)
            else:  # published before the viewer joined: nobody hears it
                publisher.encoder.sample(sample)
        publisher.finish(*end)
        assert watch is not None
        # the session stays until the viewer is done: a late one asks it for the header
        out, err = watch.communicate(timeout=SAFETY_LIMIT)
    return subprocess.CompletedProcess(watch.args, watch.returncode, out, err)


@pytest.mark.parametrize("name", ["pass", "fail"])
def test_a_viewer_on_the_bus_shows_the_runs_signals_and_verdict(
        recorded: dict[str, Path], router: Router, name: str) -> None:
    run = recorded[name]
    done = watch_published(router, run)
    out, err = done.stdout, done.stderr
    assert done.returncode == {"pass": 0, "fail": 1}[name], out + err
    assert "missed" not in err, out + err
    shown = [line.split() for line in out.splitlines() if " s  SIG_" in line]
    events = read_csv(run / "events.csv")
    assert [(float(s[0]), s[2], float(s[3]), float(s[5])) for s in shown] == [
        (round(r.time, 2), r.signal, r.utility, r.total_utility) for r in events], out + err
    assert f"verdict: {name.upper()}" in out


def test_a_viewer_that_joins_a_run_under_way_never_passes_it(
        recorded: dict[str, Path], router: Router) -> None:
    """It asks for the header (config/trace, as `rei monitor` does) and watches from the
    sample it joined at; the samples before it are missed, so the run that passed live is
    inconclusive here, never a pass."""
    done = watch_published(router, recorded["pass"], start_at=100)
    assert done.returncode == 1, done.stdout + done.stderr
    assert "rei watch: missed 100 sample(s) [[0, 99]]" in done.stderr
    assert "verdict: INCONCLUSIVE" in done.stdout


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


def test_a_live_distributed_run_watched_full_screen(
        router: Router, terminal: Callable[[str], Terminal], tmp_path: Path) -> None:
    """The real thing: `rei robot` and `rei run --bus` on the router, `rei watch --bus` in a
    terminal (tmux) shows the run as it happens and ends with the run's own verdict."""
    env = {**os.environ, "REI_BUS_CREDENTIALS": str(router.bus.path)}
    endpoint = router.bus.endpoint
    robot = subprocess.Popen(
        [sys.executable, "-m", "rei.runtime.commands", "robot", "--bus", endpoint,
         "--controller", "reference", "--once"], cwd=REPO, env=env,
        stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    try:
        term = terminal(f"REI_BUS_CREDENTIALS={shlex.quote(str(router.bus.path))} "
                        + rei_watch("--bus", endpoint))
        term.wait_for(lambda s: "rei watch: waiting for a run on the bus" in s)
        mission = EXAMPLES / "simple_wall" / "simple_wall.mission"
        done = subprocess.run(
            [sys.executable, "-m", "rei.runtime.commands", "run", str(mission), "-o",
             str(tmp_path / "dist"), "--bus", endpoint, "--wait-for-monitor", "--duration",
             "20"], cwd=REPO, env=env, capture_output=True, text=True,
            timeout=SAFETY_LIMIT, check=False)
        summary = json.loads((tmp_path / "dist" / "summary.json").read_text())
        screen = term.wait_for(lambda s: "the stream ended; q: quit" in s)
        verdict = summary["verdict"].upper()
        assert f"verdict {verdict}   total utility {summary['total_utility']:g}" in screen, \
            done.stdout + done.stderr
        assert "REI watch  to_the_wall in simple_wall" in screen and "replay at" not in screen
        assert "time factor" in screen and "██" in screen
        term.keys("q")
        screen = term.wait_for(lambda s: "EXIT=" in s)
        assert f"EXIT={done.returncode}" in screen
    finally:
        robot.wait(timeout=SAFETY_LIMIT)
        if robot.stderr is not None:
            robot.stderr.close()
