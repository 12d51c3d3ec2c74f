"""Nothing REI writes goes through a link already in the output folder (issue 13, point 7).

Each test plants, in a reused output folder, symbolic links at the names a command writes
(``run.log``, ``trace.jsonl.partial``, ``world/``, ``automata/``, ``results.csv``, ...) pointing
at a victim file or folder outside it, runs the real command, and checks that the victim is
unchanged and the outputs are regular files and folders inside. Stale files of an earlier run
in ``world/`` and ``automata/`` are gone after the next run.
"""

from __future__ import annotations

import os
import subprocess
import sys
from collections.abc import Sequence
from pathlib import Path

import pytest

from rei.generators.output import OutputTree, open_output, write_atomic, write_tree
from rei.runtime.campaigns import CampaignError, CampaignStore
from tests.campaigns.records import example_plan, write_campaign
from tests.conftest import EXAMPLES

MISSION = EXAMPLES / "simple_wall" / "simple_wall.mission"
SAFETY_LIMIT = 600.0
"""Seconds after which a stuck command fails the test instead of hanging CI."""
PRECIOUS = b"precious: must never change\n"


class Victims:
    """A file and two folders outside the output folder that nothing may write into."""

    def __init__(self, base: Path) -> None:
        self.file = base / "victim.txt"
        self.file.write_bytes(PRECIOUS)
        self.folders = [base / "victim_dir", base / "victim_dir2"]
        for folder in self.folders:
            folder.mkdir()
            (folder / "keep.txt").write_bytes(PRECIOUS)

    def plant(self, out: Path, files: Sequence[str], folders: Sequence[str] = ()) -> None:
        out.mkdir(parents=True, exist_ok=True)
        for name in files:
            (out / name).parent.mkdir(parents=True, exist_ok=True)
            (out / name).symlink_to(self.file)
        for name, target in zip(folders, self.folders, strict=False):
            (out / name).symlink_to(target, target_is_directory=True)

    def assert_untouched(self) -> None:
        assert self.file.read_bytes() == PRECIOUS
        for folder in self.folders:
            assert sorted(p.name for p in folder.iterdir()) == ["keep.txt"]
            assert (folder / "keep.txt").read_bytes() == PRECIOUS


def rei(*argv: str, program: str = "rei.runtime.commands.cli") -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", program, *argv], capture_output=True,
                          text=True, timeout=SAFETY_LIMIT, stdin=subprocess.DEVNULL)


def assert_regular(out: Path, names: list[str]) -> None:
    for name in names:
        path = out / name
        assert not path.is_symlink() and path.is_file(), name
        assert path.resolve().is_relative_to(out.resolve()), name


def assert_real_folder(path: Path) -> None:
    assert not path.is_symlink() and path.is_dir(), path


# -- the writing functions themselves ----------------------------------------------------


def test_open_output_replaces_a_symlink_a_hard_link_and_a_fifo(tmp_path: Path) -> None:
    victims = Victims(tmp_path)
    out = tmp_path / "out"
    victims.plant(out, ["link.txt"])
    os.link(victims.file, out / "hard.txt")
    os.mkfifo(out / "fifo.txt")  # opening a FIFO to write would block until a reader came
    for name in ("link.txt", "hard.txt", "fifo.txt", "new.txt"):
        with open_output(out / name) as handle:
            handle.write("ours\n")
        write_atomic(out / f"atomic-{name}", b"ours\n")
    victims.assert_untouched()
    assert_regular(out, ["link.txt", "hard.txt", "fifo.txt", "new.txt"])
    assert (out / "hard.txt").read_text() == "ours\n"
    assert os.stat(out / "hard.txt").st_nlink == 1


def test_open_output_refuses_a_folder_at_the_name(tmp_path: Path) -> None:
    (tmp_path / "run.log").mkdir()
    with pytest.raises(IsADirectoryError, match="expected a file name, found a folder"):
        open_output(tmp_path / "run.log")


def test_write_tree_never_writes_through_a_linked_subfolder(tmp_path: Path) -> None:
    victims = Victims(tmp_path)
    out = tmp_path / "out"
    victims.plant(out, ["world.json"], ["urdf"])
    tree = OutputTree()
    tree.add_text("world.json", "{}\n")
    tree.add_text("urdf/keep.txt", "generated\n")
    write_tree(tree, out)
    victims.assert_untouched()
    assert_real_folder(out / "urdf")
    assert_regular(out, ["world.json", "urdf/keep.txt"])


def test_write_tree_replace_leaves_exactly_the_new_files(tmp_path: Path) -> None:
    folder = tmp_path / "world"
    (folder / "urdf").mkdir(parents=True)
    (folder / "urdf" / "stale.urdf").write_text("<robot/>")
    tree = OutputTree()
    tree.add_text("world.json", "{}\n")
    write_tree(tree, folder, replace=True)
    assert sorted(p.relative_to(folder).as_posix() for p in folder.rglob("*")) == ["world.json"]
    # Nothing of the swap is left beside it.
    assert sorted(p.name for p in tmp_path.iterdir()) == ["world"]


# -- the commands --------------------------------------------------------------------------

RUN_FILES = ["run.log", "trace.jsonl", "trace.jsonl.partial", "summary.json",
             ".summary.json.tmp", "events.csv", "report.html"]


@pytest.mark.slow
def test_rei_run_and_replay_write_through_no_link(tmp_path: Path) -> None:
    victims = Victims(tmp_path)
    out = tmp_path / "run"
    victims.plant(out, RUN_FILES, ["world", "automata"])
    done = rei("run", str(MISSION), "-o", str(out), "--duration", "1", "--quiet")
    assert done.returncode in (0, 1), done.stderr
    victims.assert_untouched()
    assert_regular(out, ["run.log", "trace.jsonl", "summary.json", "events.csv", "report.html",
                         "world/world.json", "automata/automata.py"])
    assert_real_folder(out / "world")
    assert_real_folder(out / "automata")
    assert not (out / "trace.jsonl.partial").exists()
    # rei replay of that trace into another folder full of links.
    again = tmp_path / "replay"
    victims.plant(again, ["events.csv", "summary.json", ".summary.json.tmp", "report.html"],
                  ["automata"])
    replayed = rei("replay", str(out / "trace.jsonl"), "-o", str(again))
    assert replayed.returncode in (0, 1), replayed.stderr
    victims.assert_untouched()
    assert_regular(again, ["events.csv", "summary.json", "report.html", "automata/automata.py"])


@pytest.mark.slow
def test_bad_input_never_costs_the_outputs_of_an_earlier_run(tmp_path: Path) -> None:
    """A second `rei run` (or `rei monitor`) into a folder with a finished run's outputs that
    is refused for its input (exit 2) leaves those outputs as they were, byte for byte."""
    out = tmp_path / "run"
    done = rei("run", str(MISSION), "-o", str(out), "--duration", "1", "--quiet")
    assert done.returncode in (0, 1), done.stderr
    kept = ["summary.json", "trace.jsonl", "events.csv", "report.html"]
    before = {name: (out / name).read_bytes() for name in kept}
    bad_vepl = tmp_path / "bad.vepl"
    bad_vepl.write_text("garbage {\n", encoding="utf-8")
    bad_mission = tmp_path / "bad.mission"
    bad_mission.write_text("mission broken\n", encoding="utf-8")
    refused = [
        rei("run", str(MISSION), "-o", str(out), "--duration", "1", "--vepl", str(bad_vepl)),
        rei("run", str(bad_mission), "-o", str(out), "--duration", "1"),
        rei("run", str(MISSION), "-o", str(out), "--param", "react_zon=0.7"),
        rei("monitor", "--bus", "tcp/127.0.0.1:9", "--vepl", str(bad_vepl), "-o", str(out)),
    ]
    for done in refused:
        assert done.returncode == 2, done.stderr
        assert ("bad." in done.stderr or "react_zon" in done.stderr), done.stderr
        assert {name: (out / name).read_bytes() for name in kept} == before, done.args
    assert not [p.name for p in out.iterdir() if p.name.endswith(".earlier")]
    # a mission that is not there makes no output folder either
    fresh = tmp_path / "fresh"
    missing = rei("run", str(tmp_path / "nope.mission"), "-o", str(fresh))
    assert missing.returncode == 2, missing.stderr
    assert missing.stderr.strip() == (f"rei: error: {tmp_path / 'nope.mission'}:1:1: "
                                      f"INPUT-READ: no such file")  # the reader's own words
    assert not fresh.exists()
    # a good run into the folder still replaces them
    done = rei("run", str(MISSION), "-o", str(out), "--duration", "0.5", "--quiet")
    assert done.returncode in (0, 1), done.stderr
    assert (out / "trace.jsonl").read_bytes() != before["trace.jsonl"]
    assert not [p.name for p in out.iterdir() if p.name.endswith(".earlier")]


@pytest.mark.slow
def test_a_reused_run_folder_keeps_no_stale_urdf_or_automata(tmp_path: Path) -> None:
    out = tmp_path / "run"
    (out / "world" / "urdf").mkdir(parents=True)
    (out / "world" / "urdf" / "stale_body.urdf").write_text("<robot name='stale'/>")
    (out / "automata").mkdir()
    (out / "automata" / "stale_helper.py").write_text("raise SystemExit('stale')\n")
    done = rei("run", str(MISSION), "-o", str(out), "--duration", "1", "--quiet")
    assert done.returncode in (0, 1), done.stderr
    assert not (out / "world" / "urdf" / "stale_body.urdf").exists()
    assert not (out / "automata" / "stale_helper.py").exists()
    assert [p.name for p in (out / "automata").iterdir()] == ["automata.py"]
    assert (out / "world" / "world.json").is_file()
    assert not [p for p in out.iterdir() if p.name.startswith(".")]  # no swap leftovers


@pytest.mark.slow
def test_rei_gen_generate_writes_through_no_link(tmp_path: Path) -> None:
    victims = Victims(tmp_path)
    out = tmp_path / "gen"
    victims.plant(out, ["world.json"], ["urdf"])
    done = rei("generate", "--target", "pybullet", "-o", str(out), str(MISSION),
               program="rei.lang.cli")
    assert done.returncode == 0, done.stderr
    victims.assert_untouched()
    assert_regular(out, ["world.json"])
    assert_real_folder(out / "urdf")
    assert list((out / "urdf").glob("*.urdf"))


def test_campaign_outputs_write_through_no_link(tmp_path: Path) -> None:
    from rei.runtime.commands.campaign import finish  # noqa: PLC0415

    victims = Victims(tmp_path)
    root = tmp_path / "campaign"
    plan = write_campaign(root)
    for name in ("results.csv", "results.parquet", ".lock"):
        (root / name).unlink(missing_ok=True)
    victims.plant(root, ["results.csv", "results.parquet", "junit.xml", "report.html", ".lock"])
    with CampaignStore.open(root, plan, {}) as store:
        store.write_tables()
    finish(root)
    victims.assert_untouched()
    assert_regular(root, ["results.csv", "results.parquet", "junit.xml", "report.html", ".lock"])


def test_a_campaign_refuses_a_linked_runs_folder(tmp_path: Path) -> None:
    victims = Victims(tmp_path)
    root = tmp_path / "campaign"
    plan = example_plan()
    root.mkdir()
    victims.plant(root, [], ["runs"])
    (root / "campaign.json").write_text("{}")
    with pytest.raises(CampaignError, match="runs: expected the folder of the recorded runs"):
        CampaignStore.open(root, plan, {})
    victims.assert_untouched()
