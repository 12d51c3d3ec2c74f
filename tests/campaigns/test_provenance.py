"""Provenance of a session: versions, command line, and the controller's revision."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from rei.runtime.campaigns.provenance import collect, controller_revision, git_revision


def test_session_provenance_names_versions_and_command() -> None:
    data = collect(["rei", "campaign", "x"], {"engine": "local", "workers": 2}, None, "v1.2")
    assert data["command"] == ["rei", "campaign", "x"]
    assert data["python"] == sys.version.split()[0]
    assert data["pybullet"] and data["rei"]
    assert data["controller_version"] == "v1.2"


def test_controller_revision_from_its_git_work_tree(tmp_path: Path,
                                                    monkeypatch: pytest.MonkeyPatch) -> None:
    git = ["git", "-C", str(tmp_path), "-c", "user.name=t", "-c", "user.email=t@t"]
    subprocess.run(["git", "init", "-q", str(tmp_path)], check=True)
    (tmp_path / "my_robot.py").write_text("class Robot: ...\n")
    subprocess.run([*git, "add", "my_robot.py"], check=True)
    subprocess.run([*git, "commit", "-q", "-m", "robot"], check=True)
    head = subprocess.run([*git, "rev-parse", "HEAD"], capture_output=True, text=True,
                          check=True).stdout.strip()
    monkeypatch.syspath_prepend(str(tmp_path))
    assert controller_revision("my_robot:Robot") == head
    assert git_revision(tmp_path / "my_robot.py") == head
    (tmp_path / "my_robot.py").write_text("class Robot: pass\n")
    assert controller_revision("my_robot:Robot") == head + "+dirty"
    assert controller_revision("reference") is None
