"""A search's candidates: a suite row (levels, continuous values, layout seed) -> a checked
.room / .mission pair in memory -> files on disk with one index CSV for the campaign.

A candidate is built by the room generator exactly as `rei-gen rooms` builds a room
(``rei.generators.rooms.generate`` on a one-level-per-factor space, the layout seed as the
suite seed): valid by construction and checked with the `rei-gen check` rules before it is
written. A row's scenario parameters (start phase, stressor shift, placement shifts,
sensor faults:
generators/rooms/scenario.py) are then put into the pair, which is written and checked
again. A row the generator refuses (an impossible combination, or scenario values the room
cannot take) is a candidate with a ``problem`` and no files; it never runs. This module
never runs a simulation.
"""

from __future__ import annotations

import csv
import io
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path

from rei.catalogue import default_catalogue
from rei.generators.errors import GenerationError
from rei.generators.output import write_atomic
from rei.generators.rooms.design import SearchRow
from rei.generators.rooms.scenario import ScenarioRefused, apply_to_plan, comment, with_faults
from rei.generators.rooms.space import Factor, ParameterSpace
from rei.generators.rooms.suite import (
    INDEX_COLUMNS,
    GeneratedPair,
    Suite,
    SuiteRequest,
    check_pair,
    generate,
)
from rei.generators.rooms.suite import index_csv as suite_index_csv
from rei.generators.rooms.writer import Provenance, mission_text, room_text

CANDIDATES = "candidates"
"""``DIR/candidates/``: every built candidate's .room and .mission, and index.csv."""
INDEX = "index.csv"
SEARCH_COLUMNS = ("candidate", "batch", "search", "preset", "scenario")


@dataclass(frozen=True)
class Candidate:
    number: int
    """1-based, in proposal order over the whole search."""
    batch: int
    point: tuple[float, ...]
    row: SearchRow
    suite: Suite | None
    problem: str = ""
    """Why the generator refused the row ('' when it was built)."""

    @property
    def name(self) -> str:
        return f"cand{self.number:04d}"

    @property
    def pair(self) -> GeneratedPair | None:
        return self.suite.pairs[0] if self.suite is not None else None

    def descriptor(self, name: str) -> float:
        pair = self.pair
        return float(getattr(pair.plan.descriptors, name)) if pair is not None else 0.0


def build_candidate(row: SearchRow, number: int, batch: int, point: tuple[float, ...],
                    folder: Path, version: str) -> Candidate:
    """The candidate's pair, built and checked in memory (nothing is written here)."""
    space = ParameterSpace(tuple(Factor(name, (level,)) for name, level in row.levels))
    request = SuiteRequest(space=space, strategy="random", count=1, seed=row.layout,
                           prefix=f"cand{number:04d}", version=version)
    try:
        suite = generate(request, folder)
        if row.scenario:
            suite = with_scenario(suite, row, folder)
    except (GenerationError, ScenarioRefused) as exc:
        return Candidate(number, batch, point, row, None, str(exc))
    return Candidate(number, batch, point, row, suite)


def with_scenario(suite: Suite, row: SearchRow, folder: Path) -> Suite:
    """The suite's pair with the row's scenario parameters put in (start phase, stressor
    shift, placement shifts, faults), written again and checked with the `rei-gen check` rules;
    ScenarioRefused when the room cannot take them or the checker refuses the result."""
    pair = suite.pairs[0]
    values = {name: float(text) for name, text in row.scenario}
    plan = apply_to_plan(pair.plan, values, default_catalogue())
    request = suite.request
    provenance = Provenance(request.version, request.strategy, suite.design.design,
                            request.seed, pair.index, pair.design_row, pair.attempts)
    lines = room_text(pair.name, plan, provenance).split("\n")
    at = next(k for k, line in enumerate(lines) if line.startswith("// descriptors:"))
    room = "\n".join([*lines[:at + 1], comment(values), *lines[at + 1:]])
    mission = with_faults(mission_text(f"{pair.name}_mission", pair.room_file, plan), values)
    errors = check_pair(folder / pair.room_file, room, folder / pair.mission_file, mission)
    if errors:
        raise ScenarioRefused(f"the checker refused the candidate with "
                              f"{comment(values)[3:]}: {errors[0]}")
    return replace(suite, pairs=(replace(pair, room_text=room, mission_text=mission,
                                         plan=plan),))


def write_candidates(candidates: Sequence[Candidate], folder: Path, strategy: str,
                     preset: str) -> Path:
    """Write every built candidate's files and the index CSV of them all (the campaign's
    input: its parameter and descriptor columns go into every run's results row)."""
    folder.mkdir(parents=True, exist_ok=True)
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow((*INDEX_COLUMNS, *SEARCH_COLUMNS))
    for candidate in candidates:
        pair = candidate.pair
        if pair is None or candidate.suite is None:
            continue
        write_atomic(folder / pair.room_file, pair.room_text.encode("utf-8"))
        write_atomic(folder / pair.mission_file, pair.mission_text.encode("utf-8"))
        row = next(csv.DictReader(io.StringIO(suite_index_csv(candidate.suite))))
        row.update(index=str(candidate.number), design="search", strategy=strategy)
        writer.writerow([row[c] for c in INDEX_COLUMNS]
                        + [candidate.name, str(candidate.batch), strategy, preset,
                           " ".join(f"{k}={v}" for k, v in candidate.row.scenario)])
    path = folder / INDEX
    write_atomic(path, out.getvalue().encode("utf-8"))
    return path
