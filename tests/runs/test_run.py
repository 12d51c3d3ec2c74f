"""`rei run` end to end: outputs, determinism across processes, watchdog and error outcomes."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from rei.runtime.commands.cli import main
from rei.runtime.messages.sink import SampleList
from rei.runtime.runs.session import run_into
from rei.runtime.trace import read_trace, read_trace_end
from tests.conftest import EXAMPLES, REPO

NAVIGATION = EXAMPLES / "navigation" / "navigation.mission"
SIMPLE_WALL = EXAMPLES / "simple_wall" / "simple_wall.mission"


def test_a_short_run_writes_trace_summary_and_log(tmp_path: Path) -> None:
    status = main(["run", str(NAVIGATION), "-o", str(tmp_path), "--duration", "5", "--quiet"])
    assert status == 1  # the time ran out before the mission ended
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["outcome"] == "timeout" and summary["duration"] == 5.0
    # The default specification monitors the run: the mission's own signals are scored, and
    # the requirements that wait for the mission's end cannot pass on a run that timed out.
    counts = summary["signal_counts"]
    assert counts["SIG_MISSION_BEGIN"] == 1 and counts["SIG_MISSION_TASK_FAIL"] == 1
    verdicts = {v["requirement"]: v["status"] for v in summary["verdicts"]}
    assert verdicts["MISSION_SIMPLE"] != "pass" and verdicts["MISSION_SEQUENCE"] != "pass"
    assert (tmp_path / "events.csv").read_text().startswith("time,signal,utility,total_utility")
    header, samples = read_trace(tmp_path / "trace.jsonl")
    assert header.rate == 10.0 and header.mission == "to_the_elevator"
    roles = [o.role for o in header.objects]
    assert roles.count("wall") == 32 and "human" in roles
    rows = list(samples)
    assert [s.seq for s in rows] == list(range(len(rows)))
    assert rows[0].time == 0.0 and rows[-1].time == 5.0
    assert all(s.poses.shape == (len(header.objects), 3) for s in rows)
    kinds = [e.kind for s in rows for e in s.events]
    assert kinds == ["begin", "task_start", "task_success", "task_start", "task_fail", "end"]
    # The human walks; the walls stay.
    walker = roles.index("human")
    assert not np.array_equal(rows[0].poses[walker], rows[-1].poses[walker])
    assert np.array_equal(rows[0].poses[0], rows[-1].poses[0])
    assert rows[-1].belief.laser_min < 3.5
    assert read_trace_end(tmp_path / "trace.jsonl") == (5.0, "timeout", summary["reason"])
    log = (tmp_path / "run.log").read_text()
    assert "task_start elevator" in log and "outcome timeout" in log
    assert (tmp_path / "world" / "world.json").is_file()
    assert (tmp_path / "world" / "monitor.json").is_file()


def _run_fresh(out: Path, hashseed: str) -> None:
    env = dict(os.environ, PYTHONHASHSEED=hashseed)
    subprocess.run([sys.executable, "-m", "rei.runtime.commands", "run", str(NAVIGATION), "-o",
                    str(out), "--duration", "25", "--seed", "4", "--odom-drift", "0.01",
                    "--quiet"], cwd=REPO, env=env, check=False, capture_output=True)


def _tree(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*"))
            if p.is_file()}


@pytest.mark.slow
def test_same_inputs_and_seed_give_identical_bytes_in_fresh_processes(tmp_path: Path) -> None:
    _run_fresh(tmp_path / "a", "1")
    _run_fresh(tmp_path / "b", "2")
    a, b = _tree(tmp_path / "a"), _tree(tmp_path / "b")
    assert set(a) >= {"trace.jsonl", "summary.json", "run.log", "world/world.json"}
    assert a == b


def test_another_seed_changes_the_drifting_odometry(tmp_path: Path) -> None:
    for seed in ("1", "2"):
        main(["run", str(NAVIGATION), "-o", str(tmp_path / seed), "--duration", "3",
              "--seed", seed, "--odom-drift", "0.05", "--quiet"])
    one = [s.belief.odom for s in read_trace(tmp_path / "1" / "trace.jsonl")[1]]
    two = [s.belief.odom for s in read_trace(tmp_path / "2" / "trace.jsonl")[1]]
    assert one != two


@pytest.mark.parametrize(("name", "reason"), [
    ("Hanging", "did not return within the watchdog's 0.5 s"),
    ("Raising", "step() raised ValueError: the planner lost its map"),
    ("NonFinite", "non-finite command"),
])
def test_a_broken_controller_ends_the_run_with_an_error(name: str, reason: str,
                                                        tmp_path: Path) -> None:
    summary, _ = run_into(NAVIGATION, tmp_path, f"tests.robot.faulty:{name}", duration=10.0,
                          watchdog=0.5)
    assert summary.outcome == "error" and reason in summary.reason
    saved = json.loads((tmp_path / "summary.json").read_text())
    assert saved["outcome"] == "error" and reason in saved["reason"]
    end = read_trace_end(tmp_path / "trace.jsonl")
    assert end is not None and end[1] == "error"
    # The controller failed at its 20th step (t = 1.9 s); the trace ends there, consistently.
    rows = list(read_trace(tmp_path / "trace.jsonl")[1])
    assert rows[-1].time == pytest.approx(1.9) and rows[-1].events[-1].kind == "end"


def test_the_cli_reports_a_run_error_with_exit_status_3(tmp_path: Path) -> None:
    status = main(["run", str(NAVIGATION), "-o", str(tmp_path), "--controller",
                   "tests.robot.faulty:Raising", "--duration", "5", "--quiet"])
    assert status == 3


def test_a_controller_raising_keyboardinterrupt_is_a_run_error_not_a_ctrl_c(
        tmp_path: Path) -> None:
    """Its own KeyboardInterrupt is the controller's fault (Ctrl-C reaches the simulation,
    never the controller's process); the outputs end consistently, with the error."""
    status = main(["run", str(NAVIGATION), "-o", str(tmp_path), "--controller",
                   "tests.robot.faulty:Interrupting", "--duration", "10", "--quiet"])
    assert status == 3
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["outcome"] == "error" and summary["measurements"]["incomplete"] is False
    assert "step() raised KeyboardInterrupt" in summary["reason"]
    header, rows = read_trace(tmp_path / "trace.jsonl")
    assert [e.kind for s in rows for e in s.events][-1] == "end"


@pytest.mark.slow
def test_ctrl_c_leaves_consistent_outputs_marked_incomplete(tmp_path: Path) -> None:
    proc = subprocess.Popen([sys.executable, "-m", "rei.runtime.commands", "run", str(NAVIGATION),
                             "-o", str(tmp_path), "--controller", "tests.robot.faulty:Slow",
                             "--quiet"], cwd=REPO, stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)
    partial = tmp_path / "trace.jsonl.partial"
    # Interrupt once the run is under way (the partial trace has a few samples).
    while proc.poll() is None and (not partial.exists() or partial.stat().st_size < 20000):
        time.sleep(0.05)
    proc.send_signal(signal.SIGINT)
    assert proc.wait() == 130
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["outcome"] == "interrupted" and summary["measurements"]["incomplete"]
    header, rows = read_trace(tmp_path / "trace.jsonl")
    samples = list(rows)
    assert [s.seq for s in samples] == list(range(len(samples)))
    assert samples[-1].events[-1].kind == "end"
    assert read_trace_end(tmp_path / "trace.jsonl")[1] == "interrupted"  # type: ignore[index]


def test_tasks_fail_on_timeout_and_on_false_success(tmp_path: Path) -> None:
    summary, _ = run_into(NAVIGATION, tmp_path / "idle", "tests.robot.faulty:Idle",
                          duration=31.0)
    first = summary.measurements["tasks"][0]
    assert not first["succeeded"] and first["reason"] == "timeout after 30 s"
    # long enough for the settle period after its last (false) success: the run completes
    summary, _ = run_into(NAVIGATION, tmp_path / "liar", "tests.robot.faulty:ClaimsSuccess",
                          duration=5.0)
    tasks = summary.measurements["tasks"]
    assert tasks[0]["succeeded"]  # it starts on the first goal
    assert not tasks[1]["succeeded"] and tasks[1]["reason"].startswith("outside tolerance")
    assert summary.outcome == "failed"


def test_bad_arguments_are_input_errors(tmp_path: Path) -> None:
    assert main(["run", str(NAVIGATION), "-o", str(tmp_path), "--controller", "nope",
                 "--quiet"]) == 2
    assert main(["run", str(NAVIGATION), "-o", str(tmp_path), "--duration", "nan",
                 "--quiet"]) == 2
    assert main(["run", str(tmp_path / "missing.mission"), "-o", str(tmp_path),
                 "--quiet"]) == 2


def test_teleop_drives_into_the_wall_and_away_thesis_7_2(tmp_path: Path) -> None:
    summary, _ = run_into(SIMPLE_WALL, tmp_path, "teleop")
    m = summary.measurements
    assert "wall_e" in m["collided_with"] and "wall_w" not in m["collided_with"]
    xs = [s.robot_pose[0] for s in read_trace(tmp_path / "trace.jsonl")[1]]
    # It stops at the east wall's face (x = 2.5 m) minus half its length, then backs off.
    assert max(xs) == pytest.approx(2.5 - 0.281 / 2, abs=0.02)
    assert xs[-1] < 0.3
    assert m["tasks"][0]["succeeded"] and not m["tasks"][1]["succeeded"]


def test_teleop_circles(tmp_path: Path) -> None:
    summary, _ = run_into(EXAMPLES / "medium_sparse" / "medium_sparse.mission", tmp_path,
                          "teleop:circle", duration=25.0)
    header, rows = read_trace(tmp_path / "trace.jsonl")
    yaws = [s.robot_pose[2] for s in rows]
    assert max(yaws) > 3.0 and min(yaws) < -3.0  # it turned all the way round
    # Circles of 0.5 m from the dock reach the walls: thesis 7.2.3 touches them from the side.
    assert summary.measurements["path_length"] > 1.0


@pytest.mark.slow
@pytest.mark.parametrize("example", ["navigation", "simple_wall", "small_dense", "medium_sparse"])
def test_the_reference_navigator_completes_every_example_without_collision(
        example: str, tmp_path: Path) -> None:
    summary, _ = run_into(EXAMPLES / example / f"{example}.mission", tmp_path)
    assert summary.outcome == "completed", summary.measurements["tasks"]
    assert summary.measurements["collisions"] == 0
    # correct software passes every applicable requirement of the default specification
    assert summary.verdict == "pass", [v for v in summary.verdicts if v.status != "pass"]


def test_an_attached_sink_sees_exactly_the_recorded_stream(tmp_path: Path) -> None:
    sink = SampleList()
    run_into(NAVIGATION, tmp_path, duration=4.0, sinks=[sink])
    header, rows = read_trace(tmp_path / "trace.jsonl")
    recorded = list(rows)
    assert sink.header == header and sink.end is not None and sink.end[1] == "timeout"
    assert len(sink.samples) == len(recorded)
    for live, replayed in zip(sink.samples, recorded, strict=True):
        assert (live.seq, live.time, live.robot_pose, live.events) == \
               (replayed.seq, replayed.time, replayed.robot_pose, replayed.events)
        assert np.array_equal(live.poses, replayed.poses)
        assert np.array_equal(live.twists, replayed.twists)
        assert live.belief.laser_min == replayed.belief.laser_min


def test_bad_laser_noise_and_bad_vepl_are_located_input_errors(tmp_path: Path, capfd) -> None:  # type: ignore[no-untyped-def]
    assert main(["run", str(NAVIGATION), "-o", str(tmp_path / "a"), "--laser-noise", "inf",
                 "--quiet"]) == 2
    assert "--laser-noise: expected a finite number, found inf" in capfd.readouterr().err
    assert main(["run", str(NAVIGATION), "-o", str(tmp_path / "b"), "--laser-noise", "2",
                 "--quiet"]) == 2
    assert "--laser-noise: expected metres from 0 to 1, found 2" in capfd.readouterr().err
    spec = tmp_path / "bad.vepl"
    spec.write_text("specification bad\nquery q() { laser_mni < 1 }\n", encoding="utf-8")
    assert main(["run", str(NAVIGATION), "-o", str(tmp_path / "c"), "--vepl", str(spec),
                 "--quiet"]) == 2
    err = capfd.readouterr().err
    assert f"{spec}:2:" in err and "VEPL-UNKNOWN" in err and "laser_min" in err
    assert not (tmp_path / "c" / "world").exists()  # refused before any world was built


def test_laser_noise_makes_the_seed_matter(tmp_path: Path) -> None:
    runs = {}
    for name, seed, noise in (("a", "1", None), ("b", "1", None), ("c", "2", None),
                              ("d", "1", "0"), ("e", "2", "0"), ("f", "1", "0"),
                              ("g", "2", "0")):
        args = ["run", str(NAVIGATION), "-o", str(tmp_path / name), "--seed", seed,
                "--duration", "6", "--quiet", "--no-monitor"]
        # d, e: exact laser and no variation (no start jitter, humans as written)
        main(args + (["--laser-noise", noise] if noise is not None else [])
             + (["--no-variation"] if name in "de" else []))
        runs[name] = (tmp_path / name / "trace.jsonl").read_bytes()
    assert runs["a"] == runs["b"]  # same seed, same run
    assert runs["a"] != runs["c"]  # another seed draws other range errors
    # Without noise and variation the seed only names the run (in the header).
    assert runs["d"] != runs["e"]
    assert runs["d"].splitlines()[1:] == runs["e"].splitlines()[1:]
    # Without noise the seed still varies the humans and the start pose.
    assert runs["f"].splitlines()[1:] != runs["g"].splitlines()[1:]
