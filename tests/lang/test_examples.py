"""Every bundled example checks clean, through the API and the command line."""

from __future__ import annotations

from pathlib import Path

import pytest

from rei.lang.cli import main as rei_gen
from rei.lang.workspace import Workspace
from tests.conftest import example_files

EXAMPLE_FILES = example_files(".room") + example_files(".mission")


@pytest.mark.parametrize("path", EXAMPLE_FILES, ids=lambda p: p.name)
def test_example_checks_clean(path: Path) -> None:
    assert Workspace().check(path) == []


def test_examples_cover_the_thesis_scenarios() -> None:
    names = {p.stem for p in EXAMPLE_FILES}
    assert {"simple_wall", "navigation", "small_dense", "medium_sparse"} <= names


def test_check_command_accepts_the_examples_folder(examples_dir: Path, capsys) -> None:  # type: ignore[no-untyped-def]
    assert rei_gen(["check", str(examples_dir)]) == 0
    assert capsys.readouterr().out == ""
