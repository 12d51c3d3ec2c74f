"""The README's "A test case, end to end" works for a newcomer, exactly as written.

The command block is read from README.md itself, so the README and this test cannot drift:
every line must parse with the real `rei` / `rei-gen` parsers, and a fresh
`bash --noprofile --norc` (no virtual environment on PATH) in a copy of the checkout runs the
block line by line — with smaller counts and durations for the heavy commands — and leaves
nothing git would show as new.
"""

from __future__ import annotations

import os
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from rei.lang.cli_support import build_parser
from tests.conftest import REPO

README = REPO / "README.md"
SECTION = "## A test case, end to end"
ACTIVATE = ". .venv/bin/activate"
PARSERS = {"rei": ("rei.runtime.commands.cli", "rei.runtime.commands"),
           "rei-gen": ("rei.lang.cli", "rei.lang.commands")}
VERDICT_COMMANDS = {("rei", "run"), ("rei", "replay"), ("rei", "campaign")}
"""Commands whose exit status 1 is a verdict (a requirement failed or was inconclusive)."""


def end_to_end_block() -> list[str]:
    """The lines of the first ```sh block under the section, comments and blanks removed."""
    text = README.read_text(encoding="utf-8")
    assert SECTION in text, f"README.md has no section '{SECTION}'"
    after = text.split(SECTION, 1)[1].split("\n## ", 1)[0]
    match = re.search(r"```sh\n(.*?)```", after, re.S)
    assert match is not None, f"no ```sh block under '{SECTION}'"
    lines = []
    for line in match.group(1).splitlines():
        words = shlex.split(line, comments=True)
        if words:
            lines.append(shlex.join(words))
    return lines


def shortened(argv: list[str]) -> list[str]:
    """The same command with smaller counts and durations (the exact one is parsed by
    test_every_command_parses)."""
    swap = {("rei-gen", "rooms", "--count"): "2", ("rei", "campaign", "--repeat"): "1"}
    out = list(argv)
    for i, word in enumerate(out[:-1]):
        if (out[0], out[1], word) in swap:
            out[i + 1] = swap[(out[0], out[1], word)]
    if out[:2] in (["rei", "run"], ["rei", "campaign"]):
        out += ["--duration", "5"]
    return out


def test_the_block_starts_by_activating_the_environment() -> None:
    lines = end_to_end_block()
    assert lines[0] == ACTIVATE
    assert all(shlex.split(line)[0] in PARSERS for line in lines[1:])


def test_every_command_parses() -> None:
    """Each README line, unshortened, is valid for the real parser (names, options, values)."""
    import importlib

    for line in end_to_end_block()[1:]:
        argv = shlex.split(line)
        module, package = PARSERS[argv[0]]
        description = importlib.import_module(module).DESCRIPTION
        parser = build_parser(argv[0], description, package)
        try:
            parser.parse_args(argv[1:])
        except SystemExit:  # argparse's way of refusing
            pytest.fail(f"README line does not parse: {line}")


def checkout_copy(tmp_path: Path) -> Path:
    """A git repository holding what the README's commands read (examples/, .gitignore) and
    the environment the quickstart made (.venv, linked, excluded like the real one)."""
    root = tmp_path / "checkout"
    shutil.copytree(REPO / "examples", root / "examples")
    shutil.copy(REPO / ".gitignore", root / ".gitignore")
    venv = Path(sys.prefix)
    assert (venv / "bin" / "activate").is_file(), "the tests run from the quickstart's .venv"
    (root / ".venv").symlink_to(venv, target_is_directory=True)
    git = ["git", "-c", "user.name=t", "-c", "user.email=t@example.org", "-C", str(root)]
    subprocess.run([*git, "init", "-q"], check=True)
    (root / ".git" / "info" / "exclude").write_text(".venv\n")  # a link, not the real folder
    subprocess.run([*git, "add", "-A"], check=True)
    subprocess.run([*git, "commit", "-q", "-m", "checkout"], check=True)
    return root


def fresh_shell(root: Path, script: str) -> subprocess.CompletedProcess[str]:
    env = {"HOME": str(root.parent / "home"), "PATH": "/usr/local/bin:/usr/bin:/bin",
           "LANG": "C.UTF-8", "TMPDIR": os.environ.get("TMPDIR", "/tmp")}
    return subprocess.run(["bash", "--noprofile", "--norc", "-c", script], cwd=root, env=env,
                          capture_output=True, text=True, check=False)


@pytest.mark.slow
def test_a_fresh_shell_runs_the_readme_end_to_end(tmp_path: Path) -> None:
    root = checkout_copy(tmp_path)
    assert fresh_shell(root, "command -v rei rei-gen rei-lsp").returncode != 0, (
        "the commands must not be on PATH before the README's first line")
    lines = end_to_end_block()
    script = [lines[0], "command -v rei rei-gen rei-lsp >/dev/null || exit 97"]
    for k, line in enumerate(lines[1:], start=1):
        argv = shortened(shlex.split(line))
        script.append(f"{shlex.join(argv)}; echo \"rei-status $? {k}\"")
    done = fresh_shell(root, "\n".join(script))
    assert done.returncode != 97, f"`{lines[0]}` did not put rei, rei-gen and rei-lsp on PATH"
    statuses = re.findall(r"^rei-status (\d+) (\d+)$", done.stdout, re.M)
    assert len(statuses) == len(lines) - 1, done.stdout + done.stderr
    for status, k in statuses:
        line = lines[int(k)]
        argv = shlex.split(line)
        allowed = {0, 1} if (argv[0], argv[1]) in VERDICT_COMMANDS else {0}
        assert int(status) in allowed, f"`{line}` exited {status}:\n{done.stderr[-3000:]}"
    # The run from the launch target's run.json is the same run as the command line's.
    out = root / "out"
    assert (out / "nav" / "summary.json").read_bytes() == (
        out / "nav-again" / "summary.json").read_bytes()
    assert (out / "results" / "report.html").is_file()
    # Everything written is ignored: git sees nothing new in the checkout.
    status = subprocess.run(["git", "-C", str(root), "status", "--porcelain",
                             "--untracked-files=all"], capture_output=True, text=True,
                            check=True).stdout
    assert status == ""


def user_docs() -> dict[str, str]:
    return {p.relative_to(REPO).as_posix(): p.read_text(encoding="utf-8")
            for p in [README, *sorted((REPO / "docs").glob("*.md"))]}


def test_the_thesis_is_cited_not_pointed_to_by_a_path_a_clone_lacks() -> None:
    for name, text in user_docs().items():
        assert "shared/seed" not in text and "../shared" not in text, name
    assert "Tesztkörnyezetek generálása és monitorozása autonóm robotok" in README.read_text(
        encoding="utf-8").replace("\n", " ")


def test_links_between_the_docs_resolve() -> None:
    for name, text in user_docs().items():
        for target in re.findall(r"\]\(([^)#:]+\.md)\)", text):
            assert (REPO / name).parent.joinpath(target).is_file(), f"{name} links {target}"
        assert "see their sections" not in text, name


def test_every_controller_and_mission_keyword_a_user_can_write_is_documented() -> None:
    """Every built-in controller name and `max_speed` appear in the README and the docs."""
    from rei.runtime.robot import BUILT_IN

    readme = README.read_text(encoding="utf-8")
    generators = (REPO / "docs" / "generators.md").read_text(encoding="utf-8")
    for name in BUILT_IN:
        assert f"`{name}`" in readme and f"`{name}`" in generators, name
    mission_section = readme.split("### `.mission`", 1)[1].split("\n### ", 1)[0]
    assert "max_speed" in mission_section and "`max_speed`" in generators


def test_the_demo_ends_by_saying_how_to_reach_the_commands() -> None:
    """scripts/demo's last words (after `rei demo`, whatever its status) name the README's
    activation line, so the demo's own `rei report ...` hint works in the user's shell."""
    script = (REPO / "scripts" / "demo").read_text(encoding="utf-8")
    demo_call = script.index(".venv/bin/rei demo")
    tail = script[demo_call:]
    assert "exec" not in script[:demo_call].splitlines()[-1]
    assert ACTIVATE in tail and "exit $status" in tail
