"""`rei run --config run.json`: one JSON file that describes a whole run (format ``rei-run/1``).

The `launch` target writes ``run.json`` beside the files it generates; any user may write one
by hand. This module reads it, checks every field (an error names the file, the field, what
was expected and what was found) and maps it onto the same arguments `rei run` takes, so a
run from the file and the equivalent command line are one and the same run, byte for byte.
An option given explicitly on the command line overrides the file's field.

Fields (``format`` and ``mission`` are required; the others default like `rei run`'s options):

======================  ==============================================================
``format``              ``"rei-run/1"``
``mission``             the .mission file, relative to run.json
``vepl``                the monitoring specification, relative to run.json; ``null``:
                        REI's default one
``controller``          ``"reference"`` (default), ``"teleop"``, ``"teleop:circle"``... or
                        ``"module:Class"``
``seed``                whole number >= 0 (default 0)
``duration``            simulated seconds > 0, or ``null``: the mission's time limit
``physics_rate``        physics steps per simulated second (default 100)
``odom_drift``          relative odometry error per control tick (default 0)
``laser_noise``         metres (0 to 1), or ``null``: the robot's catalogue value
``variation``           ``true`` (default): the seed varies the start pose and the humans
``monitor``             ``true`` (default): monitor and judge the run
``parameters``          an object of the .vepl's parameters set for this run, name ->
                        finite number (``{"react_zone": 0.7}``), as ``--param``; a
                        ``--param`` on the command line overrides the same name
======================  ==============================================================

This module must never run anything: it only turns the file into arguments.
"""

from __future__ import annotations

import argparse
import json
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rei.lang.source import UnreadableInput, bounded_text, repeated_key
from rei.lang.suggest import did_you_mean
from rei.lang.vepl_parameters import NAME, parse_parameter
from rei.runtime.errors import RunError

FORMAT = "rei-run/1"
DEFAULT_OUTPUT = "run"
"""The output folder, beside run.json, when neither -o nor the file names one."""


@dataclass(frozen=True)
class Unset:
    """The default of an option the user did not give: the config file may set it."""

    value: Any


def _text(value: Any) -> str:
    return json.dumps(value) if not isinstance(value, str) else f"'{value}'"


@dataclass(frozen=True)
class Field:
    dest: str
    """The `rei run` argument the field sets."""
    expected: str
    check: Callable[[Any], bool]
    convert: Callable[[Any, Path], Any] = lambda value, _base: value


def _number(low: float, *, above: bool = False, high: float = math.inf) -> Callable[[Any], bool]:
    def ok(value: Any) -> bool:
        if isinstance(value, bool) or not isinstance(value, int | float):
            return False
        value = float(value)
        return math.isfinite(value) and (value > low if above else value >= low) and value <= high
    return ok


def _path(value: Any, base: Path) -> Path | None:
    return None if value is None else base / value


FIELDS: Mapping[str, Field] = {
    "mission": Field("mission", "a path to a .mission file, relative to run.json",
                     lambda v: isinstance(v, str) and v.endswith(".mission"), _path),
    "vepl": Field("vepl", "null or a path to a .vepl file, relative to run.json",
                  lambda v: v is None or (isinstance(v, str) and v.endswith(".vepl")), _path),
    "controller": Field("controller", "a controller name such as \"reference\"",
                        lambda v: isinstance(v, str) and v != ""),
    "seed": Field("seed", "a whole number >= 0",
                  lambda v: isinstance(v, int) and not isinstance(v, bool) and v >= 0),
    "duration": Field("duration", "null or a finite number of seconds > 0",
                      lambda v: v is None or _number(0, above=True)(v),
                      lambda v, _b: None if v is None else float(v)),
    "physics_rate": Field("physics_rate", "a finite number of steps per second > 0",
                          _number(0, above=True), lambda v, _b: float(v)),
    "odom_drift": Field("odom_drift", "a finite number >= 0", _number(0),
                        lambda v, _b: float(v)),
    "laser_noise": Field("laser_noise", "null or metres from 0 to 1",
                         lambda v: v is None or _number(0, high=1)(v),
                         lambda v, _b: None if v is None else float(v)),
    "variation": Field("no_variation", "true or false", lambda v: isinstance(v, bool),
                       lambda v, _b: not v),
    "monitor": Field("no_monitor", "true or false", lambda v: isinstance(v, bool),
                     lambda v, _b: not v),
    "parameters": Field("param", "an object of parameter names and finite numbers, such as "
                        "{\"react_zone\": 0.7}", lambda v: isinstance(v, dict),
                        lambda v, _b: sorted(v.items())),
}
"""Every field but ``format``, by name."""


MERGED = ("param",)
"""Repeatable options the file's field adds to, entry by entry, instead of setting."""


MAX_CONFIG_BYTES = 1024 * 1024
"""A run.json is a few hundred bytes; a megabyte is no run configuration."""


def _unique(path: Path, pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    repeated = repeated_key(pairs)
    if repeated is not None:
        raise RunError(f"{path}: field {_text(repeated[0])}: expected once, found "
                       f"{repeated[1]} times")
    return dict(pairs)


def load_run_config(path: Path) -> dict[str, Any]:
    """The file's fields as `rei run` arguments (by ``dest``), checked; RunError names the
    file, the field, what was expected and what was found."""
    if not path.exists() and not path.is_symlink():
        raise RunError(f"{path}: --config: expected a run.json file, found none")
    try:
        text = bounded_text(path, MAX_CONFIG_BYTES)
    except UnreadableInput as exc:
        raise RunError(f"{path}: cannot read the run configuration: {exc}") from None
    try:
        data = json.loads(text, parse_constant=lambda name: _reject_constant(path, name),
                          object_pairs_hook=lambda pairs: _unique(path, pairs))
    except json.JSONDecodeError as exc:
        raise RunError(f"{path}:{exc.lineno}:{exc.colno}: expected JSON, found an error: "
                       f"{exc.msg}") from None
    except RecursionError:
        raise RunError(f"{path}: expected a run.json object of fields, found JSON nested "
                       f"too deep to read") from None
    if not isinstance(data, dict):
        raise RunError(f"{path}: expected a JSON object of run fields, found "
                       f"{type(data).__name__}")
    if data.get("format") != FORMAT:
        raise RunError(f"{path}: field 'format': expected '{FORMAT}', found "
                       f"{_text(data.get('format', 'nothing'))}")
    known = ["format", *FIELDS]
    for key in data:
        if key not in known:
            raise RunError(f"{path}: field '{key}': expected one of {', '.join(known)}, found "
                           f"an unknown field" + did_you_mean(key, known))
    if "mission" not in data:
        raise RunError(f"{path}: field 'mission': expected a path to a .mission file, "
                       f"found nothing")
    base = path.parent
    values: dict[str, Any] = {}
    for key, spec in FIELDS.items():
        if key not in data:
            continue
        value = data[key]
        if not spec.check(value):
            raise RunError(f"{path}: field '{key}': expected {spec.expected}, found "
                           f"{_text(value)}")
        values[spec.dest] = spec.convert(value, base)
    for name, value in values.get("param", []):
        _check_parameter(path, name, value)
    return values


def _check_parameter(path: Path, name: str, value: Any) -> None:
    """One entry of ``parameters``: checked as ``--param NAME=VALUE`` is (whether the .vepl
    declares NAME is the linker's to say, as for the option)."""
    if not NAME.match(name):
        raise RunError(f"{path}: field 'parameters': expected parameter names (a letter or _, "
                       f"then letters, digits, _), found {_text(name)}")
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise RunError(f"{path}: field 'parameters.{name}': expected a finite number, found "
                       f"{_text(value)}")
    try:
        parse_parameter(f"{name}={value!r}")
    except ValueError as exc:
        raise RunError(f"{path}: field 'parameters': {exc}") from None


def _reject_constant(path: Path, name: str) -> Any:
    raise RunError(f"{path}: expected finite numbers, found {name}")


def defer_defaults(parser: argparse.ArgumentParser) -> None:
    """Add ``--config`` and mark the defaults of the options a config file may set, so
    ``apply_run_config`` can tell a flag the user typed (which wins) from a default."""
    parser.add_argument("--config", type=Path, default=None, metavar="RUN_JSON",
                        help="take the run from a run.json (format rei-run/1, e.g. written by "
                             "`rei-gen generate --target launch`): mission, vepl, controller, "
                             "seed, duration, rates, noise, variation, monitor, parameters. "
                             "Options given explicitly on the command line override the "
                             "file (--param: name by name); MISSION may "
                             f"then be left out, and -o defaults to '{DEFAULT_OUTPUT}/' beside "
                             "the file. Fields: docs/generators.md")
    defaults = {spec.dest: parser.get_default(spec.dest) for spec in FIELDS.values()
                if spec.dest not in MERGED}
    parser.set_defaults(**{dest: value if isinstance(value, Unset) else Unset(value)
                           for dest, value in defaults.items()})


def apply_run_config(args: argparse.Namespace) -> argparse.Namespace:
    """``args`` with the config file's fields where the user gave no flag, and every
    remaining default filled in; RunError when the run is not fully described."""
    config = getattr(args, "config", None)
    fields = load_run_config(config) if config is not None else {}
    resolved = argparse.Namespace(**vars(args))
    for dest, value in vars(args).items():
        if isinstance(value, Unset):
            setattr(resolved, dest, fields.get(dest, value.value))
    for dest in MERGED:  # the file's entries first: an option for the same name wins
        setattr(resolved, dest, [*fields.get(dest, []), *getattr(args, dest, [])])
    if resolved.mission is None:
        raise RunError("rei run: expected a MISSION file or --config RUN_JSON, found neither")
    if getattr(resolved, "output", None) is None:
        if config is None:
            raise RunError("rei run: expected an output folder (-o DIR), found none")
        resolved.output = config.parent / DEFAULT_OUTPUT
    return resolved
