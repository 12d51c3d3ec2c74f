"""The event log of a run: one row per signal with time, signal, utility, running total
utility and the objects involved (thesis 6.1.5), written as CSV. Never reorders rows: they
are in the order the automata raised the signals. A run with injected faults has one more
column, ``faults``: those active at the sample the signal fired on (';'-joined), so each
signal can be read against the lie the robot was told; a run without keeps five columns."""

from __future__ import annotations

import csv
from dataclasses import dataclass, field
from pathlib import Path

from rei.generators.output import open_output

COLUMNS = ("time", "signal", "utility", "total_utility", "objects")
FAULT_COLUMN = "faults"


@dataclass(frozen=True)
class SignalRow:
    time: float
    signal: str
    utility: float
    total_utility: float
    objects: tuple[str, ...]
    faults: tuple[str, ...] = ()
    """The injected faults active when the signal fired."""


@dataclass
class SignalLog:
    utilities: dict[str, float]
    rows: list[SignalRow] = field(default_factory=list)
    total: float = 0.0
    with_faults: bool = False
    """The run injected faults: the CSV has the ``faults`` column."""

    def add(self, signal: str, time: float, objects: tuple[str, ...],
            faults: tuple[str, ...] = ()) -> SignalRow:
        utility = self.utilities[signal]
        self.total += utility
        row = SignalRow(time, signal, utility, self.total, objects, faults)
        self.rows.append(row)
        return row

    def counts(self) -> dict[str, int]:
        counts = dict.fromkeys(self.utilities, 0)
        for r in self.rows:
            counts[r.signal] += 1
        return counts

    def write_csv(self, path: str | Path) -> None:
        with open_output(path, newline="") as handle:  # never written through a link
            writer = csv.writer(handle, lineterminator="\n")
            writer.writerow(COLUMNS + ((FAULT_COLUMN,) if self.with_faults else ()))
            for r in self.rows:
                row = (repr(r.time), r.signal, f"{r.utility:g}", f"{r.total_utility:g}",
                       ";".join(r.objects))
                writer.writerow(row + ((";".join(r.faults),) if self.with_faults else ()))


def read_csv(path: str | Path) -> list[SignalRow]:
    with open(path, newline="", encoding="utf-8") as handle:
        reader = csv.DictReader(handle)
        return [SignalRow(float(r["time"]), r["signal"], float(r["utility"]),
                          float(r["total_utility"]),
                          tuple(r["objects"].split(";")) if r["objects"] else (),
                          tuple(r[FAULT_COLUMN].split(";")) if r.get(FAULT_COLUMN) else ())
                for r in reader]
