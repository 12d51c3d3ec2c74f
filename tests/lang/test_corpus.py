"""The invalid-file corpus: one file per rule; the line marked `//! RULE` (or `#! RULE`) must
report that rule, through the same Workspace the command line and the editor use."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from rei.lang.rules import RULE_IDS
from rei.lang.workspace import Workspace

CORPUS = Path(__file__).parent / "corpus"
VEPL_CORPUS = Path(__file__).parent.parent / "vepl" / "corpus"
MARK = re.compile(r"(?://|#)! ([A-Z-]+)")
HELPERS = {"valid.room", "bad_types.toml", "__init__.py"}
CORPUS_FILES = sorted(p for folder in (CORPUS, VEPL_CORPUS) for p in folder.iterdir()
                      if p.name not in HELPERS and p.is_file())

# Rules whose inputs cannot be written as a corpus file; tests/lang/test_input_edges.py covers
# them (INTERNAL: tests/lsp/test_lsp_robustness.py), and tests/observation/test_user_functions.py
# VEPL-FUNCTION (it needs a Python module), tests/simulation/test_collected_data.py VEPL-DATA (it
# needs a mission or a trace beside the .vepl).
COVERED_ELSEWHERE = {"INPUT-READ", "INPUT-KIND", "INPUT-EMPTY", "INPUT-SIZE", "INPUT-ENCODING",
                     "SYNTAX-DEPTH", "INTERNAL", "VEPL-FUNCTION", "VEPL-DATA",
                     # checked by `rei run` against the run's specification and --fault
                     # options, not in one file: tests/simulation/test_fault_runs.py
                     "FAULT-NAME", "FAULT-SIGNAL", "FAULT-WINDOW"}


def expectation(path: Path) -> tuple[str, int]:
    for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), start=1):
        match = MARK.search(line)
        if match:
            return match.group(1), number
    raise AssertionError(f"{path.name} has no //! RULE marker")


@pytest.mark.parametrize("path", CORPUS_FILES, ids=lambda p: p.name)
def test_corpus_file_reports_its_rule_at_its_line(path: Path) -> None:
    rule, line = expectation(path)
    assert path.stem == rule, "a corpus file is named after the rule it breaks"
    diagnostics = Workspace().check(path)
    found = [(d.rule, d.span.line) for d in diagnostics]
    assert (rule, line) in found, f"expected {rule} at line {line}, got {found}"
    for d in diagnostics:
        assert d.rule in RULE_IDS, f"{d.rule} is not documented in rei.lang.rules"
        assert d.span.file == str(path) or d.span.file.endswith(".toml")
        assert "expected" in d.message and "found" in d.message


def test_every_rule_has_a_corpus_file_or_a_focused_test() -> None:
    in_corpus = {expectation(p)[0] for p in CORPUS_FILES}
    missing = RULE_IDS - COVERED_ELSEWHERE - in_corpus
    assert not missing, sorted(missing)


def test_all_problems_of_a_file_are_reported_at_once(write) -> None:  # type: ignore[no-untyped-def]
    path = write("many.room", """room many {
    grid g { "####" "#..#" "####" }
    robot r : turtlebot3_wafle on g_1_1
    object a : tabel on g_1_2
    object b : box on nowhere
    tile inf
}
""")
    rules = [d.rule for d in Workspace().check(path)]
    assert rules.count("CATALOGUE-TYPE") == 2
    assert "REF-UNRESOLVED" in rules and "NUM-FINITE" in rules


def test_did_you_mean_names_the_closest_floor(write) -> None:  # type: ignore[no-untyped-def]
    path = write("typo.room", """room typo {
    floor kitchen { right hallway }
    floor hallway
    robot r : turtlebot3_waffle on kitchn
}
""")
    [diagnostic] = Workspace().check(path)
    assert diagnostic.rule == "REF-UNRESOLVED"
    assert "did you mean 'kitchen'?" in diagnostic.message
    assert (diagnostic.span.line, diagnostic.span.col) == (4, 36)


def test_command_line_reports_corpus_with_exit_2(capsys) -> None:  # type: ignore[no-untyped-def]
    from rei.lang.cli import main

    assert main(["check", str(CORPUS / "REF-UNRESOLVED.room")]) == 2
    out = capsys.readouterr().out
    assert re.search(r"REF-UNRESOLVED\.room:9:23: REF-UNRESOLVED: expected the name of a floor, "
                     r"found 'g_1_9'; did you mean", out), out
