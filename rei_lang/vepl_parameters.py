"""A .vepl specification's parameters set from the command line: ``--param NAME=VALUE``.

Kept out of the ``rei.lang.vepl`` package so that every command line can offer the option
without importing the language (textX, networkx: ~0.15 s).

A user's robot may need a threshold of the .vepl other than the file's (a protective field
configured per robot, as a safety scanner's is) without copying the file. The option is read
here (``parameter_argument``, an argparse ``type``: a number, finite) and the values are
applied by the linker (``rei.lang.vepl.linker``), which checks each name against the
parameters the file declares and every parameter rule (VEPL-PARAM) against the values in
force, so every command that loads a specification with overrides refuses the same bad ones
(exit 2). Overrides travel as ``ParameterValues``: a name -> value mapping kept sorted by
name, so that records and command lines made from it are the same bytes for the same values.
The other option every such command offers, ``--functions MODULE`` (the module of the
specification's user functions), is declared here too (``add_functions_option``), for the
same reason. This module must never import the runtime.
"""

from __future__ import annotations

import argparse
import math
import re
from collections.abc import Iterable, Mapping

ParameterValues = tuple[tuple[str, float], ...]
"""Overrides sorted by name, each name once (hashable: the analysis cache keys on it)."""

PARAM_OPTION = "--param"
PARAM_HELP = ("set a parameter of the specification's `parameters` block to VALUE (a finite "
              "number) instead of the file's value; repeatable. NAME must be declared in the "
              ".vepl in use, else exit 2. The values are recorded with the verdicts "
              "(summary.json 'parameters')")
PARAM_METAVAR = "NAME=VALUE"
LIMIT = 1e9

NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
"""A parameter's name, as the .vepl grammar spells it."""


def parse_parameter(text: str) -> tuple[str, float]:
    """``NAME=VALUE`` as (name, value); ValueError saying what was expected and found."""
    name, sep, value = text.partition("=")
    name, value = name.strip(), value.strip()
    if not sep or not NAME.match(name):
        raise ValueError(f"expected NAME=VALUE with NAME a parameter's name, found '{text}'")
    try:
        number = float(value)
    except ValueError:
        raise ValueError(f"{name}: expected a number, found '{value}'") from None
    if not math.isfinite(number):
        raise ValueError(f"{name}: expected a finite number, found '{value}'")
    if abs(number) > LIMIT:
        # the bound the linker puts on a value written in the file
        raise ValueError(f"{name}: expected a number >= {-LIMIT:g} and <= {LIMIT:g}, "
                         f"found {value}")
    return name, number


def parameter_argument(text: str) -> tuple[str, float]:
    """``parse_parameter`` as an argparse ``type`` (a bad one is a usage error, exit 2)."""
    try:
        return parse_parameter(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def parameter_values(pairs: Iterable[tuple[str, float]] | Mapping[str, float] | None
                     ) -> ParameterValues:
    """Overrides in their one form: sorted by name; a name given twice keeps its last value
    (as a repeated option does), so the order they were given in changes nothing else."""
    items = pairs.items() if isinstance(pairs, Mapping) else (pairs or ())
    return tuple(sorted(dict(items).items()))


def parameter_options(values: ParameterValues) -> list[str]:
    """The command-line options that give ``values`` (for a run's or a replay's command)."""
    return [arg for name, value in values for arg in (PARAM_OPTION, f"{name}={value!r}")]


def parameter_text(values: ParameterValues) -> str:
    """``react_zone=0.7, slow_zone=0.4`` (for logs, reports and JUnit properties)."""
    return ", ".join(f"{name}={value:g}" for name, value in values)


def add_parameter_option(parser: argparse.ArgumentParser | argparse._ArgumentGroup,
                         help_prefix: str = "") -> None:
    """``--param NAME=VALUE`` (repeatable) into ``args.param``, one help text everywhere."""
    parser.add_argument(PARAM_OPTION, dest="param", action="append", default=[],
                        type=parameter_argument, metavar=PARAM_METAVAR,
                        help=help_prefix + PARAM_HELP)


FUNCTIONS_HELP = ("Python module (dotted name or .py file) defining the user functions the "
                  "specification declares with 'function'")


def add_functions_option(parser: argparse.ArgumentParser, note: str = "") -> None:
    """``--functions MODULE`` into ``args.functions`` (rei.runtime.observation.monitor.functions
    loads
    it), one help text everywhere; ``note`` says what the command does with it beyond."""
    parser.add_argument("--functions", default=None, metavar="MODULE",
                        help=FUNCTIONS_HELP + note)
