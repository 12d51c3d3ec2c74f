"""The parameter space of generated rooms: factors, their levels, presets, and validation.

A *factor* is one knob of the generator (room shape, size, object count, ...); its *levels*
are the values a suite may use. Both strategies (systematic and random) pick one level per
factor for each room, so a suite is a list of rows over one space. Levels are written as
short strings (``14x9``, ``25%``, ``yes``) because they appear verbatim on the command line,
in the index CSV and in the room's metadata comment.

This module must never touch files or random state: it only describes and validates.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from decimal import ROUND_CEILING, ROUND_FLOOR, Decimal

from rei.generators.errors import GenerationError
from rei.lang.room.model import BEHAVIOURS, WALKING_SPEEDS
from rei.lang.suggest import did_you_mean

FACTOR_NAMES: tuple[str, ...] = (
    "shape", "size", "objects", "mix", "humans", "vertices", "speed", "loop", "crossing",
    "goals", "spacing", "cycles", "behaviour", "heading", "max_speed", "stressor",
)

BEHAVIOUR_LEVELS = (*BEHAVIOURS, "mix")
"""A human behaviour for every human of a room, or ``mix``: yielding and social in turn."""
MIX_BEHAVIOURS = ("yielding", "social")
NO_LIMIT = "none"
NO_STRESSOR = "none"

SHAPES = ("rect", "L", "joined")
STRESSORS = ("none", "emerge", "oncoming", "crossing", "gap", "doorway", "standing")
"""One stress scenario on the robot's first leg (generators/rooms/stressors.py): a person
emerging from behind a corner, an oncoming person in a one-tile corridor, a cart crossing at
a right angle, a furniture row whose gap on the direct line is narrower than the robot, a
person stepping out of a doorway beside the route as the robot comes level, a person standing
in a one-tile corridor (on the phone, giving way to nobody) for a while."""
CROSSINGS = ("cross", "any")
YES_NO = ("yes", "no")

# Named mixes of the default catalogue's static types; a level may also list types
# joined by '+' ("table+box"), checked against the catalogue.
MIXES: Mapping[str, tuple[str, ...]] = {
    "mixed": ("table", "chair", "shelf", "box", "pillar"),
    "furniture": ("table", "chair", "shelf"),
    "clutter": ("box", "pillar", "chair"),
}

MAX_SIDE = 200
MAX_HUMANS = 20
MAX_VERTICES = 20
MAX_GOALS = 50
MAX_CYCLES = 100
MAX_ROBOT_SPEED = 10.0


class ParameterError(GenerationError):
    """A command-line level or a combination of levels cannot be generated."""

    def __init__(self, option: str, expected: str, found: str) -> None:
        self.option = option
        super().__init__(f"--{option}: expected {expected}, found {found}")


@dataclass(frozen=True)
class Factor:
    name: str
    levels: tuple[str, ...]


@dataclass(frozen=True)
class ParameterSpace:
    """One list of levels per factor, in FACTOR_NAMES order."""

    factors: tuple[Factor, ...]

    def levels(self, name: str) -> tuple[str, ...]:
        for factor in self.factors:
            if factor.name == name:
                return factor.levels
        raise KeyError(name)

    @property
    def grid_size(self) -> int:
        return math.prod(len(f.levels) for f in self.factors)

    def replaced(self, overrides: Mapping[str, tuple[str, ...]]) -> ParameterSpace:
        return ParameterSpace(tuple(Factor(f.name, overrides.get(f.name, f.levels))
                                    for f in self.factors))


PRESETS: Mapping[str, Mapping[str, tuple[str, ...]]] = {
    # Thesis 7.4.4: a small room, densely furnished; the robot crosses from one side to the
    # other. It is the demo's preset, so its rooms exercise what the requirements watch: a
    # reactive human crossing the robot's route, a final goal with a heading, a one-tile
    # doorway (the joined shape's door across 5 tiles) and a speed-limited mission (below
    # the Waffle's 0.26 m/s), each in some rooms.
    "small": {
        "shape": ("rect", "joined"), "size": ("7x5", "8x5"), "objects": ("6", "8"),
        "mix": ("mixed", "furniture"), "humans": ("1",), "vertices": ("2",),
        "speed": ("0.8",), "loop": ("yes",), "crossing": ("cross",), "goals": ("2",),
        "spacing": ("4",), "cycles": ("1", "2"), "behaviour": ("yielding", "social"),
        "heading": ("yes", "no"), "max_speed": ("none", "0.18"), "stressor": (NO_STRESSOR,),
    },
    # Thesis 7.4.5: a medium room, sparsely furnished, with one moving human.
    "medium": {
        "shape": ("rect", "L", "joined"), "size": ("12x8", "14x9", "16x10"),
        "objects": ("3", "5", "7"), "mix": ("mixed", "furniture", "clutter"),
        "humans": ("1",), "vertices": ("3", "4", "5"), "speed": ("0.6", "1.0"),
        "loop": ("yes", "no"), "crossing": ("cross", "any"), "goals": ("3", "4"),
        "spacing": ("5", "8"), "cycles": ("1", "2"), "behaviour": ("social", "yielding"),
        "heading": ("no", "yes"), "max_speed": (NO_LIMIT,), "stressor": (NO_STRESSOR,),
    },
    # Thesis 7.4.6: a fairly large room.
    "large": {
        "shape": ("rect", "L", "joined"), "size": ("24x16", "30x20"),
        "objects": ("15", "30"), "mix": ("mixed", "furniture"), "humans": ("0", "1", "2"),
        "vertices": ("4", "6"), "speed": ("0.8", "1.2"), "loop": ("yes",),
        "crossing": ("cross", "any"), "goals": ("3", "5"), "spacing": ("10", "16"),
        "cycles": ("1",), "behaviour": ("mix", "social"), "heading": ("no",),
        "max_speed": (NO_LIMIT,), "stressor": (NO_STRESSOR,),
    },
    # Rooms that punish late perception and a planner blind to the robot's footprint: each
    # puts one stressor on the first leg, timed from the robot's planned arrival. The
    # people they add yield (so a careful navigator can pass), but for the standing one, who
    # gives way to nobody for a while (a careful navigator waits or recovers), and no other
    # human walks, so what fails is the stressor's doing. The systematic design lists the
    # stressors first (they vary fastest), which is how `rei demo` takes one room of each.
    # `doorway` is a level of the factor but not of the preset: it needs the straight line
    # between the first goals on the floor, which a joined room seldom gives (`--stressor
    # doorway`).
    "stress": {
        "shape": ("rect", "L"), "size": ("10x6", "12x7"), "objects": ("3", "5"),
        "mix": ("furniture", "mixed"), "humans": ("0",), "vertices": ("2",),
        "speed": ("1.0", "0.8"), "loop": ("no",), "crossing": ("any",), "goals": ("2",),
        "spacing": ("6",), "cycles": ("1",), "behaviour": ("yielding",), "heading": ("no",),
        "max_speed": (NO_LIMIT,),
        "stressor": ("emerge", "crossing", "gap", "standing", "oncoming"),
    },
}


def preset_space(name: str) -> ParameterSpace:
    if name not in PRESETS:
        raise ParameterError("preset", f"one of {', '.join(PRESETS)}", f"'{name}'")
    return ParameterSpace(tuple(Factor(n, PRESETS[name][n]) for n in FACTOR_NAMES))


@dataclass(frozen=True)
class RoomParameters:
    """One row of a suite: a level of every factor, parsed and range-checked."""

    shape: str
    width: int
    height: int
    objects: int | None
    """An object count, or None when ``density`` gives it as a share of the floors."""
    density: float | None
    mix: tuple[str, ...]
    humans: int
    vertices: int
    speed: float
    loop: bool
    crossing: str
    goals: int
    spacing: float
    cycles: int
    behaviour: str
    """One of BEHAVIOUR_LEVELS."""
    heading: bool
    """Whether the final goal must be reached facing a given way."""
    max_speed: float | None
    """The mission's speed limit (m/s), None for the drive's own."""
    levels: tuple[tuple[str, str], ...]
    """The levels as written, factor by factor (for the index and the metadata)."""
    stressor: str = NO_STRESSOR
    """One of STRESSORS."""

    def level(self, name: str) -> str:
        return dict(self.levels)[name]

    def object_count(self, floors: int) -> int:
        if self.objects is not None:
            return self.objects
        assert self.density is not None
        return int(math.floor(self.density * floors + 0.5))


def _int(option: str, text: str, low: int, high: int) -> int:
    try:
        value = int(text)
    except ValueError:
        raise ParameterError(option, f"a whole number from {low} to {high}", f"'{text}'") from None
    if not low <= value <= high:
        raise ParameterError(option, f"a whole number from {low} to {high}", f"{value}")
    return value


def _float(option: str, text: str, low: float, high: float, low_open: bool = True) -> float:
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    bad_low = value <= low if low_open else value < low
    if not math.isfinite(value) or bad_low or value > high:
        bracket = "(" if low_open else "["
        raise ParameterError(option, f"a finite number in {bracket}{low:g}, {high:g}]",
                             f"'{text}'")
    return value


def _walking_speed(text: str) -> float:
    """Humans walk at human speeds: a faster 'human' is a test no navigator can pass."""
    low, high = WALKING_SPEEDS
    return _float("speed", text, low, high, low_open=False)


def parse_row(levels: Mapping[str, str], static_names: tuple[str, ...]) -> RoomParameters:
    """Parse one level per factor; ParameterError names the option when a level is bad."""
    size = levels["size"].lower().split("x")
    if len(size) != 2:
        raise ParameterError("size", "WIDTHxHEIGHT in tiles, e.g. 14x9", f"'{levels['size']}'")
    width = _int("size", size[0], 3, MAX_SIDE)
    height = _int("size", size[1], 3, MAX_SIDE)
    shape = levels["shape"]
    if shape not in SHAPES:
        raise ParameterError("shape", f"one of {', '.join(SHAPES)}", f"'{shape}'")
    if shape != "rect" and min(width, height) < 4:
        raise ParameterError("size", f"at least 4x4 tiles for the '{shape}' shape",
                             f"'{levels['size']}'")
    objects_text = levels["objects"]
    objects: int | None = None
    density: float | None = None
    if objects_text.endswith("%"):
        density = _float("objects", objects_text[:-1], 0.0, 100.0, low_open=False) / 100.0
    else:
        objects = _int("objects", objects_text, 0, MAX_SIDE * MAX_SIDE)
    mix_text = levels["mix"]
    mix = MIXES.get(mix_text) or tuple(t for t in mix_text.split("+") if t)
    for type_name in mix:
        if type_name not in static_names:
            raise ParameterError("mix", f"a named mix ({', '.join(MIXES)}) or static catalogue "
                                        f"types joined by '+' ({', '.join(static_names)})",
                                 f"'{type_name}' in '{mix_text}'")
    if not mix:
        raise ParameterError("mix", "at least one object type", f"'{mix_text}'")
    loop_text = levels["loop"]
    if loop_text not in YES_NO:
        raise ParameterError("loop", "yes or no", f"'{loop_text}'")
    crossing = levels["crossing"]
    if crossing not in CROSSINGS:
        raise ParameterError("crossing", f"one of {', '.join(CROSSINGS)}", f"'{crossing}'")
    behaviour = levels["behaviour"]
    if behaviour not in BEHAVIOUR_LEVELS:
        raise ParameterError("behaviour", f"one of {', '.join(BEHAVIOUR_LEVELS)}",
                             f"'{behaviour}'" + did_you_mean(behaviour, BEHAVIOUR_LEVELS))
    heading_text = levels["heading"]
    if heading_text not in YES_NO:
        raise ParameterError("heading", "yes or no", f"'{heading_text}'")
    limit_text = levels["max_speed"]
    max_speed = None if limit_text == NO_LIMIT else _float("max-speed", limit_text, 0.0,
                                                             MAX_ROBOT_SPEED)
    stressor = levels["stressor"]
    if stressor not in STRESSORS:
        raise ParameterError("stressor", f"one of {', '.join(STRESSORS)}",
                             f"'{stressor}'" + did_you_mean(stressor, STRESSORS))
    return RoomParameters(
        stressor=stressor, shape=shape, width=width, height=height, objects=objects,
        density=density, mix=mix,
        humans=_int("humans", levels["humans"], 0, MAX_HUMANS),
        vertices=_int("vertices", levels["vertices"], 2, MAX_VERTICES),
        speed=_walking_speed(levels["speed"]),
        loop=loop_text == "yes", crossing=crossing,
        goals=_int("goals", levels["goals"], 2, MAX_GOALS),
        spacing=_float("spacing", levels["spacing"], 0.0, float(2 * MAX_SIDE)),
        cycles=_int("cycles", levels["cycles"], 1, MAX_CYCLES),
        behaviour=behaviour, heading=heading_text == "yes", max_speed=max_speed,
        levels=tuple((n, levels[n]) for n in FACTOR_NAMES),
    )


def check_level(name: str, text: str, reference: Mapping[str, str],
                static_names: tuple[str, ...]) -> None:
    """Refuse a level ``parse_row`` would refuse for its own factor (``--humans abc``), with
    the same ParameterError. The level is parsed in the ``reference`` row (one level per
    factor); a refusal naming another option is a combination (e.g. an L shape in a 3x3
    room), not a bad level, and is left to the generator."""
    option = name.replace("_", "-")
    row = {**reference, name: text}
    if name == "size":
        row["shape"] = "rect"  # the shape allowing every size parse_row accepts
    try:
        parse_row(row, static_names)
    except ParameterError as exc:
        if exc.option == option:
            raise


def floor_count(params: RoomParameters) -> int:
    """Floors of the shape; the shapes are sized deterministically so this is exact."""
    w, h = params.width, params.height
    if params.shape == "L":
        return w * h - (w // 2) * (h // 2)
    if params.shape == "joined":
        across = h if w >= h else w  # the dividing wall runs across the shorter side
        return w * h - across + door_width(across)
    return w * h


def door_width(across: int) -> int:
    return 2 if across >= 6 else 1


def refuse_impossible(params: RoomParameters) -> None:
    """Raise ParameterError for a row no construction can satisfy (checked before any work)."""
    w, h = params.width, params.height
    # The longest straight distance between two floor centres in the bounding box.
    reach = math.hypot(w - 1, h - 1)
    if params.spacing > reach:
        raise ParameterError("spacing", f"at most {reach:.1f} m between goals in a {w}x{h} room "
                                        f"(its diagonal)", f"{params.spacing:g} m")
    floors = floor_count(params)
    objects = params.object_count(floors)
    reserved = params.goals + params.humans * params.vertices
    path = (params.goals - 1) * max(0, math.ceil(params.spacing) - 1)
    room_for = floors - reserved - path
    if objects > room_for:
        option = "objects"
        raise ParameterError(option, f"at most {max(room_for, 0)} objects in a {params.shape} "
                                     f"{w}x{h} room ({floors} floors, {reserved} kept for goals "
                                     f"and trajectory vertices, about {path} for the robot's "
                                     f"path)", f"{objects}")
    if params.humans and floors - params.goals < params.humans * 2:
        raise ParameterError("humans", f"at most {(floors - params.goals) // 2} humans in a "
                                       f"{w}x{h} room", f"{params.humans}")



# -- continuous levels, for search ----------------------------------------------------------

CONTINUOUS_FACTORS: Mapping[str, tuple[float, float, bool]] = {
    "speed": (*WALKING_SPEEDS, False),
    "spacing": (0.0, float(2 * MAX_SIDE), True),
    "max_speed": (0.0, MAX_ROBOT_SPEED, True),
}
"""Factors whose level is a number, so a row may carry any value in a range (`rei search`
writes ``LOW:HIGH`` for them): (lowest, highest, lowest excluded). The numbers are the same
limits ``parse_row`` applies, so an interval inside them only ever gives parseable levels."""

LEVEL_DECIMALS = 3
"""A continuous level is written with this many decimals: the same bytes on every machine."""


@dataclass(frozen=True)
class Interval:
    """A continuous factor's range of values, both ends included."""

    factor: str
    low: float
    high: float

    def level(self, fraction: float) -> str:
        """The level at ``fraction`` (0..1) of the way from low to high, rounded to
        LEVEL_DECIMALS and kept inside the interval."""
        value = self.low + min(max(fraction, 0.0), 1.0) * (self.high - self.low)
        value = min(max(round(value, LEVEL_DECIMALS), self.low), self.high)
        text = f"{value:.{LEVEL_DECIMALS}f}".rstrip("0").rstrip(".")
        return text or "0"


def is_interval(text: str) -> bool:
    """A level written LOW:HIGH (a range to search) rather than one value."""
    return ":" in text


def parse_interval(name: str, text: str) -> Interval:
    """``LOW:HIGH`` for a continuous factor, checked against the factor's own limits."""
    option = name.replace("_", "-")
    if name not in CONTINUOUS_FACTORS:
        numeric = ", ".join(n.replace("_", "-") for n in CONTINUOUS_FACTORS)
        raise ParameterError(option, f"levels without ':' (only {numeric} take a LOW:HIGH "
                                     f"range)", f"'{text}'")
    return parse_range(option, name, text, *CONTINUOUS_FACTORS[name])


def parse_range(option: str, name: str, text: str, low_limit: float, high_limit: float,
                low_open: bool) -> Interval:
    """``LOW:HIGH`` within [low_limit, high_limit] (low_limit excluded when ``low_open``),
    an Interval called ``name``; ParameterError naming ``--option`` otherwise. Also the
    ranges of a search's scenario parameters (generators/rooms/scenario.py)."""
    parts = text.split(":")
    if len(parts) != 2:
        raise ParameterError(option, "a range LOW:HIGH, e.g. 0.5:1.4", f"'{text}'")
    low = _float(option, parts[0].strip(), low_limit, high_limit, low_open)
    high = _float(option, parts[1].strip(), low_limit, high_limit, low_open)
    if not low < high:
        raise ParameterError(option, "a range LOW:HIGH with LOW below HIGH", f"'{text}'")
    # Levels are written with LEVEL_DECIMALS: the ends are rounded inwards to that precision
    # (low up, high down), so every level drawn is inside what was typed and parseable.
    low, high = _rounded(low, ROUND_CEILING), _rounded(high, ROUND_FLOOR)
    if not low < high:
        raise ParameterError(option, f"a range LOW:HIGH with LOW below HIGH once both are "
                                     f"rounded inwards to {LEVEL_DECIMALS} decimals (levels "
                                     f"are written with {LEVEL_DECIMALS})", f"'{text}'")
    return Interval(name, low, high)


def _rounded(value: float, rounding: str) -> float:
    step = Decimal(1).scaleb(-LEVEL_DECIMALS)
    return float(Decimal(repr(value)).quantize(step, rounding=rounding))
