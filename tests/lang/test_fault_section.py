"""The .mission fault section and ``--fault`` (issue 17): syntax, located checks, printing
back, the mission model carrying it to the concrete mission, and the editor's completion."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rei.generators.concrete.build import load_concrete_mission
from rei.lang.errors import LanguageError
from rei.lang.lsp.completion import mission_completions
from rei.lang.mission.faults import (
    FAULT_KINDS,
    KINDS,
    Activation,
    FaultDefinition,
    parse_fault_option,
)
from rei.lang.printer import print_mission
from rei.lang.workspace import Workspace
from tests.conftest import EXAMPLES

ROOM = (EXAMPLES / "simple_wall" / "simple_wall.room").read_text(encoding="utf-8")


def mission(tmp_path: Path, faults: str) -> Path:
    (tmp_path / "simple_wall.room").write_text(ROOM, encoding="utf-8")
    path = tmp_path / "m.mission"
    path.write_text('mission m in "simple_wall.room" {\n    fault {\n' + faults
                    + "\n    }\n    goal a at start\n    goal b at front\n}\n", encoding="utf-8")
    return path


def problems(tmp_path: Path, faults: str) -> list[tuple[str, int, int, str]]:
    path = mission(tmp_path, faults)
    return [(d.rule, d.span.line, d.span.col, d.message) for d in Workspace().check(path)]


def test_a_valid_section_reaches_the_concrete_mission(tmp_path: Path) -> None:
    path = mission(tmp_path, """        laser_poisson rate 20 gain 0.5 period 1 width 0.01
        laser_dropout as near share 0.3 when SIG_GEOM_FAR_TRANSIT_CLOSE for 2
        odom_jump dx 0.3 dyaw -10 from 30 to 31
        cmd_drop share 0.1 until SIG_MISSION_END""")
    assert problems(tmp_path, path.read_text().split("fault {\n")[1].split("\n    }")[0]) == []
    concrete = load_concrete_mission(path)
    assert [f.name for f in concrete.faults] == ["laser_poisson", "near", "odom_jump", "cmd_drop"]
    poisson, near, jump, drop = concrete.faults
    assert poisson.value("width") == 0.01 and poisson.value("phase") == 0.0
    assert near.activation == Activation(signal="SIG_GEOM_FAR_TRANSIT_CLOSE", duration=2.0)
    assert jump.activation == Activation(start=30.0, end=31.0) and jump.value("dy") == 0.0
    assert drop.activation == Activation(stop="SIG_MISSION_END")


@pytest.mark.parametrize(("entry", "rule", "col", "words"), [
    ("laser_dropot share 0.3", "FAULT-KIND", 9, "did you mean 'laser_dropout'"),
    ("laser_dropout sahre 0.3", "FAULT-PARAM", 23, "did you mean 'share'"),
    ("laser_dropout", "FAULT-PARAM", 9, "expected the parameter 'share'"),
    ("laser_dropout share 1.5", "NUM-RANGE", 23, "<= 1"),
    ("laser_noise sigma nan", "NUM-FINITE", 21, "finite"),
    ("cmd_delay seconds 1e999", "NUM-FINITE", 19, "finite"),
    ("laser_noise sigma 0.1 sigma 0.2", "OPTION-REPEAT", 31, "one 'sigma'"),
    ("odom_drift", "FAULT-PARAM", 9, "at least one of scale"),
    ("laser_sector min_deg 10 max_deg -10", "FAULT-PARAM", 33, "max_deg >= min_deg"),
    ("laser_freeze from 20 to 10", "FAULT-ACTIVATION", 22, "end after the start"),
    ("laser_freeze when SIG_A until SIG_A", "FAULT-ACTIVATION", 22, "other than"),
    ("laser_freeze when SIG_A for 0", "NUM-RANGE", 22, "> 0"),
    ("laser_freeze from -1", "NUM-RANGE", 22, ">= 0"),
    ("laser_dropout share", "FAULT-KIND", 23, "followed by its number: 'share 0.5'"),
])
def test_errors_are_located(tmp_path: Path, entry: str, rule: str, col: int,
                            words: str) -> None:
    found = problems(tmp_path, "        " + entry)
    assert any(r == rule and line == 3 and c == col and words in message
               for r, line, c, message in found), found


def test_duplicate_faults_are_named_apart(tmp_path: Path) -> None:
    found = problems(tmp_path, "        cmd_drop share 0.1\n        cmd_drop share 0.2")
    assert [(r, line) for r, line, _, _ in found] == [("NAME-UNIQUE", 4)]
    assert "cmd_drop as NAME" in found[0][3]
    assert problems(tmp_path, "        cmd_drop share 0.1\n        cmd_drop as b share 0.2") == []


def test_a_second_fault_section_is_a_repeat(tmp_path: Path) -> None:
    found = problems(tmp_path, "        cmd_drop share 0.1\n    }\n    fault {")
    assert [(r, m) for r, _, _, m in found] == [
        ("OPTION-REPEAT", "expected one 'fault' setting, found another")]


def test_the_command_line_option_uses_the_same_syntax() -> None:
    d = parse_fault_option("laser_dropout share 0.3 when SIG_X for 2")
    assert d == FaultDefinition.of("laser_dropout", Activation(signal="SIG_X", duration=2.0),
                                   share=0.3)
    with pytest.raises(LanguageError) as err:
        parse_fault_option("laser_dropout share 0.3 when")
    assert str(err.value).startswith("--fault:1:29: SYNTAX: expected a name")
    with pytest.raises(LanguageError, match=r"--fault:1:1: FAULT-KIND"):
        parse_fault_option("sonar_noise sigma 1")


def test_the_printer_writes_the_section_back(tmp_path: Path) -> None:
    path = mission(tmp_path, "        laser_poisson rate 20 gain 0.5 width 0.01 when SIG_A "
                   "until SIG_B\n        odom_jump as j dyaw 5 to 3")
    doc = Workspace().mission(path)
    assert doc.mission is not None
    text = print_mission(doc.mission, "simple_wall.room")
    assert "laser_poisson rate 20.0 gain 0.5 width 0.01 when SIG_A until SIG_B" in text
    path.write_text(text, encoding="utf-8")
    again = Workspace().mission(path)
    assert again.ok and again.mission is not None
    assert again.mission.faults == doc.mission.faults


@st.composite
def definitions(draw: st.DrawFn) -> FaultDefinition:
    spec = draw(st.sampled_from(FAULT_KINDS))
    params: dict[str, float] = {}
    for p in spec.parameters:
        if p.default is None or draw(st.booleans()):
            params[p.name] = draw(st.floats(p.low, p.high, exclude_min=p.low_open))
    if spec.nonzero_one_of and all(params.get(n, 0.0) == 0.0 for n in spec.nonzero_one_of):
        first = spec.parameter(spec.nonzero_one_of[0])
        assert first is not None
        params[first.name] = first.high
    if spec.kind == "laser_sector" and params["min_deg"] > params["max_deg"]:
        params["min_deg"], params["max_deg"] = params["max_deg"], params["min_deg"]
    window = draw(st.sampled_from(["always", "window", "event", "until"]))
    times = st.floats(0.0, 1e6)
    if window == "window":
        start = draw(times)
        activation = Activation(start=start, end=start + draw(st.floats(0.5, 1e5)))
    elif window == "event":
        activation = Activation(signal="SIG_A", duration=draw(st.none() | st.floats(0.01, 1e5)))
    elif window == "until":
        activation = Activation(stop="SIG_B")
    else:
        activation = Activation()
    return FaultDefinition(spec.kind, tuple(params.items()), activation,
                           draw(st.sampled_from(["", "named"])))


@given(definitions())
@settings(max_examples=150, deadline=None)
def test_text_reads_back_as_the_same_definition(d: FaultDefinition) -> None:
    assert parse_fault_option(d.text()) == d


@given(kind=st.sampled_from(sorted(KINDS)), value=st.sampled_from([math.inf, -math.inf,
                                                                  math.nan, 1e300]))
@settings(max_examples=40, deadline=None)
def test_no_parameter_accepts_a_non_finite_or_absurd_value(kind: str, value: float) -> None:
    for p in KINDS[kind].parameters:
        with pytest.raises(LanguageError, match=p.name):
            FaultDefinition.of(kind, **{q.name: (value if q is p else q.high)
                                        for q in KINDS[kind].parameters})


def test_the_editor_completes_the_fault_section() -> None:
    head = 'mission m in "r.room" {\n    fault {\n        '
    kinds = {k.kind for k in FAULT_KINDS}
    assert {c.label for c in mission_completions(head, None)} == kinds
    after_kind = {c.label for c in mission_completions(head + "laser_poisson rate 3 ", None)}
    assert {"gain", "period", "width", "phase", "when", "from"} <= after_kind
    assert "rate" not in after_kind
    assert mission_completions(head + "laser_poisson rate ", None) == []
    signals = {c.label for c in mission_completions(head + "cmd_drop share 1 when ", None)}
    assert "SIG_GEOM_FAR_TRANSIT_CLOSE" in signals
    after_signal = {c.label for c in mission_completions(head + "cmd_drop share 1 when S_A ",
                                                         None)}
    assert {"for", "until"} <= after_signal
    outside = {c.label for c in mission_completions('mission m in "r.room" {\n    ', None)}
    assert "fault" in outside and not outside & {"when", "until", "as", "from"}


@pytest.mark.parametrize(("text", "words"), [
    ("", "found nothing"),
    (" \n ", "found nothing"),
    ("x" * 100_000, "xxx...'"),
    ("cmd_drop \x1b[31m share 1", "\\x1b"),
    ("cmd_drop share 0.1 when SIG_A for 1e999", "finite"),
])
def test_hostile_options_get_clear_errors(text: str, words: str) -> None:
    with pytest.raises(LanguageError) as err:
        parse_fault_option(text)
    message = str(err.value)
    assert message.startswith("--fault:1:") and words in message
    assert len(message) < 400


@pytest.mark.parametrize(("activation", "words"), [
    (Activation(start=5.0, end=5.0), "end after the start"),
    (Activation(signal="SIG_A", start=3.0), "either a time window or a signal"),
    (Activation(duration=2.0), "'for': expected after 'when SIGNAL'"),
    (Activation(stop="SIG_B", end=3.0), "'until': expected after"),
    (Activation(signal="SIG A"), "expected a signal name"),
    (Activation(start=math.inf), "finite"),
])
def test_python_definitions_are_checked_too(activation: Activation, words: str) -> None:
    with pytest.raises(LanguageError, match=words):
        FaultDefinition.of("cmd_drop", activation, share=0.5)


def test_fault_argument_is_an_argparse_type() -> None:
    import argparse  # noqa: PLC0415

    from rei.lang.mission.faults import FAULT_OPTION_HELP, fault_argument  # noqa: PLC0415

    parser = argparse.ArgumentParser(prog="rei run", exit_on_error=False)
    parser.add_argument("--fault", type=fault_argument, action="append", default=[],
                        help=FAULT_OPTION_HELP)
    args = parser.parse_args(["--fault", "cmd_drop share 0.2", "--fault",
                              "laser_freeze when SIG_A for 1"])
    assert [d.kind for d in args.fault] == ["cmd_drop", "laser_freeze"]
    with pytest.raises(argparse.ArgumentError, match=r"column 10: cmd_drop share \(share\): "
                       r"expected a number > 0 and <= 1, found 2"):
        parser.parse_args(["--fault", "cmd_drop share 2"])


def test_the_outline_lists_faults_among_the_goals(tmp_path: Path) -> None:
    from rei.lang.lsp.outline import mission_outline  # noqa: PLC0415
    from rei.lang.lsp.positions import LineIndex  # noqa: PLC0415

    path = mission(tmp_path, "        cmd_drop share 0.2\n        laser_freeze as stuck from 3")
    doc = Workspace().mission(path)
    assert doc.mission is not None
    outline = mission_outline(doc.mission, LineIndex.of(path.read_text(encoding="utf-8")))
    assert [(s.name, s.kind, s.span.line) for s in outline.children] == [
        ("cmd_drop", "fault", 3), ("stuck", "fault", 4), ("a", "goal", 6), ("b", "goal", 7)]
    assert outline.children[1].detail == "laser_freeze as stuck from 3.0"


@pytest.mark.parametrize(("text", "words"), [
    ("laser_poisson rate 20 gain 0", "gain not 0"),
    ("laser_dropout share 0", "share (share): expected a number > 0"),
    ("cmd_drop share 0 from 5", "share (share): expected a number > 0"),
    ("laser_poisson rate 1 gain 0.1 period 1e-7 width 0.5", "expected a number >= 0.01"),
])
def test_faults_that_change_nothing_or_hang_the_run_are_refused(text: str, words: str) -> None:
    """A zero gain or share silently tests nothing; an impulse period of 1e-7 s made the run
    list ten million high phases a second and the supervisor killed it as hung."""
    with pytest.raises(LanguageError) as err:
        parse_fault_option(text)
    assert words in str(err.value) and str(err.value).count("\n") == 0


def test_a_fault_name_is_at_most_100_characters(tmp_path: Path) -> None:
    """events.csv joins the active faults' names into one field: a 140,000-letter one made
    the run's report fail to read it back (an internal error after the run)."""
    found = problems(tmp_path, f"laser_freeze as n{'x' * 140_000}")
    assert [(rule, line) for rule, line, _, _ in found] == [("FAULT-PARAM", 3)]
    assert "at most 100 characters, found 140001" in found[0][3] and len(found[0][3]) < 200
    assert parse_fault_option(f"laser_freeze as n{'x' * 99}").name == "n" + "x" * 99
