"""REI targets through textX: the registration objects and the `textx generate` command."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner
from textx import TextXError, metamodel_for_language
from textx.registration import (
    clear_generator_registrations,
    generator_descriptions,
    register_generator,
)

from rei.generators import textx_generators
from rei.generators.targets import available_targets
from tests.conftest import EXAMPLES


@pytest.fixture
def navigation(tmp_path: Path) -> Path:
    shutil.copytree(EXAMPLES / "navigation", tmp_path / "navigation")
    return tmp_path / "navigation"


def test_every_registration_names_a_real_target_and_language() -> None:
    targets = set(available_targets()) | {"all"}
    for desc in textx_generators.REGISTRATIONS:
        assert desc.language in ("rei-room", "rei-mission", "rei-vepl")
        assert desc.target in targets, desc.target
        suffix = "." + desc.language.removeprefix("rei-")
        assert desc.target == "all" or suffix in available_targets()[desc.target].accepts
        assert callable(desc.generator)


def test_registered_generator_writes_what_rei_gen_writes(navigation: Path, tmp_path: Path) -> None:
    mission = navigation / "navigation.mission"
    model = metamodel_for_language("rei-mission").model_from_file(str(mission))
    out = tmp_path / "out"
    textx_generators.mission_mission.generator(None, model, str(out), False, False)
    assert (out / "mission.xml").read_bytes().startswith(b"<?xml")
    with pytest.raises(TextXError, match="use --overwrite"):
        textx_generators.mission_mission.generator(None, model, str(out), False, False)
    textx_generators.mission_mission.generator(None, model, str(out), True, False)


def test_textx_generate_command(navigation: Path) -> None:
    from textx.cli import textx as textx_cli

    clear_generator_registrations()
    try:
        generator_descriptions()  # the installed entry points, if the project declares them
        for desc in textx_generators.REGISTRATIONS:
            try:
                register_generator(desc)
            except TextXError:
                pass  # already registered through pyproject's entry points
        result = CliRunner().invoke(textx_cli, [
            "generate", str(navigation / "navigation.mission"), "--target", "launch",
            "--seed", "5"], catch_exceptions=False)
    finally:
        clear_generator_registrations()  # the next look-up reloads the entry points only
    assert result.exit_code == 0, result.output
    run = navigation / "navigation-launch" / "run.json"
    assert (navigation / "navigation-launch" / "sources" / "navigation.mission").is_file()
    assert '"seed": 5' in run.read_text()


@pytest.mark.slow
def test_textx_cli_generates_the_automata_of_a_vepl(navigation: Path, tmp_path: Path) -> None:
    """The installed `textx` program (a new process, entry points as a user has them) writes
    the same automata module as `rei-gen generate --target rx`."""
    textx_cli = Path(sys.executable).parent / "textx"
    vepl = navigation / "human_safety.vepl"
    done = subprocess.run([str(textx_cli), "generate", str(vepl), "--target", "rx",
                           "-o", str(tmp_path / "textx")], capture_output=True, text=True,
                          check=False)
    assert done.returncode == 0, done.stdout + done.stderr
    rei_gen = Path(sys.executable).parent / "rei-gen"
    subprocess.run([str(rei_gen), "generate", str(vepl), "--target", "rx",
                    "-o", str(tmp_path / "rei-gen")], capture_output=True, check=True)
    generated = (tmp_path / "textx" / "automata.py").read_bytes()
    assert b"reactivex" in generated
    assert generated == (tmp_path / "rei-gen" / "automata.py").read_bytes()
