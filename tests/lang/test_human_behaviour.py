"""`behaviour` of a human: parsed, checked with a located 'did you mean', carried into the
concrete model and world.json, offered by the editor's completion."""

from __future__ import annotations

import json
from pathlib import Path

from rei.generators.concrete.build import concretise_room
from rei.generators.output import write_tree
from rei.generators.targets import GenerationRequest, get_target
from rei.lang.lsp.completion import room_completions
from rei.lang.room.model import BEHAVIOURS
from rei.lang.workspace import Workspace, load_room
from rei.runtime.artifacts.world import load_manifest

ROOM = """room walkers {
    grid g {
        "#######"
        "#.....#"
        "#######"
    }
    robot r : turtlebot3_waffle on g_1_1
    human a on g_1_3 trajectory total 4 { g_1_3 g_1_5 } behaviour BEHAVIOUR
    human b on g_1_4 trajectory total 4 { g_1_4 g_1_2 }
}
"""


def _write(tmp_path: Path, behaviour: str) -> Path:
    path = tmp_path / "walkers.room"
    path.write_text(ROOM.replace("BEHAVIOUR", behaviour), encoding="utf-8")
    return path


def test_behaviour_reaches_the_concrete_model_and_world_json(tmp_path: Path) -> None:
    path = _write(tmp_path, "social")
    doc = load_room(path, Workspace())
    assert doc.ok and doc.room is not None
    assert [o.behaviour for o in doc.room.objects if o.role == "human"] == ["social",
                                                                          "scripted"]
    world = concretise_room(doc)
    assert [h.behaviour for h in world.humans] == ["social", "scripted"]
    folder = tmp_path / "world"
    write_tree(get_target("pybullet").generate(GenerationRequest(path, world, None)), folder)
    manifest = load_manifest(folder)
    assert [b.behaviour for b in manifest.objects] == ["social", "scripted"]
    assert json.loads((folder / "world.json").read_text())["version"] == 3


def test_a_misspelt_behaviour_is_located_with_did_you_mean(tmp_path: Path) -> None:
    path = _write(tmp_path, "yeilding")
    [problem] = Workspace().check(path)
    assert problem.rule == "HUMAN-BEHAVIOUR"
    assert (problem.span.file, problem.span.line) == (str(path), 8)
    assert "expected a behaviour (scripted, yielding, social), found 'yeilding'" in \
        problem.message
    assert "did you mean 'yielding'?" in problem.message
    assert f"{path}:8:" in str(problem)


def test_completion_after_behaviour_offers_the_behaviours() -> None:
    offered = room_completions("room r {\n human h on f trajectory total 3 { f g } behaviour ",
                               None, None)
    assert [c.label for c in offered] == list(BEHAVIOURS)
    after_human = "room r {\n human h on f trajectory total 3 { f g } "
    assert "behaviour" in [c.label for c in room_completions(after_human, None, None)]
    # only a human's statement takes one, so it is not a statement of its own
    keywords = [c.label for c in room_completions("room r {\n  ", None, None)]
    assert "behaviour" not in keywords and "human" in keywords
