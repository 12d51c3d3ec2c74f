"""User functions declared in a .vepl reach `rei replay`, `rei run` and `rei campaign`
through `--functions MODULE` (issue 14.10); a missing module or function is bad input."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from rei.lang.errors import LanguageError
from rei.runtime.campaigns import plan_campaign
from rei.runtime.commands.cli import main as rei
from rei.runtime.errors import RunError
from rei.runtime.observation.monitor.functions import load_functions
from rei.runtime.trace import write
from tests.conftest import EXAMPLES
from tests.observation.streams import drive, straight, wall

SPEC = """function clearance(o)
query tight(o: object) { clearance(o) < 0.3 }
queryEvent tightening(o) as tight(o) found
signal SIG_TIGHT on tightening utility -1
requirement NEVER_TIGHT { never SIG_TIGHT }
"""
MODULE = """def clearance(model, objects):
    # the footprint distance, as the user's own code reports it
    return model.distance
"""


@pytest.fixture
def files(tmp_path: Path) -> tuple[Path, Path, Path]:
    spec = tmp_path / "fn.vepl"
    spec.write_text(SPEC, encoding="utf-8")
    module = tmp_path / "my_checks.py"
    module.write_text(MODULE, encoding="utf-8")
    h, samples = drive([wall("w", 2.0, 0.0)], straight(0.0, 1.3, 14))
    trace = tmp_path / "trace.jsonl"
    write(trace, h, samples, samples[-1].time, "completed", "")
    return spec, module, trace


def test_replay_finds_the_functions_in_a_module_file(files, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    spec, module, trace = files
    out = tmp_path / "out"
    assert rei(["replay", str(trace), "--vepl", str(spec), "--functions", str(module),
                "-o", str(out)]) == 1  # the robot comes within 0.3 m of the wall: it fails
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    assert summary["signal_counts"] == {"SIG_TIGHT": 1}


def test_replay_finds_a_dotted_module_in_the_current_folder(  # type: ignore[no-untyped-def]
        files, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    spec, _, trace = files
    monkeypatch.chdir(tmp_path)
    assert rei(["replay", str(trace), "--vepl", str(spec), "--functions", "my_checks",
                "-o", str(tmp_path / "out")]) == 1


def test_a_missing_module_or_function_is_bad_input(  # type: ignore[no-untyped-def]
        files, tmp_path: Path, capsys) -> None:
    spec, module, trace = files
    assert rei(["replay", str(trace), "--vepl", str(spec), "--functions", "no_such_module_x",
                "-o", str(tmp_path / "a")]) == 2
    assert "--functions: expected an importable Python module, found 'no_such_module_x'" in \
        capsys.readouterr().err
    module.write_text("def clearence(model, o):\n    return model.distance\n", encoding="utf-8")
    assert rei(["replay", str(trace), "--vepl", str(spec), "--functions", str(module),
                "-o", str(tmp_path / "b")]) == 2
    err = capsys.readouterr().err
    assert f"{spec}:1:1: VEPL-FUNCTION: function 'clearance': expected a callable " \
           f"'clearance' in the module" in err
    assert "did you mean 'clearence'?" in err
    # a declared function and no module at all
    assert rei(["replay", str(trace), "--vepl", str(spec), "-o", str(tmp_path / "c")]) == 2
    assert "expected the module that defines it (--functions MODULE), found none" in \
        capsys.readouterr().err


def test_a_module_that_breaks_while_importing_is_bad_input(tmp_path: Path) -> None:
    broken = tmp_path / "broken.py"
    broken.write_text("raise ValueError('oops')\n", encoding="utf-8")
    spec = tmp_path / "fn.vepl"
    spec.write_text(SPEC, encoding="utf-8")
    with pytest.raises(RunError, match="failed to import: ValueError: oops"):
        load_functions(str(broken), spec)
    with pytest.raises(LanguageError):
        load_functions(None, spec)
    assert load_functions(None, None) == {}


def test_campaign_passes_the_module_to_every_run(files, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    spec, module, _ = files
    mission = EXAMPLES / "simple_wall" / "simple_wall.mission"
    plan = plan_campaign([mission], repeat=2, vepl=spec, functions=str(module))
    for run in plan.runs:
        argv = run.run_argv("out")
        assert argv[argv.index("--functions") + 1] == str(module.resolve())
        assert run.to_json()["functions"] == str(module.resolve())
    with pytest.raises(RunError):
        plan_campaign([mission], vepl=spec, functions=str(tmp_path / "nothing.py"))


@pytest.mark.slow
def test_run_monitors_live_with_the_users_functions(files, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    spec, module, _ = files
    out = tmp_path / "run"
    mission = EXAMPLES / "simple_wall" / "simple_wall.mission"
    status = rei(["run", str(mission), "-o", str(out), "--vepl", str(spec), "--functions",
                  str(module), "--controller", "teleop", "--duration", "15", "--quiet"])
    assert status == 1
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    assert summary["signal_counts"].get("SIG_TIGHT", 0) >= 1
