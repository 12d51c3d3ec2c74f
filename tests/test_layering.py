"""The house's rules hold: pyproject.toml's import-linter contracts (runtime's wings import
downward only, the judging side never reaches pybullet or the loop, the robot side never the
simulator, no cycle between sibling packages), checked by `lint-imports` over every import,
those inside functions too; and a wrong import, direct or indirect, breaks them."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
LINT = Path(sys.executable).with_name("lint-imports")
FOLDERS = {"lang": "rei_lang", "grammars": "grammars", "generators": "generators",
           "catalogue": "catalogue"}

pytestmark = pytest.mark.skipif(not LINT.exists(), reason="import-linter is in the test extra")


def lint(root: Path, env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run([str(LINT), "--no-cache", "--config", str(root / "pyproject.toml")],
                          cwd=root,
                          env=env, capture_output=True, text=True, timeout=300)


def test_the_house_keeps_its_rules() -> None:
    done = lint(REPO)
    assert done.returncode == 0, done.stdout + done.stderr
    assert "0 broken" in done.stdout


@pytest.fixture(scope="module")
def house(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict[str, str]]:
    """A copy of the runtime in the installed layout (rei/runtime, the other folders linked),
    found first on PYTHONPATH, so a test can break it without touching the checkout."""
    root = tmp_path_factory.mktemp("house")
    (root / "rei").mkdir()
    shutil.copytree(REPO / "runtime", root / "rei" / "runtime",
                    ignore=shutil.ignore_patterns("__pycache__"))
    for name, folder in FOLDERS.items():
        (root / "rei" / name).symlink_to(REPO / folder)
    shutil.copy(REPO / "pyproject.toml", root / "pyproject.toml")
    env = {**os.environ, "PYTHONPATH": str(root)}
    return root, env


def lint_broken(house: tuple[Path, dict[str, str]], module: str, line: str
                ) -> subprocess.CompletedProcess[str]:
    """`lint-imports` on the copy with ``line`` added at the end of ``module`` (a path under
    rei/runtime), the module restored afterwards."""
    root, env = house
    path = root / "rei" / "runtime" / module
    before = path.read_text(encoding="utf-8")
    path.write_text(before + line, encoding="utf-8")
    try:
        return lint(root, env)
    finally:
        path.write_text(before, encoding="utf-8")


def test_a_copy_of_the_house_keeps_its_rules(house: tuple[Path, dict[str, str]]) -> None:
    root, env = house
    done = lint(root, env)
    assert done.returncode == 0, done.stdout + done.stderr


def test_an_upward_import_inside_a_function_breaks_the_layers(
        house: tuple[Path, dict[str, str]]) -> None:
    done = lint_broken(house, "robot/teleop.py", "\n\ndef _wrong() -> None:\n"
                       "    from rei.runtime.commands import cli  # noqa: F401\n")
    assert done.returncode != 0
    assert "downward only" in done.stdout and "BROKEN" in done.stdout
    assert "rei.runtime.robot.teleop -> rei.runtime.commands" in done.stdout


def test_the_judge_reaching_pybullet_through_another_module_breaks_its_contract(
        house: tuple[Path, dict[str, str]]) -> None:
    """observation may import a contract of the simulation (layers allow it), but once that
    module imports pybullet, the observation side reaches it indirectly and fails."""
    done = lint_broken(house, "simulation/faults/stage.py",
                       "\n\nimport pybullet  # noqa: E402,F401\n")
    assert done.returncode != 0
    broken = done.stdout.split("Broken contracts")[1]
    assert "never reach pybullet" in broken
    assert "rei.runtime.simulation.faults.stage -> pybullet" in broken
    assert "downward only" not in broken  # the layers themselves are kept


def test_a_cycle_between_sibling_packages_breaks_its_contract(
        house: tuple[Path, dict[str, str]]) -> None:
    done = lint_broken(house, "observation/automata/records.py", "\n\ndef _wrong() -> None:\n"
                       "    from rei.runtime.observation import monitor  # noqa: F401\n")
    assert done.returncode != 0
    assert "No cycles are allowed in rei.runtime.observation" in done.stdout
