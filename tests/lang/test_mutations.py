"""Random mutations of valid files give a valid model or clean, located errors — never an
exception, and every diagnostic names a documented rule and a position inside the file."""

from __future__ import annotations

from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rei.lang.rules import RULE_IDS
from rei.lang.workspace import Workspace
from tests.conftest import EXAMPLES

ROOM = (EXAMPLES / "navigation" / "navigation.room").read_text(encoding="utf-8")
MISSION = (EXAMPLES / "navigation" / "navigation.mission").read_text(encoding="utf-8")
TOKENS = ["floor", "wall", "grid", "{", "}", "\"", ":", "on", "at", "heading", "1e999", "-5",
          "nan", "trajectory", "loop", "total", "lab_2_6", "start", "elevator", "robot", "\x00",
          "é", "\n", "legend", "=", "goal", "cycles", "0"]


@st.composite
def mutated(draw, text: str) -> str:  # type: ignore[no-untyped-def]
    for _ in range(draw(st.integers(min_value=1, max_value=4))):
        pos = draw(st.integers(min_value=0, max_value=len(text)))
        action = draw(st.sampled_from(["delete", "insert", "replace", "swap-line"]))
        if action == "delete":
            text = text[:pos] + text[pos + draw(st.integers(1, 12)):]
        elif action == "insert":
            text = text[:pos] + " " + draw(st.sampled_from(TOKENS)) + " " + text[pos:]
        elif action == "replace":
            text = text[:pos] + draw(st.text(max_size=3)) + text[pos + 3:]
        else:
            lines = text.splitlines()
            if len(lines) > 2:
                i = draw(st.integers(0, len(lines) - 2))
                lines[i], lines[i + 1] = lines[i + 1], lines[i]
                text = "\n".join(lines)
    return text


def check_clean(path: Path, text: str) -> None:
    lines = max(1, text.count("\n") + 1)
    for d in Workspace().check(path):
        assert d.rule in RULE_IDS
        assert d.message
        if d.span.file == str(path):
            assert 1 <= d.span.line <= lines


SETTINGS = settings(max_examples=120, deadline=None,
                    suppress_health_check=[HealthCheck.function_scoped_fixture])


@SETTINGS
@given(text=mutated(ROOM))
def test_mutated_rooms_never_crash(tmp_path: Path, text: str) -> None:
    path = tmp_path / "m.room"
    path.write_bytes(text.encode("utf-8", "surrogatepass"))
    check_clean(path, text)


@SETTINGS
@given(room=mutated(ROOM), mission=mutated(MISSION))
def test_mutated_missions_never_crash(tmp_path: Path, room: str, mission: str) -> None:
    (tmp_path / "navigation.room").write_bytes(room.encode("utf-8", "surrogatepass"))
    path = tmp_path / "m.mission"
    path.write_bytes(mission.encode("utf-8", "surrogatepass"))
    check_clean(path, mission)
