"""`--param NAME=VALUE` (rei.lang.vepl_parameters): a .vepl's parameter values set from the
command line. Each check is shown failing on input that breaks it and passing on input that
does not: the option is read as a finite number, a name the specification does not declare is
refused (exit 2, with the declared names and a did-you-mean), every parameter rule is checked
against the values in force, the generated automata carry the value, the cache never serves
automata made with other values, and the values travel into the campaign plan (a resume with
other values is refused), the run's command line, summary.json and the JUnit properties."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import pytest
from lxml import etree

from rei.generators.pipeline import plan
from rei.lang.cli import main as rei_gen
from rei.lang.errors import LanguageError
from rei.lang.vepl.document import DEFAULT_VEPL, changed_parameters, load_vepl
from rei.lang.vepl_parameters import (
    parameter_options,
    parameter_text,
    parameter_values,
    parse_parameter,
)
from rei.runtime.campaigns import CampaignError, CampaignStore, RunSpec
from rei.runtime.campaigns.plan import CampaignPlan, plan_campaign
from rei.runtime.campaigns.run_records import RunRecord
from rei.runtime.campaigns.search.driver import SearchConfig
from rei.runtime.campaigns.shrink.oracle import RunSettings
from rei.runtime.presentation.junit import junit_xml
from rei.runtime.results import RunSummary, Verdict
from rei.runtime.runs.cache import ArtifactCache
from rei.runtime.runs.supervisor import RunRequest

from ..conftest import EXAMPLES

SLOW = (("react_zone", 0.7),)


def automata_text(parameters: tuple[tuple[str, float], ...] = ()) -> str:
    return plan(DEFAULT_VEPL, "rx", parameters=parameters).tree.files["automata.py"].decode()


# ---- reading the option --------------------------------------------------------------------

def test_the_option_is_a_name_and_a_finite_number() -> None:
    assert parse_parameter("react_zone=0.7") == ("react_zone", 0.7)
    assert parse_parameter(" slow_zone = 4e-1 ") == ("slow_zone", 0.4)
    for text, found in (("react_zone=nan", "expected a finite number, found 'nan'"),
                        ("react_zone=inf", "expected a finite number, found 'inf'"),
                        ("react_zone=-Infinity", "expected a finite number"),
                        ("react_zone=fast", "expected a number, found 'fast'"),
                        ("react_zone=", "expected a number, found ''"),
                        ("react_zone", "expected NAME=VALUE"),
                        ("2x=1", "expected NAME=VALUE"),
                        ("react_zone=1e12", r"expected a number >= -1e\+09 and <= 1e\+09")):
        with pytest.raises(ValueError, match=found):
            parse_parameter(text)


def test_values_have_one_form_whatever_the_order_given() -> None:
    given = [("slow_zone", 0.4), ("react_zone", 0.9), ("react_zone", 0.7)]
    assert parameter_values(given) == (("react_zone", 0.7), ("slow_zone", 0.4))
    # the last of a name given twice wins, as for any repeated option
    assert parameter_values(given[::-1]) == (("react_zone", 0.9), ("slow_zone", 0.4))
    assert parameter_values([("slow_zone", 0.4), ("react_zone", 0.7)]) == \
        parameter_values({"react_zone": 0.7, "slow_zone": 0.4})
    options = parameter_options(parameter_values(given))
    assert options == ["--param", "react_zone=0.7", "--param", "slow_zone=0.4"]
    # the options read back to the same values (a run's command line repeats the run)
    assert parameter_values(parse_parameter(o) for o in options[1::2]) == \
        parameter_values(given)
    assert parameter_text(parameter_values(given)) == "react_zone=0.7, slow_zone=0.4"


# ---- applying it to a specification ---------------------------------------------------------

def test_an_override_replaces_the_files_value_everywhere_it_is_used() -> None:
    plain, slow = load_vepl(None), load_vepl(None, SLOW)
    assert plain.parameters["react_zone"] == 1.05 and slow.parameters["react_zone"] == 0.7
    assert {k: v for k, v in slow.parameters.items() if k != "react_zone"} == \
        {k: v for k, v in plain.parameters.items() if k != "react_zone"}
    # the generated automata carry the value in the query's condition and the table
    before, after = automata_text(), automata_text(SLOW)
    assert "w.hazard_clearance < 1.05" in before and "w.hazard_clearance < 1.05" not in after
    assert "w.hazard_clearance < 0.7" in after and "'react_zone': 0.7," in after
    # the same values give the same bytes
    assert automata_text(SLOW) == after
    assert automata_text((("react_zone", 1.05),)) == before


def test_an_undeclared_name_is_refused_with_the_declared_ones() -> None:
    with pytest.raises(LanguageError) as caught:
        load_vepl(None, (("react_zon", 0.7),))
    [diagnostic] = caught.value.diagnostics
    assert diagnostic.rule == "VEPL-UNKNOWN" and diagnostic.span.file.endswith("default.vepl")
    assert "--param react_zon: expected a parameter the specification declares (" \
        in diagnostic.message
    assert "react_zone, rest_after, rest_tolerance, settle_tolerance" in diagnostic.message
    assert diagnostic.message.endswith("found 'react_zon'; did you mean 'react_zone'?")
    # a specification's own names: human_safety.vepl has no react_zone
    with pytest.raises(LanguageError, match="declares .*personal_space.*found 'react_zone'"):
        load_vepl(EXAMPLES / "navigation" / "human_safety.vepl", SLOW)
    assert load_vepl(EXAMPLES / "navigation" / "human_safety.vepl",
                     (("personal_space", 0.8),)).parameters["personal_space"] == 0.8


def test_the_parameter_rules_hold_for_the_values_in_force() -> None:
    with pytest.raises(LanguageError, match=r"eps_close \(0.01, set by --param\), found 0.02$"):
        load_vepl(None, (("eps_close", 0.01),))
    with pytest.raises(LanguageError, match=r"\(0.25\), found 0.3 \(set by --param\)$"):
        load_vepl(None, (("eps_collision", 0.3),))
    with pytest.raises(LanguageError, match=r"hysteresis band >= 0 m, found -1 \(set by"):
        load_vepl(None, (("hysteresis", -1.0),))
    # both moved together keep the rule: accepted
    spec = load_vepl(None, (("eps_close", 0.5), ("eps_collision", 0.3)))
    assert (spec.parameters["eps_close"], spec.parameters["eps_collision"]) == (0.5, 0.3)


def test_what_differs_from_the_file_is_what_a_result_records() -> None:
    assert changed_parameters(None, ()) == ()
    assert changed_parameters(None, SLOW) == SLOW
    assert changed_parameters(None, (("react_zone", 1.05), ("slow_zone", 0.4))) == \
        (("slow_zone", 0.4),)
    with pytest.raises(LanguageError):
        changed_parameters(None, (("nothing", 1.0),))


# ---- rei-gen generate ----------------------------------------------------------------------

def test_rei_gen_generates_automata_with_the_value(tmp_path: Path,
                                                   capsys: pytest.CaptureFixture[str]) -> None:
    vepl = str(DEFAULT_VEPL)
    assert rei_gen(["generate", vepl, "-t", "rx", "-o", str(tmp_path / "slow"),
                    "--param", "react_zone=0.7"]) == 0
    assert (tmp_path / "slow" / "automata.py").read_text(encoding="utf-8") == automata_text(SLOW)
    capsys.readouterr()
    assert rei_gen(["generate", vepl, "-t", "rx", "-o", str(tmp_path / "bad"),
                    "--param", "slow_zon=0.3"]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "did you mean 'slow_zone'?" in err
    with pytest.raises(SystemExit) as usage:
        rei_gen(["generate", vepl, "-t", "rx", "-o", str(tmp_path / "bad"),
                 "--param", "slow_zone=nan"])
    assert usage.value.code == 2
    assert "argument --param: slow_zone: expected a finite number, found 'nan'" \
        in capsys.readouterr().err
    mission = str(EXAMPLES / "simple_wall" / "simple_wall.mission")
    assert rei_gen(["generate", mission, "-t", "monitor", "-o", str(tmp_path / "bad"),
                    "--param", "slow_zone=0.3"]) == 2
    assert ("--param: expected a .vepl file to set parameters of, or a .mission for target "
            "'launch' (its run.json), found 'simple_wall.mission' for target 'monitor'"
            in capsys.readouterr().err)
    assert rei_gen(["generate", mission, "-t", "launch", "-o", str(tmp_path / "bad"),
                    "--param", "react_zon=0.7"]) == 2
    assert "did you mean 'react_zone'?" in capsys.readouterr().err
    assert not (tmp_path / "bad").exists()  # nothing written on bad input


def test_the_launch_targets_run_json_carries_the_values(tmp_path: Path) -> None:
    """`rei-gen generate M -t launch --param ...` writes them into run.json's `parameters`,
    which `rei run --config` reads back as the same --param (tests/generators/
    test_run_config.py); without --param the field is left out, as before."""
    mission = str(EXAMPLES / "navigation" / "navigation.mission")
    assert rei_gen(["generate", mission, "-t", "launch", "-o", str(tmp_path / "set"),
                    "--param", "slow_zone=0.4", "--param", "react_zone=0.7"]) == 0
    run = json.loads((tmp_path / "set" / "run.json").read_text(encoding="utf-8"))
    assert run["parameters"] == {"react_zone": 0.7, "slow_zone": 0.4}
    assert rei_gen(["generate", mission, "-t", "launch", "-o", str(tmp_path / "plain")]) == 0
    assert "parameters" not in json.loads((tmp_path / "plain" / "run.json").read_text(
        encoding="utf-8"))
    # checked against the .vepl the run will use (option monitor), not the default one
    assert rei_gen(["generate", mission, "-t", "launch", "-o", str(tmp_path / "own"),
                    "--option", "monitor=human_safety.vepl", "--param", "max_path_ratio=2"]) == 2
    assert not (tmp_path / "own").exists()


# ---- the cache -----------------------------------------------------------------------------

def test_the_cache_never_serves_automata_made_with_other_values(tmp_path: Path) -> None:
    cache = ArtifactCache(tmp_path / "cache")
    read = lambda name: (tmp_path / name / "automata.py").read_text(encoding="utf-8")  # noqa: E731
    cache.automata(None, tmp_path / "plain")
    cache.automata(None, tmp_path / "slow", SLOW)
    cache.automata(None, tmp_path / "slower", (("react_zone", 0.5),))
    assert read("plain") == automata_text() and read("slow") == automata_text(SLOW)
    assert read("slower") == automata_text((("react_zone", 0.5),))
    assert len({read("plain"), read("slow"), read("slower")}) == 3
    entries = sorted(p for p in cache.root.glob("*/*") if not p.name.startswith("."))
    assert len(entries) == 3
    # the same values again are a hit (no new entry), with the same bytes
    cache.automata(None, tmp_path / "slow-again", SLOW)
    cache.automata(None, tmp_path / "plain-again")
    assert read("slow-again") == read("slow") and read("plain-again") == read("plain")
    assert len([p for p in cache.root.glob("*/*") if not p.name.startswith(".")]) == 3


# ---- where the values travel ---------------------------------------------------------------

def test_a_campaign_plan_records_the_values_and_passes_them_to_each_run(tmp_path: Path) -> None:
    plain = plan_campaign([EXAMPLES / "simple_wall"], seed=3)
    slow = plan_campaign([EXAMPLES / "simple_wall"], seed=3, vepl_parameters=SLOW)
    spec = slow.runs[0]
    assert spec.vepl_parameters == SLOW
    assert spec.run_argv("out")[-2:] == ["--param", "react_zone=0.7"]
    assert "--param" not in plain.runs[0].run_argv("out")
    assert spec.to_json()["vepl_parameters"] == {"react_zone": 0.7}
    assert "vepl_parameters" not in plain.runs[0].to_json()  # older plans keep their shape
    assert RunSpec.from_json(json.loads(json.dumps(spec.to_json()))) == spec
    assert CampaignPlan.from_json(json.loads(json.dumps(slow.to_json()))) == slow
    with pytest.raises(LanguageError, match="did you mean 'react_zone'"):
        plan_campaign([EXAMPLES / "simple_wall"], vepl_parameters=(("react_zon", 0.7),))
    # resuming with other values (or none) is another campaign: refused; the same: accepted
    with CampaignStore.open(tmp_path, slow, {}):
        pass
    for other in (plain, plan_campaign([EXAMPLES / "simple_wall"], seed=3,
                                       vepl_parameters=(("react_zone", 0.8),))):
        with pytest.raises(CampaignError, match=r"differs in vepl_parameters"):
            CampaignStore.open(tmp_path, other, {})
    with CampaignStore.open(tmp_path, slow, {}):
        pass


def test_search_shrink_and_the_supervised_run_carry_the_values() -> None:
    config = SearchConfig(vepl_parameters=SLOW)
    assert SearchConfig.from_json(json.loads(json.dumps(config.to_json()))) == config
    assert "vepl_parameters" not in SearchConfig().to_json()["config"]
    settings = RunSettings(seeds=(0, 1), vepl_parameters=SLOW)
    spec = settings.spec(EXAMPLES / "simple_wall" / "simple_wall.mission", 1, "x")
    assert spec.vepl_parameters == SLOW and spec.run_argv("o")[-2:] == ["--param",
                                                                        "react_zone=0.7"]
    assert settings.describe()["vepl_parameters"] == {"react_zone": 0.7}
    assert "vepl_parameters" not in RunSettings(seeds=(0,)).describe()
    request = RunRequest("m.mission", "out", parameters=SLOW)
    assert RunRequest.from_json(request.to_json()) == request


def _summary(parameters: dict[str, float]) -> RunSummary:
    return RunSummary(1, "m", "r", 0, "reference", "completed", "", 1.0, 0.0, {},
                      (Verdict("REACTION_TIME", "pass", None, "slowed"),),
                      parameters=parameters)


def test_summary_and_junit_show_the_values_other_than_the_files() -> None:
    plain, slow = _summary({}), _summary({"react_zone": 0.7})
    assert "parameters" not in plain.to_json()  # a run without overrides writes as before
    assert slow.to_json()["parameters"] == {"react_zone": 0.7}
    assert RunSummary.from_json(slow.to_json()) == slow
    assert RunSummary.from_json(plain.to_json()) == plain
    spec = plan_campaign([EXAMPLES / "simple_wall"]).runs[0]

    def properties(summary: RunSummary) -> dict[str, str]:
        record = RunRecord(spec, "ran", 0, 1.0, "", summary)
        doc = etree.fromstring(junit_xml([record], {}))
        return {p.get("name"): p.get("value") for p in doc.iter("property")}

    assert properties(slow)["param.react_zone"] == "0.7"
    assert not any(k.startswith("param.") for k in properties(plain))
    assert not any(k.startswith("param.") for k in properties(replace(slow, parameters={})))


def test_every_command_that_judges_refuses_an_undeclared_name_before_it_starts(
        tmp_path: Path, capfd: pytest.CaptureFixture[str]) -> None:
    """Each command has the option and checks it first: one line, exit 2, nothing made."""
    from rei.runtime.commands.cli import main as rei  # noqa: PLC0415

    mission = str(EXAMPLES / "simple_wall" / "simple_wall.mission")
    trace = tmp_path / "trace.jsonl"
    trace.write_text("{}\n", encoding="utf-8")
    out = tmp_path / "out"
    commands = {
        "run": ["run", mission, "-o", str(out)],
        "replay": ["replay", str(trace), "-o", str(out)],
        "campaign": ["campaign", mission, "-o", str(out)],
        "demo": ["demo", "-o", str(out)],
        "search": ["search", "-o", str(out), "--budget", "1"],
        "shrink": ["shrink", mission, "-o", str(out)],
        "monitor": ["monitor", "--bus", "tcp/127.0.0.1:9", "-o", str(out)],
        "watch": ["watch", "--replay", str(trace), "--plain"],
    }
    for name, argv in commands.items():
        capfd.readouterr()
        assert rei([*argv, "--param", "react_zon=0.7"]) == 2, name
        err = capfd.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "--param react_zon: expected a parameter" in err[0] \
            and err[0].endswith("did you mean 'react_zone'?"), (name, err)
        assert not out.exists(), name
