"""Junk, empty, huge, deep and absurd inputs give one located message, never a traceback."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from rei.lang.cli import main
from rei.lang.parsing import parse
from rei.lang.source import MAX_SOURCE_BYTES, SourceText, read_bounded, unreadable
from rei.lang.workspace import Workspace


def rules_of(path: Path) -> list[str]:
    return [d.rule for d in Workspace().check(path)]


def test_empty_file(write) -> None:  # type: ignore[no-untyped-def]
    assert rules_of(write("e.room", "  \n\n")) == ["INPUT-EMPTY"]


def test_binary_junk_names_the_line_of_the_nul_byte(write) -> None:  # type: ignore[no-untyped-def]
    path = write("junk.mission", b"mission m\n in \x00\xff\xfe")
    [d] = Workspace().check(path)
    assert (d.rule, d.span.line, d.span.col) == ("INPUT-ENCODING", 2, 5)


def test_invalid_utf8(write) -> None:  # type: ignore[no-untyped-def]
    [d] = Workspace().check(write("latin.room", "room caf\xe9 {}".encode("latin-1")))
    assert d.rule == "INPUT-ENCODING" and "0xe9" in d.message


def test_huge_file_is_refused_before_reading(write) -> None:  # type: ignore[no-untyped-def]
    path = write("huge.room", b"")
    with path.open("wb") as handle:
        handle.truncate(MAX_SOURCE_BYTES + 1)
    assert rules_of(path) == ["INPUT-SIZE"]


def test_looking_says_what_reading_would(tmp_path: Path) -> None:
    """``unreadable`` (a command's check before it starts work) gives the reader's diagnostic
    word for word, and None for a file the reader reads."""
    import os

    good = tmp_path / "ok.mission"
    good.write_text("x")
    os.mkfifo(tmp_path / "pipe.mission")
    (tmp_path / "dir.mission").mkdir()
    (tmp_path / "loop.mission").symlink_to(tmp_path / "loop.mission")
    assert unreadable(good) is None and read_bounded(good) == b"x"
    for name in ("nope.mission", "pipe.mission", "dir.mission", "loop.mission", ""):
        path = tmp_path / name if name else ""
        problem = unreadable(path)
        assert problem is not None and problem.rule == "INPUT-READ", name
        assert str(problem) == str(read_bounded(path)), name
    assert "found a FIFO" in str(unreadable(tmp_path / "pipe.mission"))


def test_missing_file_folder_and_unknown_suffix(tmp_path: Path, write) -> None:  # type: ignore[no-untyped-def]
    assert rules_of(tmp_path / "nope.room") == ["INPUT-READ"]
    folder = tmp_path / "dir.room"
    folder.mkdir()
    assert rules_of(folder) == ["INPUT-READ"]
    assert rules_of(write("notes.txt", "hello")) == ["INPUT-KIND"]


def test_deep_nesting_becomes_a_diagnostic() -> None:
    # The .room grammar does not nest, so provoke the parser's recursion limit directly.
    import inspect

    parse("room", SourceText("warm.room", "room r { floor a }"))  # lazy imports done first:
    limit = sys.getrecursionlimit()                                # not under the low limit
    source = SourceText("deep.room", "room r {" + " floor a" * 20 + " }")
    try:
        sys.setrecursionlimit(len(inspect.stack()) + 20)
        result = parse("room", source)
    finally:
        sys.setrecursionlimit(limit)
    assert getattr(result, "rule", None) == "SYNTAX-DEPTH"


@pytest.mark.parametrize("text,rule", [
    ("room r { tile 1e400 }", "NUM-FINITE"),
    ("room r { tile nan }", "NUM-FINITE"),
    ("room r { tile 1e300 }", "NUM-RANGE"),
    ("room r { floor a robot x : turtlebot3_waffle on a heading 1e12 }", "NUM-RANGE"),
])
def test_absurd_numbers(write, text: str, rule: str) -> None:  # type: ignore[no-untyped-def]
    assert rule in rules_of(write("n.room", text))


def test_syntax_error_says_expected_and_found(write) -> None:  # type: ignore[no-untyped-def]
    [d] = Workspace().check(write("s.room", "room r {\n  floor a { rigth b }\n}\n"))
    assert (d.rule, d.span.line, d.span.col) == ("SYNTAX", 2, 13)
    assert d.message.startswith("expected one of 'top', 'right', 'bottom', 'left'")
    assert d.message.endswith("found 'rigth'")


def test_unterminated_file_says_end_of_file(write) -> None:  # type: ignore[no-untyped-def]
    [d] = Workspace().check(write("u.room", "room r {\n  floor a\n"))
    assert d.rule == "SYNTAX" and d.message.endswith("found the end of the file")


def test_command_line_never_prints_a_traceback(tmp_path: Path, write) -> None:  # type: ignore[no-untyped-def]
    files = [write("junk.room", bytes(range(256))), write("e.mission", ""),
             write("s.room", "room {"), tmp_path / "missing.mission"]
    proc = subprocess.run([sys.executable, "-m", "rei.lang.cli", "check", *map(str, files)],
                          capture_output=True, text=True, check=False)
    assert proc.returncode == 2
    assert "Traceback" not in proc.stdout + proc.stderr
    assert len(proc.stdout.strip().splitlines()) == 4


def test_exit_status(examples_dir: Path, write, capsys) -> None:  # type: ignore[no-untyped-def]
    assert main(["check", str(examples_dir / "navigation" / "navigation.mission")]) == 0
    assert main(["check", str(write("bad.room", "room r { }"))]) == 2
    capsys.readouterr()


def test_json_output(write, capsys) -> None:  # type: ignore[no-untyped-def]
    import json

    main(["check", "--format", "json", str(write("bad.room", "room r { }"))])
    [item] = json.loads(capsys.readouterr().out)
    assert item["rule"] == "ROBOT-COUNT" and item["line"] == 1 and item["severity"] == "error"


def test_deeply_nested_vepl_expression_is_refused_cleanly(write) -> None:  # type: ignore[no-untyped-def]
    depth = 3000
    text = ("specification deep\nparameters { eps_close = 0.25 eps_collision = 0.02 }\n"
            "query q() {\n  " + "(" * depth + " laser_min < 1 " + ")" * depth + "\n}\n")
    [d] = Workspace().check(write("deep.vepl", text))
    assert d.rule == "SYNTAX-DEPTH"
