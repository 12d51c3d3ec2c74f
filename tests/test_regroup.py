"""scripts/regroup.py migrates a user's code from the import paths before issue 34's
regrouping: every rewritten import resolves in this REI, names included."""

from __future__ import annotations

import ast
import importlib
import importlib.util
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]

OLD = '''\
"""A user's controller and script, written against REI before the regrouping."""
from rei.runtime.robot.protocol import Controller, NavGoal
from rei.runtime.commands.run import run_into, print_results
from rei.runtime.collector import read_trace, load_monitor_config
from rei.runtime.animator import animator as paths
from rei.runtime.animator.reactive import Agent, SocialForce, YieldRule, wall_normals
from rei.runtime.monitor.model import RuntimeModel, FloorMap
from rei.runtime.report.run_page import write_run_page
from rei.runtime import cli


def later() -> None:
    from rei.runtime.campaign.store import RunRecord, CampaignStore  # inside a function too


SPEC = "rei.runtime.robot.reference:ReferenceNavigator"
'''


def test_old_imports_are_rewritten_to_ones_that_resolve(tmp_path: Path) -> None:
    user = tmp_path / "mine.py"
    user.write_text(OLD, encoding="utf-8")
    done = subprocess.run([sys.executable, str(REPO / "scripts" / "regroup.py"), str(tmp_path)],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert "1 files rewritten" in done.stderr
    text = user.read_text(encoding="utf-8")
    assert "rei.runtime.robot.navigator.reference:ReferenceNavigator" in text
    imports = [n for n in ast.walk(ast.parse(text)) if isinstance(n, ast.ImportFrom)]
    assert len(imports) >= 9
    for node in imports:
        assert node.module is not None
        module = importlib.import_module(node.module)
        for alias in node.names:
            assert hasattr(module, alias.name) or importlib.util.find_spec(
                f"{node.module}.{alias.name}") is not None, (node.module, alias.name)
    assert "from rei.runtime.runs.session import run_into" in text
    assert "from rei.runtime.simulation.animator import engine as paths" in text


def test_a_file_without_old_imports_is_left_as_it_is(tmp_path: Path) -> None:
    user = tmp_path / "new.py"
    text = "from rei.runtime.runs import run_into\n"
    user.write_text(text, encoding="utf-8")
    done = subprocess.run([sys.executable, str(REPO / "scripts" / "regroup.py"), str(user)],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0 and "0 files rewritten" in done.stderr
    assert user.read_text(encoding="utf-8") == text
