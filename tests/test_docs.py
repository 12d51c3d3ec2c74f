"""README.md and docs/*.md stay true to the code: their command lines, paths and references.

Every `rei` / `rei-gen` command line in a code block is parsed with the real parsers (one with
placeholders such as MISSION or DIR... has its command and options checked instead); every
`rei`/`rei-gen` command written inline in backquotes names a command that exists and options
it has; every path into the checkout (examples/, runtime/, docs/, ...) exists; every dotted
reference into the package (``rei.runtime.x.y``) imports. These are what went stale before
(a renamed option, a moved module); prose and numbers are for a reader to check.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import io
import re
import shlex
from pathlib import Path

import pytest

from rei.lang.cli import DESCRIPTION as GEN_DESCRIPTION
from rei.lang.cli_support import build_parser
from rei.runtime.commands.cli import DESCRIPTION as RUN_DESCRIPTION
from tests.conftest import REPO

DOCUMENTS = [REPO / "README.md", *sorted((REPO / "docs").glob("*.md"))]
PROGRAMS = {"rei": (RUN_DESCRIPTION, "rei.runtime.commands"),
            "rei-gen": (GEN_DESCRIPTION, "rei.lang.commands")}
SHELL_ENDS = ("|", "||", "&&", ";", "&", ">", "2>", ">>")
PATH = re.compile(r"(?<![\w/.-])((?:examples|runtime|rei_lang|generators|catalogue|grammars|"
                  r"bench|tests|docs|scripts)/[\w./*-]*[\w*])")
REFERENCE = re.compile(r"(?<![\w.])(rei\.(?:runtime|lang|generators|catalogue|grammars)"
                       r"(?:\.\w+)*)")
INLINE_COMMAND = re.compile(r"`((?:rei|rei-gen) [^`]*)`")
PLACEHOLDER = re.compile(r"\.\.\.|[<>\[\]]|^[A-Z][A-Z0-9_.]+$|…")


def parsers() -> dict[str, argparse.ArgumentParser]:
    return {name: build_parser(name, *made) for name, made in PROGRAMS.items()}


def commands(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    (sub,) = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    return dict(sub.choices)


def options(parser: argparse.ArgumentParser) -> set[str]:
    return {o for a in parser._actions for o in a.option_strings}


def code_lines(text: str) -> list[tuple[int, str]]:
    """(line number, command line) of the code blocks' lines (continuations joined)."""
    found: list[tuple[int, str]] = []
    inside, pending, start = False, "", 0
    for number, raw in enumerate(text.split("\n"), 1):
        if raw.strip().startswith("```"):
            inside, pending = not inside, ""
            continue
        if not inside:
            continue
        line = raw.strip()
        if not pending:
            start = number
        line = pending + line
        if line.endswith("\\"):
            pending = line[:-1] + " "
            continue
        pending = ""
        found.append((start, line.removeprefix("$ ")))
    return found


def prose_lines(text: str) -> list[tuple[int, str]]:
    found: list[tuple[int, str]] = []
    inside = False
    for number, line in enumerate(text.split("\n"), 1):
        if line.strip().startswith("```"):
            inside = not inside
        elif not inside:
            found.append((number, line))
    return found


def problems_of_command(words: list[str], programs: dict[str, argparse.ArgumentParser]
                        ) -> str | None:
    """What is wrong with a documented command line (None: nothing)."""
    for end in SHELL_ENDS:
        if end in words:
            words = words[:words.index(end)]
    program, parser = words[0], programs[words[0]]
    found = commands(parser)
    if len(words) < 2 or words[1] not in found:
        return f"{program} has no command {words[1:2]}"
    if any(PLACEHOLDER.search(w) for w in words[2:]):
        known = options(found[words[1]])
        unknown = [w for w in words[2:] if w.startswith("--") and w.split("=")[0] not in known]
        return f"no option {unknown}" if unknown else None
    try:
        with contextlib.redirect_stderr(io.StringIO()) as said:
            parser.parse_args(words[1:])
    except SystemExit as exc:
        if exc.code not in (0, None):
            return said.getvalue().strip().splitlines()[-1]
    return None


def document_problems(path: Path) -> list[str]:
    text = path.read_text(encoding="utf-8")
    programs = parsers()
    problems = []
    where = path.relative_to(REPO) if path.is_relative_to(REPO) else path.name
    for number, line in code_lines(text):
        if not re.match(r"(rei|rei-gen) ", line):
            continue
        problem = problems_of_command(shlex.split(line, comments=True), programs)
        if problem:
            problems.append(f"{where}:{number}: `{line}`: {problem}")
    for number, line in prose_lines(text):
        for match in INLINE_COMMAND.finditer(line):
            words = match.group(1).split()
            found = commands(programs[words[0]])
            if words[1].startswith("-") or words[1].endswith(":"):
                continue  # `rei --help`, or a message the command prints (`rei watch: ...`)
            if words[1] not in found:
                problems.append(f"{where}:{number}: `{match.group(1)}`: no command {words[1]}")
                continue
            known = options(found[words[1]])
            for word in words[2:]:
                flag = word.split("=")[0].rstrip(",.;:)")
                if word.startswith("--") and flag not in known:
                    problems.append(f"{where}:{number}: `{match.group(1)}`: no option {flag}")
    for number, line in enumerate(text.split("\n"), 1):
        for match in PATH.finditer(line):
            name = match.group(1)
            if not (list(REPO.glob(name)) if "*" in name else (REPO / name).exists()):
                problems.append(f"{where}:{number}: no file or folder {name}")
        for match in REFERENCE.finditer(line):
            if not resolves(match.group(1)):
                problems.append(f"{where}:{number}: {match.group(1)} does not import")
    return problems


def resolves(reference: str) -> bool:
    parts = reference.split(".")
    for cut in range(len(parts), 1, -1):
        try:
            target: object = importlib.import_module(".".join(parts[:cut]))
        except ImportError:
            continue
        for name in parts[cut:]:
            if not hasattr(target, name):
                return False
            target = getattr(target, name)
        return True
    return False


@pytest.mark.parametrize("path", DOCUMENTS, ids=lambda p: p.name)
def test_documented_commands_paths_and_references_exist(path: Path) -> None:
    assert document_problems(path) == []


def test_the_check_finds_what_went_stale(tmp_path: Path) -> None:
    """The same check on a page with a renamed option, a moved file and module, and a
    command that is gone: each is found (and a sound page next to them is not)."""
    page = tmp_path / "stale-probe.md"
    page.write_text("```sh\nrei run examples/simple_wall/simple_wall.mission -o out/x "
                    "--seeds 3\nrei run MISSION -o DIR --wachdog 5\n"
                    "rei run examples/simple_wall/simple_wall.mission -o out/ok --seed 3\n```\n"
                    "See `rei campain DIR`, `rei report DIR --html`, examples/nowhere/x.room "
                    "and rei.runtime.simulation.sensors.laser.Laser3D; "
                    "rei.runtime.simulation.sensors.laser.Laser2D "
                    "is fine.\n", encoding="utf-8")
    found = document_problems(page)
    assert len(found) == 6, found
    for expected in ("--seeds", "--wachdog", "campain", "--html", "examples/nowhere/x.room",
                     "Laser3D"):
        assert any(expected in problem for problem in found), (expected, found)
