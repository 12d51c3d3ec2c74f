"""The test case names what the data collector forwards and how often (issue 14.11; thesis
3.2.2.2, 6.1.2): the mission's ``monitor`` block is checked, written into monitor.json,
honoured by the collector and the trace (only those data, at that rate, named in the
header), and a specification reading data the stream lacks is refused, never judged."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from rei.generators.pipeline import plan
from rei.lang.errors import LanguageError
from rei.lang.lsp.completion import mission_completions
from rei.lang.mission.model import COLLECTED_DATA
from rei.lang.printer import print_mission
from rei.lang.vepl.document import load_vepl
from rei.lang.workspace import Workspace
from rei.runtime.artifacts.monitor_config import load_monitor_config
from rei.runtime.commands.replay import replay
from rei.runtime.errors import RunError
from rei.runtime.observation.monitor import MonitorSink
from rei.runtime.observation.monitor.needs import needed_data
from rei.runtime.runs.session import run_into
from rei.runtime.trace import TraceError, read_trace, read_trace_end
from tests.commands.test_cli_streams import rei

EXAMPLE = Path(__file__).parents[2] / "examples" / "simple_wall"
SUBSET = "ground_truth, mission_events"
GEOMETRY_VEPL = """specification geometry_only

query wallClose(o: object[wall]) { distance(robot, o) < 0.05 }
query missionEnded() { mission_state == ended }
queryEvent touchWall(o) as wallClose(o) found
queryEvent missionEnds() as missionEnded found
signal SIG_WALL on touchWall utility -10
signal SIG_END on missionEnds utility 10
requirement NO_WALL "never touches a wall" { never SIG_WALL }
"""
LASER_VEPL = """specification laser_needed

query near(o: object[wall]) { distance(robot, o) < 0.3 }
query laserClose() { laser_min < 0.2 }
query slowAndLost() { cmd_speed < 0.01 and odom_error > 1 }
queryEvent close() as laserClose found
signal SIG_CLOSE on close utility -10
requirement NO_CLOSE "never close" { never SIG_CLOSE }
"""


def _mission(folder: Path, monitor: str) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    shutil.copy(EXAMPLE / "simple_wall.room", folder / "simple_wall.room")
    path = folder / "wall.mission"
    path.write_text(f"""mission to_the_wall in "simple_wall.room" {{
    {monitor}
    goal start_place at start tolerance 0.25 timeout 30
    goal at_the_wall at front tolerance 0.25 timeout 60
}}
""", encoding="utf-8")
    return path


def _problems(path: Path) -> list[tuple[str, int, str]]:
    return [(d.rule, d.span.line, d.message) for d in Workspace().check(path) if d.is_error]


# ---- the language ------------------------------------------------------------------------

def test_the_monitor_block_is_read_in_the_collectors_order(tmp_path: Path) -> None:
    path = _mission(tmp_path, "monitor { data mission_events, laser, ground_truth rate 2.5 Hz }")
    assert _problems(path) == []
    tree = plan(path, "monitor").tree
    config = json.loads(tree.files["monitor.json"].decode())
    assert config["data"] == ["ground_truth", "laser", "mission_events"]
    assert config["rate"] == 2.5
    # the generator's option still wins when given
    config = json.loads(plan(path, "monitor", {"rate": "20"}).tree.files["monitor.json"].decode())
    assert config["rate"] == 20.0 and config["data"] == ["ground_truth", "laser",
                                                         "mission_events"]


def test_the_monitor_block_prints_back(tmp_path: Path) -> None:
    path = _mission(tmp_path, "monitor { data laser, ground_truth rate 0.5 }")
    first = Workspace().mission(path).mission
    assert first is not None
    printed = tmp_path / "printed.mission"
    printed.write_text(print_mission(first, "simple_wall.room"), encoding="utf-8")
    second = Workspace().mission(printed).mission
    assert second is not None and (second.sample_rate, second.data) == (0.5, ("ground_truth",
                                                                               "laser"))
    assert "monitor" not in print_mission(Workspace().mission(_mission(tmp_path / "d", ""))
                                          .mission, "r.room")  # type: ignore[arg-type]


def test_without_a_monitor_block_everything_is_collected_at_10_hz(tmp_path: Path) -> None:
    path = _mission(tmp_path, "")
    config = json.loads(plan(path, "monitor").tree.files["monitor.json"].decode())
    assert config["data"] == list(COLLECTED_DATA) and config["rate"] == 10.0


@pytest.mark.parametrize(("monitor", "rule", "message"), [
    ("monitor { data ground_truth, odometri }", "MONITOR-DATA",
     "expected one of ground_truth, odometry, laser, nav_state, mission_events, found "
     "'odometri'; did you mean 'odometry'?"),
    ("monitor { data ground_truth, laser, laser }", "MONITOR-DATA",
     "expected each name once, found 'laser' again (first at line 2)"),
    ("monitor { data laser, odometry }", "MONITOR-DATA",
     "expected 'ground_truth' among the collected data (every sample is built around the "
     "bodies' poses), found laser, odometry"),
    ("monitor { rate 0 }", "NUM-RANGE", "monitor rate (samples per second): expected a "
                                        "number > 0 and <= 1000, found 0"),
    ("monitor { rate 5000 Hz }", "NUM-RANGE", "expected a number > 0 and <= 1000, found 5000"),
    ("monitor { rate nan }", "NUM-FINITE", "expected a finite number, found 'nan'"),
    ("monitor { rate 5 rate 6 }", "OPTION-REPEAT", "monitor: expected one 'rate', found "
                                                   "another"),
])
def test_a_bad_monitor_block_is_a_located_error(tmp_path: Path, monitor: str, rule: str,
                                                message: str) -> None:
    problems = _problems(_mission(tmp_path, monitor))
    assert [(r, line) for r, line, _ in problems] == [(rule, 2)]
    assert message in problems[0][2]


def test_the_editor_completes_the_monitor_block() -> None:
    head = 'mission m in "r.room" {\n    monitor {\n        '
    assert {c.label for c in mission_completions(head, None)} == {"rate", "data"}
    names = {c.label for c in mission_completions(head + "data ground_truth, la", None)}
    assert names == set(COLLECTED_DATA)
    outside = {c.label for c in mission_completions('mission m in "r.room" {\n    ', None)}
    assert "monitor" in outside and not outside & {"rate", "data", "Hz"}


def test_the_monitor_configuration_is_checked_when_read(tmp_path: Path) -> None:
    path = _mission(tmp_path, "")
    tree = plan(path, "monitor").tree
    config = json.loads(tree.files["monitor.json"].decode())
    for bad in (["laser"], ["ground_truth", "sonar"], ["ground_truth", "ground_truth"], "all"):
        (tmp_path / "monitor.json").write_text(json.dumps({**config, "data": bad}),
                                               encoding="utf-8")
        with pytest.raises(RunError, match="monitor.json: data: expected a list of distinct "
                                           "names"):
            load_monitor_config(tmp_path)


# ---- what each query reads ---------------------------------------------------------------

def test_the_default_specification_needs_laser_navigation_state_and_events() -> None:
    assert needed_data(load_vepl()) == {"laser", "nav_state", "mission_events"}


def test_what_a_query_reads_is_found_through_its_terms(tmp_path: Path) -> None:
    path = tmp_path / "needs.vepl"
    path.write_text(LASER_VEPL, encoding="utf-8")
    assert needed_data(load_vepl(path)) == {"laser", "nav_state", "odometry"}
    path.write_text(GEOMETRY_VEPL, encoding="utf-8")
    assert needed_data(load_vepl(path)) == {"mission_events"}


# ---- the run and the replay --------------------------------------------------------------

@pytest.fixture(scope="module")
def subset_run(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """A mission collecting ground truth and mission events at 4 samples per second, run
    with a specification that reads nothing else: (its output folder, its .vepl)."""
    folder = tmp_path_factory.mktemp("subset")
    mission = _mission(folder, f"monitor {{ rate 4 Hz data {SUBSET} }}")
    vepl = folder / "geometry.vepl"
    vepl.write_text(GEOMETRY_VEPL, encoding="utf-8")
    out = folder / "out"
    summary, _ = run_into(mission, out, vepl=vepl)
    assert summary.outcome == "completed"
    return out, vepl


def test_the_trace_holds_only_the_collected_data_at_the_missions_rate(
        subset_run: tuple[Path, Path]) -> None:
    out, _ = subset_run
    lines = (out / "trace.jsonl").read_text(encoding="utf-8").splitlines()
    head = json.loads(lines[0])
    assert head["data"] == ["ground_truth", "mission_events"] and head["rate"] == 4.0
    samples = [json.loads(line) for line in lines[1:-1]]
    assert all(s["belief"] == {} and "events" in s for s in samples)
    assert sum(len(s["events"]) for s in samples) > 0  # mission events are collected
    # four samples in each whole simulated second (the last sample may close the run early)
    end = samples[-1]["time"]
    per_second = [sum(1 for s in samples if k <= s["time"] < k + 1) for k in range(int(end))]
    assert per_second and set(per_second) == {4}
    header, rows = read_trace(out / "trace.jsonl")
    assert header.data == ("ground_truth", "mission_events") and header.rate == 4.0
    assert all(r.belief.scan is None for r in rows)


def test_the_subset_run_is_deterministic(subset_run: tuple[Path, Path], tmp_path: Path) -> None:
    out, vepl = subset_run
    again = tmp_path / "again"
    run_into(out.parent / "wall.mission", again, vepl=vepl)
    for name in ("trace.jsonl", "events.csv", "summary.json", "world/monitor.json"):
        assert (again / name).read_bytes() == (out / name).read_bytes(), name


def test_the_default_mission_collects_everything(tmp_path: Path) -> None:
    summary, _ = run_into(_mission(tmp_path, ""), tmp_path / "out", duration=1.0,
                          monitor=False)
    header, rows = read_trace(tmp_path / "out" / "trace.jsonl")
    assert header.data == COLLECTED_DATA and header.rate == 10.0
    samples = list(rows)
    assert len(samples) == 11 and any(s.belief.scan is not None for s in samples)


def test_a_specification_needing_uncollected_data_is_refused_before_the_run(
        tmp_path: Path) -> None:
    mission = _mission(tmp_path, f"monitor {{ data {SUBSET} }}")
    vepl = tmp_path / "laser.vepl"
    vepl.write_text(LASER_VEPL, encoding="utf-8")
    with pytest.raises(LanguageError) as caught:
        run_into(mission, tmp_path / "lib", vepl=vepl)
    found = [(d.rule, d.span.file, d.span.line) for d in caught.value.diagnostics]
    assert found == [("VEPL-DATA", str(vepl), 4), ("VEPL-DATA", str(vepl), 5)]
    assert not (tmp_path / "lib" / "trace.jsonl").exists()
    done = rei("run", str(mission), "-o", str(tmp_path / "cli"), "--vepl", str(vepl))
    assert done.returncode == 2, done.stderr
    assert (f"{vepl}:4:1: VEPL-DATA: query 'laserClose' reads laser_min, which needs the "
            f"'laser' data; expected the mission 'to_the_wall' to collect it, found only "
            f"ground_truth, mission_events") in done.stderr
    assert (f"{vepl}:5:1: VEPL-DATA: query 'slowAndLost' reads cmd_speed, which needs the "
            f"'nav_state' data and odom_error, which needs the 'odometry' data") in done.stderr
    assert not (tmp_path / "cli" / "trace.jsonl").exists()


def test_a_replay_needing_data_the_trace_lacks_is_refused(subset_run: tuple[Path, Path],
                                                          tmp_path: Path) -> None:
    out, _ = subset_run
    vepl = tmp_path / "laser.vepl"
    vepl.write_text(LASER_VEPL, encoding="utf-8")
    done = rei("replay", str(out / "trace.jsonl"), "--vepl", str(vepl), "-o",
               str(tmp_path / "replayed"))
    assert done.returncode == 2, done.stderr
    assert (f"{vepl}:4:1: VEPL-DATA: query 'laserClose' reads laser_min, which needs the "
            f"'laser' data; expected the trace '{out / 'trace.jsonl'}' to carry it") \
        in done.stderr
    assert not (tmp_path / "replayed" / "summary.json").exists()
    # so is the default specification (it reads the laser, the command and the nav state)
    done = rei("replay", str(out / "trace.jsonl"), "-o", str(tmp_path / "default"))
    assert done.returncode == 2 and "VEPL-DATA" in done.stderr


def test_the_monitor_sink_refuses_a_stream_without_the_data_it_reads(
        subset_run: tuple[Path, Path], tmp_path: Path) -> None:
    """A library user feeding the monitor a stream of their own is refused as well."""
    header, rows = read_trace(subset_run[0] / "trace.jsonl")
    list(rows)
    vepl = tmp_path / "laser.vepl"
    vepl.write_text(LASER_VEPL, encoding="utf-8")
    with pytest.raises(LanguageError, match="expected the stream to carry it"):
        MonitorSink(vepl, tmp_path / "monitor").start(header)
    MonitorSink(subset_run[1], tmp_path / "geometry").start(header)  # reads what is there


def test_a_replay_of_the_subset_gives_the_live_verdicts(subset_run: tuple[Path, Path],
                                                        tmp_path: Path) -> None:
    out, vepl = subset_run
    summary = replay(out / "trace.jsonl", vepl, tmp_path / "replayed")
    live = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    assert [(v.requirement, v.status) for v in summary.verdicts] == [
        (v["requirement"], v["status"]) for v in live["verdicts"]] == [("NO_WALL", "pass")]
    assert (tmp_path / "replayed" / "events.csv").read_bytes() == \
        (out / "events.csv").read_bytes()


# ---- the trace's rules -------------------------------------------------------------------

def _rewrite(src: Path, dst: Path, header: dict[str, object] | None = None,
             sample: dict[str, object] | None = None) -> Path:
    lines = src.read_text(encoding="utf-8").splitlines()
    head = json.loads(lines[0])
    if header is not None:
        head = {k: v for k, v in {**head, **header}.items() if v is not None}
    first = json.loads(lines[1])
    if sample is not None:
        first.update(sample)
    dst.write_text("\n".join([json.dumps(head), json.dumps(first), *lines[2:]]) + "\n",
                   encoding="utf-8")
    return dst


@pytest.mark.parametrize(("header", "sample", "message"), [
    ({"data": ["ground_truth", "sonar"]}, None,
     r":1: data\[1\]: expected one of ground_truth, .*, found 'sonar'"),
    ({"data": ["ground_truth", "mission_events", "ground_truth"]}, None,
     r":1: data\[2\]: expected another of .*, found 'ground_truth'"),
    ({"data": ["mission_events"]}, None,
     r":1: data: expected 'ground_truth' among the collected data"),
    ({"data": "everything"}, None, r":1: data: expected a list of the names"),
    (None, {"belief": {"laser_min": 1.0, "scan": None}},
     r":2: belief: expected no fields, found the unknown field 'laser_min'"),
    ({"data": ["ground_truth"]}, None, r":2: expected only the fields .*, found the unknown "
                                       r"field 'events'"),
])
def test_a_trace_must_carry_exactly_its_collected_data(
        subset_run: tuple[Path, Path], tmp_path: Path, header: dict[str, object] | None,
        sample: dict[str, object] | None, message: str) -> None:
    path = _rewrite(subset_run[0] / "trace.jsonl", tmp_path / "bad.jsonl", header, sample)
    with pytest.raises(TraceError, match=message):
        _, rows = read_trace(path)
        list(rows)


def test_a_schema_3_trace_is_read_as_collecting_everything(tmp_path: Path) -> None:
    run_into(_mission(tmp_path, ""), tmp_path / "out", duration=0.5, monitor=False)
    new = tmp_path / "out" / "trace.jsonl"
    old = _rewrite(new, tmp_path / "old.jsonl", {"version": 3, "data": None})
    header, rows = read_trace(old)
    assert header.data == COLLECTED_DATA
    assert [s.belief for s in rows] == [s.belief for s in read_trace(new)[1]]
    assert read_trace_end(old) == read_trace_end(new)
    # a schema 3 header never names its data: one that does is damaged
    with pytest.raises(TraceError, match="unknown field 'data'"):
        read_trace(_rewrite(new, tmp_path / "odd.jsonl", {"version": 3}))
