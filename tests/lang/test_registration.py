"""The languages are registered with textX: `textx list-languages` and `textx check` see them."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

from textx import metamodel_for_file

from tests.conftest import EXAMPLES, REPO


def textx_command() -> list[str]:
    exe = Path(sys.executable).parent / "textx"
    return [str(exe)] if exe.exists() else [shutil.which("textx") or "textx"]


def test_list_languages_shows_rei() -> None:
    proc = subprocess.run([*textx_command(), "list-languages"], capture_output=True, text=True,
                          check=True)
    out = proc.stdout + proc.stderr  # textX prints the table on stderr
    assert "rei-room" in out and "rei-mission" in out


def test_textx_check_accepts_an_example_and_rejects_a_corpus_file() -> None:
    ok = subprocess.run([*textx_command(), "check",
                         str(EXAMPLES / "navigation" / "navigation.mission")],
                        capture_output=True, text=True, check=False)
    assert ok.returncode == 0, ok.stdout + ok.stderr
    bad = subprocess.run([*textx_command(), "check",
                          str(REPO / "tests" / "lang" / "corpus" / "REF-UNRESOLVED.room")],
                         capture_output=True, text=True, check=False)
    assert bad.returncode != 0
    assert "REF-UNRESOLVED" in bad.stdout + bad.stderr


def test_metamodel_for_file_resolves_by_suffix() -> None:
    mm = metamodel_for_file("x.room")
    model = mm.model_from_str("room r { floor a }")
    assert model.name == "r"
