"""`rei shrink` end to end: real `rei run` processes (pybullet) with a navigator of the
bug-finding benchmark that has one known defect (bench/defects: ExceedsDriveLimit, caught by
SPEED_LIMIT) in a room with people, objects and goals that have nothing to do with it."""

from __future__ import annotations

import json
import shlex
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from rei.lang.cli import main as rei_gen
from rei.runtime.campaigns.shrink import RunSettings, load_case, size_reduction, sizes
from rei.runtime.commands.cli import main

REPO = Path(__file__).resolve().parents[2]
CASES = Path(__file__).parent / "cases"
CLUTTERED = CASES / "cluttered.mission"
SPEEDING = "bench.defects.control:ExceedsDriveLimit"


@pytest.fixture
def at_repo(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(REPO)  # `module:Class` controllers import from the current folder


def _shrink(out: Path, *extra: str) -> int:
    return main(["shrink", str(CLUTTERED), "-o", str(out), "--controller", SPEEDING,
                 "--requirement", "SPEED_LIMIT", "--seeds", "2", "--duration", "3",
                 "--keep", "floors", "--workers", "2", "-q", *extra])


@pytest.mark.slow
@pytest.mark.usefixtures("at_repo")
def test_shrink_drops_what_is_irrelevant_and_keeps_the_failure(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "shrunk"
    assert _shrink(out) == 1  # the case fails: the one pass rule, and a case was written
    line = capsys.readouterr().out.strip().splitlines()[-1]
    assert line.startswith("verdict: FAIL (SPEED_LIMIT, shrunk 25 -> ")
    summary = json.loads((out / "shrink.json").read_text(encoding="utf-8"))
    assert summary["result"] == "shrunk" and summary["requirement"] == "SPEED_LIMIT"
    assert summary["run"]["seeds"] == [0, 1] and summary["complete"] is True
    after = summary["sizes"]["after"]
    # the people, the objects, the third goal and the trajectory went; the floors were kept
    assert (after["humans"], after["objects"], after["trajectory_vertices"]) == (0, 0, 0)
    assert after["goals"] == 2 and after["floors"] == 15  # two goals: the least a mission has
    assert summary["sizes"]["before"]["elements"] == 25
    assert summary["reduction"]["elements"] == round(1 - after["elements"] / 25, 4) > 0.3
    assert summary["runs"] <= 40 and summary["rejected_by_check"] >= 1
    # the result checks clean with the same checks as a hand-written file
    assert rei_gen(["check", str(out / "cluttered.mission"), str(out / "cluttered.room")]) == 0
    assert (out / "before-after.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # the replay command reproduces the failure
    argv = shlex.split(summary["replay"])
    assert argv[:3] == ["rei", "run", str(out / "cluttered.mission")] and "--seed" in argv
    assert main(argv[1:] + ["-q"]) == 1
    replayed = json.loads((Path(argv[argv.index("-o") + 1]) / "summary.json").read_text(
        encoding="utf-8"))
    assert {v["requirement"]: v["status"] for v in replayed["verdicts"]}["SPEED_LIMIT"] == "fail"
    # the same command again resumes from shrink-runs.jsonl: nothing runs, same outputs
    first = {name: (out / name).read_bytes()
             for name in ("cluttered.mission", "cluttered.room", "shrink.json")}
    capsys.readouterr()
    assert main(["shrink", str(CLUTTERED), "-o", str(out), "--controller", SPEEDING,
                 "--requirement", "SPEED_LIMIT", "--seeds", "2", "--duration", "3",
                 "--keep", "floors", "--workers", "2"]) == 1
    assert "0 runs started now" in capsys.readouterr().err
    assert {name: (out / name).read_bytes() for name in first} == first
    # the benchmarks' figure, from the library: the same shrink, all of it remembered
    settings = RunSettings(seeds=(0, 1), controller=SPEEDING, duration=3.0, workers=2)
    assert size_reduction(CLUTTERED, out, settings, requirement="SPEED_LIMIT",
                          keep=frozenset({"floors"})) == summary["reduction"]["elements"]
    assert json.loads((out / "shrink.json").read_text(encoding="utf-8"))["runs"] == \
        summary["runs"]
    # a campaign's report shows the shrunk case as its cluster's reproducer (issue 25.4)
    campaign = tmp_path / "campaign"
    assert main(["campaign", str(CLUTTERED), "-o", str(campaign), "--controller", SPEEDING,
                 "--duration", "3", "--workers", "1", "-q"]) == 1
    shutil.copytree(out, campaign / "shrunk" / "cluttered")
    assert main(["report", str(campaign)]) == 1
    clusters = json.loads((campaign / "clusters.json").read_text(encoding="utf-8"))["clusters"]
    assert [c["requirement"] for c in clusters] == ["SPEED_LIMIT"]
    reproducer = clusters[0]["reproducer"]
    assert reproducer["shrunk"] is True and reproducer["replay"] == summary["replay"]
    assert reproducer["mission"] == "shrunk/cluttered/cluttered.mission"
    assert reproducer["elements"] == after["elements"]


@pytest.mark.slow
@pytest.mark.usefixtures("at_repo")
def test_a_case_that_passes_is_not_shrunk(tmp_path: Path,
                                          capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "nothing"
    assert main(["shrink", str(CLUTTERED), "-o", str(out), "--seeds", "1", "-q"]) == 0
    line = capsys.readouterr().out.strip()
    assert line.startswith("verdict: NOTHING TO SHRINK: every requirement passes")
    summary = json.loads((out / "shrink.json").read_text(encoding="utf-8"))
    assert summary["result"] == "passes" and summary["replay"] is None
    assert not list(out.glob("*.mission")) and not (out / "before-after.png").exists()


def test_bad_input_is_refused_in_one_line(tmp_path: Path,
                                          capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "out"
    assert main(["shrink", str(tmp_path / "missing.mission"), "-o", str(out)]) == 2
    assert "missing.mission: expected a .mission file to shrink, found nothing" in \
        capsys.readouterr().err
    (tmp_path / "bad.room").write_text("room bad {\n    tile 1.0\n}\n", encoding="utf-8")
    (tmp_path / "bad.mission").write_text(
        'mission m in "bad.room" {\n    goal a at nowhere\n    goal b at nowhere\n}\n',
        encoding="utf-8")
    assert main(["shrink", str(tmp_path / "bad.mission"), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert "bad.mission:2:" in err and "Traceback" not in err
    for option in (["--duration", "nan"], ["--timeout", "-1"]):
        assert main(["shrink", str(CLUTTERED), "-o", str(out), *option]) == 2
        assert "expected a positive finite number" in capsys.readouterr().err
    assert main(["shrink", str(CLUTTERED), "-o", str(CASES)]) == 2  # would replace the case
    assert "expected a folder other than the case's own" in capsys.readouterr().err
    (tmp_path / "a_file").write_text("", encoding="utf-8")
    assert main(["shrink", str(CLUTTERED), "-o", str(tmp_path / "a_file")]) == 2
    err = capsys.readouterr().err
    assert "a_file: expected a folder (new or existing), found a file" in err
    assert len(err.splitlines()) == 1
    assert main(["shrink", str(CLUTTERED), "-o", str(tmp_path / "refused"), "--controller",
                 "no_such_module:Navigator", "--seeds", "1", "--duration", "1", "-q"]) == 2
    assert "cannot import module 'no_such_module'" in capsys.readouterr().err
    with pytest.raises(SystemExit) as exit_:
        main(["shrink", str(CLUTTERED), "-o", str(out), "--seeds", "0"])
    assert exit_.value.code == 2
    assert not out.exists() or not list(out.iterdir())  # nothing was run or written


@pytest.mark.slow
def test_an_interrupted_shrink_keeps_its_best_case_and_resumes(tmp_path: Path) -> None:
    out = tmp_path / "stopped"
    argv = [sys.executable, "-m", "rei.runtime.commands", "shrink", str(CLUTTERED), "-o", str(out),
            "--controller", SPEEDING, "--requirement", "SPEED_LIMIT", "--seeds", "2",
            "--duration", "3", "--keep", "floors", "--workers", "2", "-q"]
    process = subprocess.Popen(argv, cwd=REPO, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                               text=True)
    journal = out / "shrink-runs.jsonl"
    # interrupt once the original and a first candidate are judged (more remain)
    while process.poll() is None and (not journal.is_file()
                                      or len(journal.read_text().splitlines()) < 2):
        time.sleep(0.2)
    process.send_signal(signal.SIGINT)
    stdout, stderr = process.communicate()
    assert process.returncode == 130, stderr
    assert "interrupted; the best case so far is in" in stderr
    summary = json.loads((out / "shrink.json").read_text(encoding="utf-8"))
    assert summary["stopped"] == "interrupted" and summary["complete"] is False
    kept = load_case(out / "cluttered.mission")  # the best case so far: whole, and clean
    assert kept.problems() == []
    assert sizes(kept)["elements"] == summary["sizes"]["after"]["elements"] < 25
    assert not list(out.glob("*.partial"))
    remembered = len(journal.read_text().splitlines())
    # the same command again goes on from the journal: what was judged is not run again
    done = subprocess.run(argv[:-1], cwd=REPO, capture_output=True, text=True, check=False)
    assert done.returncode == 1, done.stderr
    assert f"remembered from {journal}" in done.stderr
    started = int(done.stderr.split(" runs started now")[0].rsplit(None, 1)[-1])
    total = json.loads((out / "shrink.json").read_text(encoding="utf-8"))["runs"]
    assert started <= total - 2 * (remembered - 1)  # each remembered candidate: 2 seeds saved
