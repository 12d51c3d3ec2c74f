"""The package stays typed (`mypy --strict`) and linted (ruff): scripts/typecheck's two checks.

Both tools come from the `test` extra, so nothing here is skipped. The checks run through
scripts/typecheck, the same script developers run, with this interpreter as its python.
These tests must never change a file of the checkout.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys

import pytest

from tests.conftest import REPO

ERROR = re.compile(r"^\S+:\d+: error: .*$", re.MULTILINE)


def typecheck(check: str) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "PYTHON": sys.executable}
    return subprocess.run(["bash", str(REPO / "scripts" / "typecheck"), check], cwd=REPO,
                          env=env, capture_output=True, text=True, check=False)


@pytest.mark.slow
def test_mypy_strict_reports_no_errors() -> None:
    done = typecheck("mypy")
    errors = ERROR.findall(done.stdout)
    assert errors == [], f"{len(errors)} mypy errors:\n" + "\n".join(errors)
    assert done.returncode == 0, done.stdout + done.stderr
    # Not vacuous: mypy really looked at the whole `rei` package.
    checked = re.search(r"Success: no issues found in (\d+) source files", done.stdout)
    assert checked is not None, done.stdout + done.stderr
    assert int(checked.group(1)) > 100


def test_ruff_reports_no_errors() -> None:
    done = typecheck("ruff")
    assert done.returncode == 0, done.stdout + done.stderr
    assert "All checks passed!" in done.stdout
