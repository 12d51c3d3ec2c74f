"""The .vepl language: the default specification, the thesis's patterns as written, operator
precedence, located semantic errors (one corpus file per rule) and `rei-gen check`."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from rei.lang.cli import main as rei_gen
from rei.lang.errors import LanguageError
from rei.lang.source import SourceText
from rei.lang.vepl import DEFAULT_VEPL, analyse_vepl, load_vepl
from rei.lang.vepl import model as m
from rei.lang.workspace import Workspace

CORPUS = Path(__file__).parent / "corpus"
MARK = re.compile(r"//! ([A-Z-]+)")
VEPL_RULES = ("VEPL-UNKNOWN", "VEPL-ARITY", "VEPL-ORDER", "VEPL-WINDOW", "VEPL-TYPE",
              "VEPL-NOT-WINDOW", "VEPL-MULTIPLICITY", "VEPL-CYCLE", "VEPL-PARAM",
              "VEPL-LIMIT")

TABLE_3 = {"SIG_MISSION_BEGIN": 20, "SIG_MISSION_END": 20, "SIG_MISSION_TASK_START": 5,
           "SIG_MISSION_TASK_FAIL": -100, "SIG_MISSION_TASK_SUCCESS": 10,
           "SIG_GEOM_FAR_TRANSIT_CLOSE": -2, "SIG_GEOM_CLOSE_TRANSIT_FAR": 1,
           "SIG_GEOM_CLOSE_TRANSIT_COLLISION": -10, "SIG_GEOM_COLLISION_TRANSIT_CLOSE": 1,
           "SIG_LASER_CLOSE_TRANSIT_COLLISION": -5, "SIG_LASER_COLLISION_TRANSIT_CLOSE": 1}


def spec_of(text: str) -> m.Specification:
    doc = analyse_vepl(SourceText("t.vepl", text))
    assert doc.ok, [str(d) for d in doc.diagnostics]
    assert doc.spec is not None
    return doc.spec


def diagnostics_of(text: str) -> list[tuple[str, int]]:
    doc = analyse_vepl(SourceText("t.vepl", text))
    return [(d.rule, d.span.line) for d in doc.diagnostics]


def test_default_specification_has_table_3_and_the_5_1_2_requirements() -> None:
    spec = load_vepl()
    table_3 = {s.name: s.utility for s in spec.signals if s.name in TABLE_3}
    assert table_3 == TABLE_3
    assert [r.name for r in spec.requirements] == [
        "GEOM_CLOSE_LASER_CORRECT", "GEOM_COLLISION_LASER_CORRECT", "MISSION_SIMPLE",
        "MISSION_SEQUENCE", "MISSION_SEQUENCE_CYCLE", "MISSION_WITH_HUMAN_TRAJECTORY",
        "MISSION_GOALS_REACHED", "GOAL_HEADING", "SPEED_LIMIT", "HUMAN_SLOW_ZONE",
        "NO_ROBOT_COLLISION", "EFFICIENT_PATH", "TIME_TO_GOAL", "NO_SPIN_AT_GOAL", "SETTLE",
        "SMOOTH_MOTION", "REACTION_TIME", "COMMAND_ACCELERATION", "COMMAND_CHATTER",
        "COMMAND_AT_REST"]
    assert spec.parameters["N_COLLISION"] == 1
    by_name = {r.name: r for r in spec.requirements}
    human = by_name["MISSION_WITH_HUMAN_TRAJECTORY"]
    assert human.clauses == (m.CountBound("humanCollision", "<", 1.0),)
    # the 5.1.2 set is kept as written; premises only make absent scenarios not applicable
    assert human.premise == "humansPresent"
    assert by_name["GOAL_HEADING"].premise == "missionHasHeadings"
    # issue 22: reacting to a hazard the laser shows is asked only where there can be one
    assert by_name["REACTION_TIME"].premise == "hazardsPresent"
    assert by_name["REACTION_TIME"].clauses == (
        m.Whenever("hazardSensedFast", ("commandsSlow",), 0.3),)
    # thesis 5.1.2's GIVEN: a pair of neighbouring goals; a back-and-forth cycle (g1, g2)*
    assert by_name["MISSION_SIMPLE"].premise == "neighbouringGoalPair"
    assert by_name["MISSION_SEQUENCE_CYCLE"].premise == "backAndForth"
    queries = {q.name: q for q in spec.queries}
    assert queries["neighbouringGoalPair"].params == queries["backAndForth"].params == ()
    # the two no longer compile to the same clauses under the same premise
    simple, cycle = by_name["MISSION_SIMPLE"], by_name["MISSION_SEQUENCE_CYCLE"]
    assert (simple.clauses, simple.premise) != (cycle.clauses, cycle.premise)


def test_thesis_pattern_parses_and_means_a_windowed_repeated_sequence() -> None:
    spec = spec_of("""
query findFarObject() { laser_min > 1 }
query findCloseToObject() { laser_min <= 1 }
queryEvent notAtomicFarFromObject() as findFarObject lost
queryEvent atomicCloseToObject() as findCloseToObject found
complexEvent transitionFarToClose(){ as (notAtomicFarFromObject -> atomicCloseToObject){+}[1000]
context immediate }
""")
    ce = spec.complex_events[0]
    assert ce.context == "immediate"
    assert ce.pattern == m.EvWindow(m.EvRepeat(m.EvSeq((m.EvRef("notAtomicFarFromObject"),
                                                        m.EvRef("atomicCloseToObject"))),
                                               1, False), 1.0)


@pytest.mark.parametrize("text, expected", [
    # OR is loosest, then AND, then ->, then NOT, then postfix
    ("a OR b AND c", m.EvOr((m.EvRef("a"), m.EvAnd((m.EvRef("b"), m.EvRef("c")))))),
    ("a AND b -> c", m.EvAnd((m.EvRef("a"), m.EvSeq((m.EvRef("b"), m.EvRef("c")))))),
    ("NOT a -> b[5]", m.EvSeq((m.EvNot(m.EvRef("a")), m.EvWindow(m.EvRef("b"), 0.005)))),
    ("(a OR b){2}", m.EvRepeat(m.EvOr((m.EvRef("a"), m.EvRef("b"))), 2, True)),
    ("a{*} -> b", m.EvSeq((m.EvRepeat(m.EvRef("a"), 0, False), m.EvRef("b")))),
])
def test_event_operator_precedence(text: str, expected: m.Pattern) -> None:
    spec = spec_of(f"""query q() {{ laser_min < 1 }}
queryEvent a() as q found
queryEvent b() as q lost
queryEvent c() as q found
complexEvent x(){{ as {text} context chronicle }}
""")
    assert spec.complex_events[0].pattern == expected
    assert spec.complex_events[0].context == "chronicle"


def test_contexts_parse() -> None:
    spec = spec_of("""query q() { laser_min < 1 }
queryEvent a() as q found
complexEvent s(){ as a -> a context strict immediate }
complexEvent d(){ as a -> a }
""")
    assert [c.context for c in spec.complex_events] == ["strict", "immediate"]


def test_queries_are_ordered_after_what_they_find() -> None:
    spec = spec_of("""query far() { neg find close(_) }
query close(o: object[wall, human]) { distance(robot, o) < 0.5 }
""")
    assert [q.name for q in spec.queries] == ["close", "far"]
    assert spec.queries[0].params == (m.QueryParam("o", "object", ("wall", "human")),)


CORPUS_FILES = sorted(CORPUS.glob("*.vepl"))


@pytest.mark.parametrize("path", CORPUS_FILES, ids=lambda p: p.name)
def test_corpus_file_reports_its_rule_at_its_line(path: Path) -> None:
    lines = path.read_text(encoding="utf-8").splitlines()
    rule, line = next((mk.group(1), i) for i, text in enumerate(lines, 1)
                      if (mk := MARK.search(text)))
    assert path.stem == rule
    found = [(d.rule, d.span.line) for d in Workspace().check(path)]
    assert (rule, line) in found, found
    for d in Workspace().check(path):
        assert "expected" in d.message and "found" in d.message


def test_every_vepl_rule_has_a_corpus_file() -> None:
    assert {p.stem for p in CORPUS_FILES} == set(VEPL_RULES)


def test_unknown_names_get_did_you_mean() -> None:
    doc = analyse_vepl(SourceText("t.vepl", "parameters { eps_close = 1 }\n"
                                            "query q() { laser_min < eps_clse }\n"))
    assert "did you mean 'eps_close'" in doc.diagnostics[0].message


def test_a_premise_must_be_a_query_located_with_did_you_mean() -> None:
    doc = analyse_vepl(SourceText("t.vepl", "query humansPresent() { humans > 0 }\n"
                                            "queryEvent e() as humansPresent found\n"
                                            'requirement R "r" when humansPresnt { never e }\n'))
    (problem,) = doc.diagnostics
    assert (problem.rule, problem.span.line) == ("VEPL-UNKNOWN", 3)
    assert "'when' expected a query, found 'humansPresnt'" in problem.message
    assert "did you mean 'humansPresent'" in problem.message
    premised = spec_of("query humansPresent() { humans > 0 }\n"
                       "queryEvent e() as humansPresent found\n"
                       'requirement R "r" when humansPresent { never e }\n')
    assert premised.requirements[0].premise == "humansPresent"


def test_all_problems_are_reported_at_once() -> None:
    found = diagnostics_of("""query q() { laser_min < 1 }
queryEvent a() as nothing found
complexEvent x(){ as a[-1] }
signal S on nowhere utility 1
requirement R { never T }
""")
    assert {r for r, _ in found} >= {"VEPL-UNKNOWN"}
    assert len(found) >= 3


def test_non_finite_numbers_are_rejected() -> None:
    assert ("NUM-FINITE", 1) in diagnostics_of("parameters { eps_close = inf }\n")


def test_syntax_error_is_located() -> None:
    assert diagnostics_of("query q( { }\n")[0][0] == "SYNTAX"


def test_rei_gen_check_accepts_the_default_and_rejects_the_corpus(
        capsys: pytest.CaptureFixture[str]) -> None:
    assert rei_gen(["check", str(DEFAULT_VEPL)]) == 0
    assert rei_gen(["check", str(CORPUS / "VEPL-ORDER.vepl")]) == 2
    assert "VEPL-ORDER" in capsys.readouterr().out


def test_load_vepl_raises_with_every_problem() -> None:
    with pytest.raises(LanguageError) as info:
        load_vepl(CORPUS / "VEPL-CYCLE.vepl")
    assert info.value.diagnostics[0].rule == "VEPL-CYCLE"
