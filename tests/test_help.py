"""Help that tells the truth (issue 27.3): every command's --help ends with examples that its
own parser accepts, -q stands beside every --quiet, -v says what it adds for that command,
the controllers named are the ones that exist, descriptions are wrapped; `rei-gen rooms`
shows its progress on a terminal only; a .vepl without requirements says UNJUDGED clearly."""

from __future__ import annotations

import argparse
import fcntl
import os
import pty
import re
import shlex
import struct
import subprocess
import sys
import termios
from dataclasses import replace
from pathlib import Path

import pytest

from rei.lang.cli import DESCRIPTION as GEN_DESCRIPTION
from rei.lang.cli_support import build_parser
from rei.lang.vepl_parameters import FUNCTIONS_HELP
from rei.runtime.commands.cli import DESCRIPTION as RUN_DESCRIPTION
from rei.runtime.commands.run import CONTROLLER_HELP, final_line
from rei.runtime.robot.teleop import SCRIPTS
from rei.runtime.runs.session import exit_code
from tests.campaigns.records import summary_for

PROGRAMS = {"rei": (RUN_DESCRIPTION, "rei.runtime.commands"),
            "rei-gen": (GEN_DESCRIPTION, "rei.lang.commands")}


def parser_of(program: str) -> argparse.ArgumentParser:
    description, package = PROGRAMS[program]
    return build_parser(program, description, package)


def commands(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    (sub,) = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    return dict(sub.choices)


def example_lines(help_text: str) -> list[str]:
    """The command lines under 'examples:' (continuations joined, comments dropped)."""
    block = help_text.split("\nexamples:\n", 1)[1]
    lines: list[str] = []
    pending = ""
    for raw in block.split("\n"):
        line = raw.strip()
        if not line:
            continue
        line = pending + line
        if line.endswith("\\"):
            pending = line[:-1] + " "
            continue
        pending = ""
        lines.append(line.split("  #")[0].split("|")[0].strip())
    return lines


@pytest.mark.parametrize("program", sorted(PROGRAMS))
def test_every_command_shows_examples_its_parser_accepts(program: str) -> None:
    """Every command's --help ends with examples, at least one of that command; every
    example line of the program (a set-up step may be another of its commands, as `rei
    watch` first records a run) parses. Shell steps (`export ...`) and notes are left."""
    parser = parser_of(program)
    found = commands(parser)
    for name, command in found.items():
        lines = example_lines(command.format_help())
        runs = [shlex.split(line) for line in lines if line.startswith(program + " ")]
        assert any(argv[:2] == [program, name] for argv in runs), name
        for argv in runs:
            parser.parse_args(argv[1:])  # SystemExit (exit 2) on a flag or argument it lacks


@pytest.mark.parametrize("program", sorted(PROGRAMS))
def test_every_quiet_has_its_short_form(program: str) -> None:
    for name, command in commands(parser_of(program)).items():
        for action in command._actions:
            if "--quiet" in action.option_strings:
                assert "-q" in action.option_strings, name


def test_verbose_says_what_it_adds_for_each_command() -> None:
    found = commands(parser_of("rei"))

    def verbose_help(name: str) -> str:
        (action,) = [a for a in found[name]._actions if "--verbose" in a.option_strings]
        return str(action.help)

    assert "mission's events" in verbose_help("run")
    for name in ("replay", "monitor"):  # they judge a trace: no mission runs to show
        assert "mission's events" not in verbose_help(name)
    for name in ("campaign", "demo"):
        assert "reruns it" in verbose_help(name) and "mission's events" not in verbose_help(name)


def test_controller_help_lists_every_teleop_script() -> None:
    for script in SCRIPTS:
        assert script in CONTROLLER_HELP
    found = commands(parser_of("rei"))
    for name in ("run", "campaign", "demo", "robot"):
        (action,) = [a for a in found[name]._actions if "--controller" in a.option_strings]
        assert CONTROLLER_HELP in str(action.help)


def test_every_functions_option_says_the_same() -> None:
    """--functions is one option (rei.lang.vepl_parameters.add_functions_option) wherever a
    specification is loaded; its help had drifted into four wordings over six commands."""
    found = commands(parser_of("rei"))
    offering = {name: action for name, command in found.items() for action in command._actions
                if "--functions" in action.option_strings}
    assert {"run", "replay", "campaign", "shrink", "monitor", "watch"} <= set(offering)
    for name, action in offering.items():
        assert str(action.help).startswith(FUNCTIONS_HELP), name
        assert action.metavar == "MODULE" and action.default is None, name


@pytest.mark.parametrize("program", sorted(PROGRAMS))
def test_help_is_wrapped_to_the_terminal(program: str, monkeypatch: pytest.MonkeyPatch) -> None:
    """Descriptions, options and lists (rei-gen generate's targets) fit 80 columns; only the
    example command lines are kept whole, to be copied."""
    monkeypatch.setenv("COLUMNS", "80")
    for name, command in commands(parser_of(program)).items():
        text = command.format_help().split("\nexamples:\n")[0]
        long = [line for line in text.split("\n") if len(line) > 80]
        assert long == [], name


def test_a_vepl_without_requirements_is_unjudged_and_says_why() -> None:
    summary = replace(summary_for("m", "r", 0, True, 10.0), verdicts=())
    line = final_line(summary, Path("out"))
    assert line.startswith("verdict: UNJUDGED (the .vepl declares no requirement")
    assert exit_code(summary) == 1  # never a pass
    assert exit_code(summary, monitored=False) == 0  # --no-monitor: recorded, judged later
    assert "NOT JUDGED" in final_line(summary, Path("out"), monitored=False)


ROOMS = [sys.executable, "-m", "rei.lang.cli", "rooms", "--count", "6", "--seed", "4",
         "--preset", "small"]


def test_rooms_shows_progress_on_a_terminal_only(tmp_path: Path) -> None:
    # On a pipe (a CI log): no progress display.
    piped = subprocess.run([*ROOMS, "-o", str(tmp_path / "piped")], capture_output=True,
                           text=True, check=True, timeout=600)
    assert not re.search(r"\d+/6 left", piped.stderr)
    # On a terminal (a pty of 100 columns): the display, rooms done of the total.
    main, secondary = pty.openpty()
    fcntl.ioctl(secondary, termios.TIOCSWINSZ, struct.pack("HHHH", 30, 100, 0, 0))
    process = subprocess.Popen([*ROOMS, "-o", str(tmp_path / "tty")], stdin=subprocess.DEVNULL,
                               stdout=subprocess.DEVNULL, stderr=secondary)
    os.close(secondary)
    shown = b""
    while True:
        try:
            chunk = os.read(main, 4096)
        except OSError:  # the other side closed: the program ended
            break
        if not chunk:
            break
        shown += chunk
    os.close(main)
    assert process.wait(timeout=600) == 0
    text = re.sub(r"\x1b\[[0-9;?]*[a-zA-Z]", "", shown.decode("utf-8", errors="replace"))
    assert re.search(r"rooms .*\d/6 left", text)
    # The display changes nothing in the files.
    for name in ("index.csv", "room_0001.room", "room_0006.mission"):
        assert (tmp_path / "piped" / name).read_bytes() == (tmp_path / "tty" / name).read_bytes()


@pytest.mark.parametrize("program", sorted(PROGRAMS))
def test_a_command_line_builds_only_its_own_commands_parser(program: str) -> None:
    """`rei run …` imports and builds the run command alone (every command's module costs
    ~0.45 CPU s per process a campaign starts); the same parser as in the full build, and
    anything else (no word, an option, a misspelling, a module without a command) gets the
    full listing and its errors."""
    description, package = PROGRAMS[program]
    full = commands(build_parser(program, description, package))
    assert len(full) > 4
    for name, whole in full.items():
        alone = commands(build_parser(program, description, package, name))
        assert set(alone) == {name}
        assert alone[name].format_help() == whole.format_help()
    for word in (None, "--help", "rnu", "run_config", "cli_support"):
        assert set(commands(build_parser(program, description, package, word))) == set(full)


def test_rei_run_imports_no_other_commands_module() -> None:
    probe = ("import sys\n"
             "from rei.runtime.commands.cli import main\n"
             "try:\n"
             "    main(['run', '--help'])\n"
             "except SystemExit:\n"
             "    pass\n"
             "print(sorted(m for m in sys.modules if m.startswith('rei.runtime.commands.')))\n")
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True,
                          check=True, timeout=600)
    loaded = done.stdout.strip().splitlines()[-1]
    assert "'rei.runtime.commands.run'" in loaded
    for other in ("campaign", "search", "shrink", "watch", "bus", "demo"):
        assert f"'rei.runtime.commands.{other}'" not in loaded, loaded
