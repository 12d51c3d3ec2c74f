"""A suite of generated rooms: design rows -> constructed plans -> checked text -> files.

Every pair is checked with ``rei.lang.workspace.Workspace`` (exactly the `rei-gen check`
rules) before anything is written; a pair that fails is rejected and counted, and the room
is rebuilt from a fresh random stream, a bounded number of times. The whole suite is built
in memory first, so a refused request leaves no files behind.

Randomness: one ``random.Random`` per (seed, room index, attempt), derived by hashing, so
the same seed and version give byte-identical files in any process.
"""

from __future__ import annotations

import csv
import io
import random
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from rei.catalogue import default_catalogue
from rei.generators.errors import GenerationError
from rei.generators.output import write_atomic
from rei.generators.rooms.construct import AttemptFailed, CatalogueFacts, RoomPlan, construct
from rei.generators.rooms.descriptors import DESCRIPTOR_NAMES
from rei.generators.rooms.design import Strategy, SuiteDesign, derived_seed, design_suite
from rei.generators.rooms.space import (
    FACTOR_NAMES,
    ParameterError,
    ParameterSpace,
    RoomParameters,
    parse_row,
    refuse_impossible,
)
from rei.generators.rooms.stressors import MOVER_KINDS, side_of
from rei.generators.rooms.writer import Provenance, mission_text, room_text
from rei.lang.errors import Diagnostic
from rei.lang.workspace import Workspace

INDEX_FILE = "index.csv"
COVERAGE_FILE = "coverage.txt"
MAX_ATTEMPTS = 40


@dataclass(frozen=True)
class SuiteRequest:
    space: ParameterSpace
    strategy: Strategy
    count: int | None
    seed: int
    max_grid: int = 256
    design: str = "auto"
    prefix: str = "room"
    max_attempts: int = MAX_ATTEMPTS
    version: str = "0"


@dataclass(frozen=True)
class GeneratedPair:
    index: int
    name: str
    room_file: str
    mission_file: str
    room_text: str
    mission_text: str
    params: RoomParameters
    plan: RoomPlan
    design_row: int
    attempts: int
    rejected: int
    """Candidates the checker refused (construction failures are counted in ``attempts``)."""


@dataclass
class StageTimes:
    """Seconds spent per stage, for the benchmark (never written into the suite)."""

    construct: float = 0.0
    text: float = 0.0
    check: float = 0.0
    write: float = 0.0
    failures: dict[str, int] = field(default_factory=dict)


@dataclass(frozen=True)
class Suite:
    request: SuiteRequest
    design: SuiteDesign
    pairs: tuple[GeneratedPair, ...]


def check_pair(room_path: Path, room_src: str, mission_path: Path, mission_src: str
               ) -> list[Diagnostic]:
    """Every error `rei-gen check` would report for the pair, without touching the disk."""
    workspace = Workspace(overlays={str(room_path.resolve()): room_src,
                                    str(mission_path.resolve()): mission_src})
    return [d for d in workspace.check(room_path) + workspace.check(mission_path) if d.is_error]


def rows_of(request: SuiteRequest) -> tuple[SuiteDesign, list[tuple[int, RoomParameters]]]:
    """The design and, per room, its design row and parsed parameters (refusals raised here)."""
    if request.count is not None and request.count <= 0:
        raise ParameterError("count", "a whole number of rooms of at least 1",
                             f"{request.count}")
    design, count = design_suite(request.space, request.strategy, request.count, request.seed,
                                 request.max_grid, request.design)
    static_names = tuple(default_catalogue().names("static"))
    parsed: dict[tuple[int, ...], RoomParameters] = {}
    out = []
    for index in range(count):
        row_index = index % len(design.rows)
        row = design.rows[row_index]
        if row not in parsed:
            levels = {f.name: f.levels[k] for f, k in zip(request.space.factors, row, strict=False)}
            params = parse_row(levels, static_names)
            refuse_impossible(params)
            parsed[row] = params
        out.append((row_index, parsed[row]))
    return design, out


def generate(request: SuiteRequest, out_dir: Path, times: StageTimes | None = None,
             progress: Callable[[int, int], None] | None = None) -> Suite:
    """Build and check every pair in memory; GenerationError when a room cannot be built.
    ``progress(done, total)`` is called after each pair (a display; it changes nothing)."""
    times = times if times is not None else StageTimes()
    design, rows = rows_of(request)
    facts = CatalogueFacts.of(default_catalogue())
    width = max(4, len(str(len(rows))))
    pairs = []
    movers = 0  # mover rooms so far: their sides alternate (stressors.side_of)
    for index, (row_index, params) in enumerate(rows):
        name = f"{request.prefix}_{index + 1:0{width}d}"
        side = None
        if params.stressor in MOVER_KINDS:
            side = side_of(request.seed, movers)
            movers += 1
        room_file, mission_file = f"{name}.room", f"{name}.mission"
        rejected = 0
        reasons: dict[tuple[str, str], int] = {}
        for attempt in range(request.max_attempts):
            rng = random.Random(derived_seed(request.seed, "room", index, attempt))
            t0 = time.perf_counter()
            try:
                plan = construct(params, facts, rng, side)
            except AttemptFailed as exc:
                times.construct += time.perf_counter() - t0
                key = (exc.option, exc.reason)
                reasons[key] = reasons.get(key, 0) + 1
                times.failures[exc.option] = times.failures.get(exc.option, 0) + 1
                continue
            t1 = time.perf_counter()
            provenance = Provenance(request.version, request.strategy, design.design,
                                    request.seed, index + 1, row_index + 1, attempt + 1)
            rtext = room_text(name, plan, provenance)
            mtext = mission_text(f"{name}_mission", room_file, plan)
            t2 = time.perf_counter()
            errors = check_pair(out_dir / room_file, rtext, out_dir / mission_file, mtext)
            t3 = time.perf_counter()
            times.construct += t1 - t0
            times.text += t2 - t1
            times.check += t3 - t2
            if errors:
                rejected += 1
                key = ("checker", f"the checker refused it: {errors[0]}")
                reasons[key] = reasons.get(key, 0) + 1
                times.failures["checker"] = times.failures.get("checker", 0) + 1
                continue
            pairs.append(GeneratedPair(index + 1, name, room_file, mission_file, rtext, mtext,
                                       params, plan, row_index + 1, attempt + 1, rejected))
            if progress is not None:
                progress(len(pairs), len(rows))
            break
        else:
            levels = " ".join(f"{k}={v}" for k, v in params.levels)
            (option, reason), times_seen = max(reasons.items(), key=lambda kv: (kv[1], kv[0]))
            raise GenerationError(
                f"--{option}: expected a room that can be built within "
                f"{request.max_attempts} attempts, found every attempt failing; most often "
                f"({times_seen} times): {reason} "
                f"(room {index + 1}: {levels}; fewer objects, humans or goals, a smaller "
                f"--spacing or a larger --size make it possible)")
    return Suite(request, design, tuple(pairs))


INDEX_COLUMNS: tuple[str, ...] = (
    "index", "room", "mission", "name", "strategy", "design", "design_row", "seed", "attempts",
    "rejected", *FACTOR_NAMES, "floors", "object_count", *DESCRIPTOR_NAMES)


def index_csv(suite: Suite) -> str:
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(INDEX_COLUMNS)
    for pair in suite.pairs:
        levels = dict(pair.params.levels)
        row = [str(pair.index), pair.room_file, pair.mission_file, pair.name,
               suite.request.strategy, suite.design.design, str(pair.design_row),
               str(suite.request.seed), str(pair.attempts), str(pair.rejected)]
        row += [levels[n] for n in FACTOR_NAMES]
        row += [str(len(pair.plan.floors)), str(len(pair.plan.objects))]
        row += list(pair.plan.descriptors.as_row().values())
        writer.writerow(row)
    return buffer.getvalue()


def write_suite(suite: Suite, out_dir: Path, coverage: str, times: StageTimes | None = None
                ) -> list[Path]:
    t0 = time.perf_counter()
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
        written = []
        for pair in suite.pairs:
            for file_name, text in ((pair.room_file, pair.room_text),
                                    (pair.mission_file, pair.mission_text)):
                path = out_dir / file_name
                write_atomic(path, text.encode("utf-8"))
                written.append(path)
        write_atomic(out_dir / INDEX_FILE, index_csv(suite).encode("utf-8"))
        write_atomic(out_dir / COVERAGE_FILE, coverage.encode("utf-8"))
    except OSError as exc:
        raise GenerationError(f"-o {out_dir}: expected a writable folder, found {exc}") from None
    if times is not None:
        times.write += time.perf_counter() - t0
    return written

