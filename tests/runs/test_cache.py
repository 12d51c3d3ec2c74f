"""The cache of generated worlds and automata (rei.runtime.runs.cache): a hit gives the bytes and
the
model generation gives; a changed input, a changed REI, a half-written or corrupt entry and
concurrent writers never serve a stale artifact; runs with the cache write the same outputs."""

from __future__ import annotations

import concurrent.futures
import multiprocessing
import shutil
from pathlib import Path

import pytest

from rei.lang.errors import LanguageError
from rei.runtime.observation.monitor import generate_automata
from rei.runtime.runs import cache as cache_module
from rei.runtime.runs.cache import CACHE_VARIABLE, ArtifactCache
from rei.runtime.runs.session import run_into
from rei.runtime.simulation.assembly import generate_world

from ..conftest import EXAMPLES


def files_of(folder: Path) -> dict[str, bytes]:
    return {p.relative_to(folder).as_posix(): p.read_bytes()
            for p in sorted(folder.rglob("*")) if p.is_file()}


def entries(root: Path) -> list[Path]:
    """The whole entries in a cache folder (temporary folders start with a dot)."""
    return sorted(p for p in root.glob("*/*") if not p.name.startswith("."))


@pytest.fixture
def room_copy(tmp_path: Path) -> Path:
    """simple_wall's mission and room in a folder of the test's own, to be edited."""
    folder = tmp_path / "inputs"
    folder.mkdir()
    for name in ("simple_wall.mission", "simple_wall.room"):
        shutil.copy(EXAMPLES / "simple_wall" / name, folder / name)
    return folder / "simple_wall.mission"


def test_a_hit_gives_what_generation_gives(tmp_path: Path, room_copy: Path) -> None:
    cache = ArtifactCache(tmp_path / "cache")
    expected = generate_world(room_copy, tmp_path / "plain", replace=True)
    made = cache.world(room_copy, tmp_path / "first")
    assert len(entries(cache.root)) == 1
    reused = cache.world(room_copy, tmp_path / "second")
    assert made == expected and reused == expected
    assert files_of(tmp_path / "first") == files_of(tmp_path / "plain") \
        == files_of(tmp_path / "second")
    assert files_of(tmp_path / "plain")  # not vacuous: the targets were written

    generate_automata(None, tmp_path / "automata-plain", replace=True)
    cache.automata(None, tmp_path / "automata-first")
    cache.automata(None, tmp_path / "automata-second")
    assert files_of(tmp_path / "automata-plain") == files_of(tmp_path / "automata-first") \
        == files_of(tmp_path / "automata-second")
    assert len(entries(cache.root)) == 2


def test_a_hit_reads_no_source(tmp_path: Path, room_copy: Path,
                               monkeypatch: pytest.MonkeyPatch) -> None:
    cache = ArtifactCache(tmp_path / "cache")
    cache.world(room_copy, tmp_path / "first")

    def no_generation(*args: object) -> None:
        raise AssertionError("generated again although nothing changed")

    monkeypatch.setattr("rei.generators.concrete.build.load_concrete_mission", no_generation)
    cache.world(room_copy, tmp_path / "second")


CRATE = """[types.crate]
kind = "static"
footprint = {{ shape = "box", size = [{size}, 0.4] }}
height = 0.5
mass = 3.0
"""


ROOM = """room r {
    catalogue "types.toml"
    tile 1.0
    floor a { right b } floor b { right c } floor c { top d } floor d
    robot bot : turtlebot3_waffle on a
    object box1 : crate on d
}
"""
MISSION = ('mission m in "r.room" {\n    goal s at a tolerance 0.25 timeout 30\n'
           '    goal g at c tolerance 0.25 timeout 60\n}\n')


@pytest.mark.parametrize("edit", ["room", "mission", "catalogue"])
def test_a_changed_input_is_generated_again(tmp_path: Path, edit: str) -> None:
    # a mission, the room it imports and the catalogue the room names: only the mission's
    # bytes are in the key; the others are inputs the entry lists
    folder = tmp_path / "inputs"
    folder.mkdir()
    (folder / "types.toml").write_text(CRATE.format(size=0.4))
    (folder / "r.room").write_text(ROOM)
    mission = folder / "m.mission"
    mission.write_text(MISSION)
    cache = ArtifactCache(tmp_path / "cache")
    before = cache.world(mission, tmp_path / "before")
    if edit == "room":
        (folder / "r.room").write_text(ROOM.replace("tile 1.0", "tile 1.25"))
    elif edit == "mission":
        mission.write_text(MISSION.replace("timeout 60", "timeout 61"))
    else:
        (folder / "types.toml").write_text(CRATE.format(size=0.5))
    expected = generate_world(mission, tmp_path / "plain", replace=True)
    got = cache.world(mission, tmp_path / "after")
    assert got == expected and got != before
    assert files_of(tmp_path / "after") == files_of(tmp_path / "plain")
    if edit != "mission":  # a changed mission is another key; the others replace the entry
        assert len(entries(cache.root)) == 1
        assert files_of(tmp_path / "after") != files_of(tmp_path / "before")


def test_a_changed_specification_is_generated_again(tmp_path: Path) -> None:
    vepl = tmp_path / "spec.vepl"
    shutil.copy(EXAMPLES / "navigation" / "human_safety.vepl", vepl)
    cache = ArtifactCache(tmp_path / "cache")
    cache.automata(vepl, tmp_path / "before")
    vepl.write_text(vepl.read_text() + "\n// edited\n")
    text = vepl.read_text()
    vepl.write_text(text.replace("1.0", "1.5", 1) if "1.0" in text else text + "\n")
    generate_automata(vepl, tmp_path / "plain", replace=True)
    cache.automata(vepl, tmp_path / "after")
    assert files_of(tmp_path / "after") == files_of(tmp_path / "plain")


def test_another_rei_misses(tmp_path: Path, room_copy: Path,
                            monkeypatch: pytest.MonkeyPatch) -> None:
    cache = ArtifactCache(tmp_path / "cache")
    cache.world(room_copy, tmp_path / "first")
    key = cache.key("world", room_copy)
    monkeypatch.setattr(cache_module, "code_fingerprint", lambda: "an edited generator")
    assert cache.key("world", room_copy) != key
    cache.world(room_copy, tmp_path / "second")
    assert len(entries(cache.root)) == 2


@pytest.mark.parametrize("damage", ["truncated file", "no index", "corrupt index",
                                    "corrupt model", "emptied"])
def test_a_damaged_entry_is_never_served(tmp_path: Path, room_copy: Path,
                                         damage: str) -> None:
    cache = ArtifactCache(tmp_path / "cache")
    expected = generate_world(room_copy, tmp_path / "plain", replace=True)
    cache.world(room_copy, tmp_path / "first")
    (entry,) = entries(cache.root)
    if damage == "truncated file":  # a half-written artifact
        first = entry / "files" / "0"
        first.write_bytes(first.read_bytes()[:10])
    elif damage == "no index":
        (entry / "entry.json").unlink()
    elif damage == "corrupt index":
        (entry / "entry.json").write_text('{"format": ')
    elif damage == "corrupt model":
        (entry / "value.pickle").write_bytes(b"\x80\x05junk")
    else:
        shutil.rmtree(entry)
        entry.mkdir()
    assert cache.lookup(entry.name) is None
    assert cache.world(room_copy, tmp_path / "second") == expected
    assert files_of(tmp_path / "second") == files_of(tmp_path / "plain")
    assert cache.lookup(entry.name) is not None  # made again, whole


def test_a_cache_that_cannot_be_written_changes_nothing(tmp_path: Path,
                                                        room_copy: Path) -> None:
    blocked = tmp_path / "a-file"
    blocked.write_text("not a folder")
    cache = ArtifactCache(blocked / "cache")
    expected = generate_world(room_copy, tmp_path / "plain", replace=True)
    assert cache.world(room_copy, tmp_path / "out") == expected
    assert files_of(tmp_path / "out") == files_of(tmp_path / "plain")


def test_bad_input_is_reported_as_without_a_cache(tmp_path: Path, room_copy: Path) -> None:
    room_copy.write_text(room_copy.read_text().replace("at front", "at nowhere"))
    cache = ArtifactCache(tmp_path / "cache")
    with pytest.raises(LanguageError) as plain:
        generate_world(room_copy, tmp_path / "plain", replace=True)
    with pytest.raises(LanguageError) as cached:
        cache.world(room_copy, tmp_path / "out")
    assert str(cached.value) == str(plain.value)
    assert entries(cache.root) == []


def _world_files(args: tuple[str, str, str]) -> dict[str, bytes]:
    """In another process: the world the cache gives."""
    root, mission, out = args
    ArtifactCache(Path(root)).world(Path(mission), Path(out))
    return files_of(Path(out))


@pytest.mark.slow
def test_concurrent_writers_and_readers_agree(tmp_path: Path, room_copy: Path) -> None:
    root = tmp_path / "cache"
    generate_world(room_copy, tmp_path / "plain-old", replace=True)
    context = multiprocessing.get_context("spawn")
    with concurrent.futures.ProcessPoolExecutor(4, mp_context=context) as pool:
        # an empty cache, four writers of the same key at once
        jobs = [(str(root), str(room_copy), str(tmp_path / f"a{i}")) for i in range(8)]
        assert all(r == files_of(tmp_path / "plain-old") for r in pool.map(_world_files, jobs))
        assert len(entries(root)) == 1
        # the room changes: every process must see the new room, whoever replaces the entry
        room = room_copy.with_name("simple_wall.room")
        room.write_text(room.read_text().replace("tile 1.0", "tile 1.5"))
        generate_world(room_copy, tmp_path / "plain-new", replace=True)
        jobs = [(str(root), str(room_copy), str(tmp_path / f"b{i}")) for i in range(8)]
        assert all(r == files_of(tmp_path / "plain-new") for r in pool.map(_world_files, jobs))
    assert len(entries(root)) == 1
    assert not [p for p in root.glob("*/.*")], "temporary folders were left behind"


@pytest.mark.slow
def test_runs_with_the_cache_write_the_same_bytes(tmp_path: Path,
                                                  monkeypatch: pytest.MonkeyPatch) -> None:
    mission = EXAMPLES / "navigation" / "navigation.mission"
    run_into(mission, tmp_path / "plain", seed=3, duration=2.0)
    monkeypatch.setenv(CACHE_VARIABLE, str(tmp_path / "cache"))
    run_into(mission, tmp_path / "miss", seed=3, duration=2.0)
    run_into(mission, tmp_path / "hit", seed=3, duration=2.0)
    assert len(entries(tmp_path / "cache")) == 2  # the world and the automata
    plain = files_of(tmp_path / "plain")
    assert {"trace.jsonl", "summary.json", "events.csv", "world/world.json",
            "automata/automata.py"} <= set(plain)
    assert files_of(tmp_path / "miss") == plain
    assert files_of(tmp_path / "hit") == plain


def test_the_environment_names_the_cache_or_turns_it_off(
        monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    from rei.runtime.campaigns.execute import run_environment

    monkeypatch.delenv(CACHE_VARIABLE, raising=False)
    assert ArtifactCache.from_environment() is None
    assert run_environment(tmp_path / "c")[CACHE_VARIABLE] == str(tmp_path / "c")
    monkeypatch.setenv(CACHE_VARIABLE, "off")  # the user's word wins over the campaign's
    assert ArtifactCache.from_environment() is None
    assert run_environment(tmp_path / "c")[CACHE_VARIABLE] == "off"
    monkeypatch.setenv(CACHE_VARIABLE, str(tmp_path / "mine"))
    assert ArtifactCache.from_environment() == ArtifactCache(tmp_path / "mine")


@pytest.mark.slow
def test_a_campaign_generates_once_for_all_its_runs(tmp_path: Path,
                                                    monkeypatch: pytest.MonkeyPatch) -> None:
    import io

    from rei.runtime.campaigns import LocalEngine, plan_campaign, run_campaign

    monkeypatch.delenv(CACHE_VARIABLE, raising=False)
    plan = plan_campaign([EXAMPLES / "simple_wall"], repeat=3, seed=4, duration=1.0)
    result = run_campaign(plan, tmp_path / "c", LocalEngine(2), {"command": ["test"]},
                          stream=io.StringIO())
    assert [r.status for r in result.records] == ["ran"] * 3
    assert len(entries(tmp_path / "c" / "cache")) == 2  # one world, one set of automata
    worlds = [files_of(tmp_path / "c" / "runs" / r.spec.run_id / "world")
              for r in result.records]
    assert worlds[0] and worlds[0] == worlds[1] == worlds[2]
