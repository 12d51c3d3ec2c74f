"""The `rx` target: a readable, importable, deterministic module of RxPY event automata."""

from __future__ import annotations

from pathlib import Path

from rei.generators.targets import check_target, get_target
from rei.generators.targets.rx import render_module
from rei.lang.cli import main as rei_gen
from rei.lang.vepl import DEFAULT_VEPL, load_vepl
from rei.runtime.observation.automata.records import load_generated


def test_target_conforms_and_accepts_vepl() -> None:
    target = get_target("rx")
    assert check_target(target) == []
    assert target.accepts == (".vepl",)


def test_generate_command_writes_an_importable_module(tmp_path: Path) -> None:
    assert rei_gen(["generate", str(DEFAULT_VEPL), "--target", "rx", "-o", str(tmp_path)]) == 0
    path = tmp_path / "automata.py"
    text = path.read_text(encoding="utf-8")
    assert text.startswith('"""Event automata of the .vepl specification')
    assert "(notAtomicFarFromObject -> atomicCloseToObject){+}[1000]" in text
    assert max(len(line) for line in text.splitlines()) <= 130
    module = load_generated(path)
    assert module.SPEC_NAME == "default"
    assert {s.name for s in module.SIGNALS} >= {"SIG_GEOM_FAR_TRANSIT_CLOSE"}
    params = module.PARAMETERS
    assert module.DISTANCE_CUTOFF == max(params["eps_close"], params["slow_zone"])


def test_generation_is_deterministic() -> None:
    spec = load_vepl()
    assert render_module(spec, "default.vepl") == render_module(load_vepl(), "default.vepl")


def test_hysteresis_generates_relaxed_thresholds(tmp_path: Path) -> None:
    path = tmp_path / "h.vepl"
    path.write_text("parameters { hysteresis = 0.1 }\n"
                    "query close(o: object) { distance(robot, o) < 0.5 }\n", encoding="utf-8")
    text = render_module(load_vepl(path), "h.vepl")
    assert "< 0.5 + HYSTERESIS" in text
    assert "DISTANCE_CUTOFF = 0.6" in text


def test_automata_of_an_older_rei_are_refused_by_name(tmp_path: Path) -> None:
    """Automata generated before the runtime's regrouping import rei.runtime.monitor.*: loading
    them (a saved run folder's automata/) says what they are and what to do, never a
    traceback; a run's page falls back to the default thresholds and says why."""
    import pytest

    from rei.runtime.observation.errors import MonitorError
    from rei.runtime.presentation.run_page.run_data import read_thresholds

    assert rei_gen(["generate", str(DEFAULT_VEPL), "--target", "rx", "-o", str(tmp_path)]) == 0
    path = tmp_path / "automata.py"
    text = path.read_text(encoding="utf-8")
    old = text.replace("rei.runtime.observation.automata.records", "rei.runtime.monitor.automata")
    old = old.replace("FORMAT_VERSION = 5", "FORMAT_VERSION = 4")
    assert old != text
    folder = tmp_path / "run"
    (folder / "automata").mkdir(parents=True)
    (folder / "automata" / "automata.py").write_text(old, encoding="utf-8")
    with pytest.raises(MonitorError) as refused:
        load_generated(folder / "automata" / "automata.py")
    message = str(refused.value)
    assert "expected automata of format 5, found automata of an older REI" in message
    assert "rei.runtime.monitor" in message and "rei-gen generate" in message
    source = read_thresholds(folder).source
    assert source.startswith("default; automata/automata.py: expected automata of format 5")
    assert "older REI" in source
    (folder / "automata" / "automata.py").write_text(text, encoding="utf-8")
    assert read_thresholds(folder).source == "automata/automata.py"
