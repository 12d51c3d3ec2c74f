"""Golden files: the module generated from the default .vepl, and the event log of the
synthetic teleop wall drive. Regenerate after an intended change with

    REI_REGENERATE_GOLDEN=1 .venv/bin/python -m pytest tests/vepl/test_golden.py

and review the diff like code."""

from __future__ import annotations

import os
from pathlib import Path

from rei.generators.targets.rx import render_module
from rei.lang.vepl import load_vepl
from tests.observation.helpers import monitor
from tests.observation.streams import drive, straight, wall

GOLDEN = Path(__file__).parent / "golden"


def _compare(name: str, text: str) -> None:
    path = GOLDEN / name
    if os.environ.get("REI_REGENERATE_GOLDEN"):
        path.write_text(text, encoding="utf-8")
    assert path.read_text(encoding="utf-8") == text, f"{name} changed; see the module docstring"


def test_generated_default_automata() -> None:
    _compare("default_automata.py.txt", render_module(load_vepl(), "default.vepl"))


def test_teleop_wall_event_log(tmp_path: Path) -> None:
    poses = straight(0.0, 1.45, 30) + straight(1.45, 0.0, 30)
    h, samples = drive([wall("wall_e", 2.0, 0.0)], poses)
    monitor(h, samples, tmp_path)
    _compare("teleop_wall_events.csv", (tmp_path / "events.csv").read_text(encoding="utf-8"))
