"""Shared plumbing of REI's command-line programs (`rei-gen`, `rei`).

Sub-commands are modules in a commands package, each with ``register(subparsers)`` that
adds its parser and sets ``func``; they are found at start-up, so a stage adds a command
without editing a central list. A module's ``HELP_EXAMPLES`` text (command lines, one per line,
each with a comment) ends its command's --help. Exit status: 0 ok, 1 a test verdict failed,
2 bad input, 3 a run error, 130 interrupted.
"""

from __future__ import annotations

import argparse
import importlib
import pkgutil
import re
import sys
import textwrap
from collections.abc import Callable, Sequence

from rei.lang.errors import LanguageError, ReiError, printable_lines

EXIT_OK = 0
EXIT_FAILED = 1
EXIT_BAD_INPUT = 2
EXIT_RUN_ERROR = 3
EXIT_INTERRUPTED = 130


class ReiHelpFormatter(argparse.HelpFormatter):
    """Paragraphs of a description or epilog are wrapped to the terminal; a block with
    indented lines (a list of targets, examples) is kept as written."""

    def _fill_text(self, text: str, width: int, indent: str) -> str:
        blocks = re.split(r"\n\s*\n", text.strip("\n"))
        out = []
        for block in blocks:
            lines = block.split("\n")
            if any(line[:1].isspace() for line in lines):
                out.append("\n".join(_hanging(indent + line, width) for line in lines))
            else:
                out.append(textwrap.fill(" ".join(line.strip() for line in lines), width,
                                         initial_indent=indent, subsequent_indent=indent))
        return "\n\n".join(out)


_DEFINITION = re.compile(r"^(\s+\S+\s{2,})(\S.*)$")


def _hanging(line: str, width: int) -> str:
    """A long line of a list of names and what they are ("  gazebo     an SDF world..."):
    its text wrapped under itself; any other line as written."""
    match = _DEFINITION.match(line)
    if len(line) <= width or match is None:
        return line
    head = match.group(1)
    return textwrap.fill(match.group(2), width, initial_indent=head,
                         subsequent_indent=" " * len(head))


def examples_epilog(examples: str, epilog: str | None) -> str:
    """A command's epilog with its examples after it."""
    lines = "\n".join("  " + line if line.strip() else "" for line in
                      textwrap.dedent(examples).strip("\n").split("\n"))
    return (epilog.rstrip("\n") + "\n\n" if epilog else "") + "examples:\n" + lines


def command_word(argv: Sequence[str] | None) -> str | None:
    """The command a command line names (its first word, when it is not an option)."""
    words = list(sys.argv[1:] if argv is None else argv)
    return words[0] if words and not words[0].startswith("-") else None


def build_parser(prog: str, description: str, package: str,
                 command: str | None = None) -> argparse.ArgumentParser:
    """The parser of every command in ``package`` (a module each, with ``register``). With
    ``command`` (`command_word` of the command line) only the module of that name is
    imported when it registers that command: building every command's parser imports every
    command's module (~0.45 CPU s, paid by each `rei run` a campaign starts), where one
    command needs its own (~0.07). Any other word (a misspelling, an option) gets them all,
    so the listing and the errors are the full ones."""
    parser = argparse.ArgumentParser(prog=prog, description=description,
                                     formatter_class=ReiHelpFormatter)
    from rei.lang import __version__  # noqa: PLC0415  (kept out of import time of rei.lang)

    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    pkg = importlib.import_module(package)
    names = sorted(info.name for info in pkgutil.iter_modules(pkg.__path__))
    if command in names:
        _register(sub, package, command)
        if command in sub.choices:
            return parser
    for name in names:
        if name != command:
            _register(sub, package, name)
    return parser


def _register(sub: argparse._SubParsersAction[argparse.ArgumentParser], package: str,
              name: str) -> None:
    """Add the commands the module ``package.name`` registers (if any) to ``sub``."""
    module = importlib.import_module(f"{package}.{name}")
    register: Callable[[argparse._SubParsersAction[argparse.ArgumentParser]], None] | None
    register = getattr(module, "register", None)
    if register is None:
        return
    before = set(sub.choices)
    register(sub)
    examples = getattr(module, "HELP_EXAMPLES", None)
    for added in set(sub.choices) - before:
        command = sub.choices[added]
        command.formatter_class = ReiHelpFormatter
        if isinstance(examples, str):
            command.epilog = examples_epilog(examples, command.epilog)


def run_main(parser: argparse.ArgumentParser, argv: Sequence[str] | None) -> int:
    args = parser.parse_args(argv)
    try:
        status: int = args.func(args)
        return status
    except LanguageError as exc:
        for diagnostic in exc.diagnostics:
            print(diagnostic, file=sys.stderr)
        return EXIT_BAD_INPUT
    except ReiError as exc:
        # a message may quote the user's input (a path, a name): shown, never interpreted
        print(f"{parser.prog}: error: {printable_lines(str(exc))}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        print(f"{parser.prog}: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except BrokenPipeError:
        return EXIT_OK
