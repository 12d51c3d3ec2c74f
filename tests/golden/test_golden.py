"""Every target's output on every example equals its golden files, byte for byte."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.conftest import REPO
from tests.golden.regen import GOLDEN, REGEN_COMMAND, case_dir, cases, generated, stored

CASES = cases()


@pytest.mark.parametrize("path,target", CASES, ids=[f"{p.name}-{t}" for p, t in CASES])
def test_output_matches_golden_files(path: Path, target: str) -> None:
    folder = case_dir(path, target)
    if not folder.is_dir():
        pytest.fail(f"no golden files for target '{target}' on {path.name} in {folder}; "
                    f"run `{REGEN_COMMAND}` and review the new files")
    expected = stored(folder)
    actual = generated(path, target)
    assert sorted(actual) == sorted(expected), (
        f"target '{target}' on {path.name} writes other files than its goldens; "
        f"if intended, run `{REGEN_COMMAND}`")
    for rel in sorted(actual):
        assert actual[rel] == expected[rel], (
            f"{folder / rel} differs from what target '{target}' generates now; "
            f"if intended, run `{REGEN_COMMAND}` and review the diff")


def test_every_golden_folder_belongs_to_a_case() -> None:
    known = {case_dir(p, t) for p, t in CASES}
    folders = {f for f in GOLDEN.glob("*/*/*") if f.is_dir()}
    assert sorted(folders - known) == [], f"stale golden folders; run `{REGEN_COMMAND}`"


def test_every_target_has_golden_cases_for_the_example_kinds_it_accepts() -> None:
    from rei.generators.targets import available_targets
    from tests.golden.regen import inputs

    suffixes = {p.suffix for p in inputs()}
    expected = {n for n, t in available_targets().items() if suffixes & set(t.accepts)}
    assert {".room", ".mission"} <= suffixes
    assert {t for _, t in CASES} == expected


def test_golden_files_hold_no_absolute_paths() -> None:
    offenders = [p for p in GOLDEN.rglob("*") if p.is_file() and p.suffix != ".py"
                 and (str(REPO).encode() in p.read_bytes() or b"/tmp/" in p.read_bytes())]
    assert offenders == []
