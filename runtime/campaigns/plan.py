"""Planning a campaign: which missions run, how often, with which derived seed and run id.

Inputs are .mission files, folders (searched for .mission files) or the index CSV of a suite
written by `rei-gen rooms` (columns ``room`` and ``mission`` relative to the CSV, plus parameter
and difficulty-descriptor columns, carried into every run of that mission). The plan is pure
data and deterministic: the same inputs, seed and repeat count give the same runs, seeds and ids
on any machine, which is what makes resuming safe. This module must never run anything.
"""

from __future__ import annotations

import csv
import hashlib
import io
import math
import re
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from rei.lang.source import UnreadableInput, bounded_text
from rei.lang.vepl.document import load_vepl
from rei.lang.vepl_parameters import parameter_options, parameter_values
from rei.runtime.campaigns.errors import CampaignError
from rei.runtime.observation.monitor.functions import load_functions

PLAN_VERSION = 1


@dataclass(frozen=True)
class RunSpec:
    """One run of one mission: everything the run command needs, and the row's identity."""

    run_id: str
    mission_file: str
    """Absolute path of the .mission file."""
    mission_key: str
    """FOLDER/NAME.mission of the mission file: seeds derive from it, so a mission gets the
    same seeds however it is named on the command line and wherever the suite lies."""
    group: str
    """The group of the mission for tables: the suite's preset, else the input it came from."""
    repeat: int
    seed: int
    controller: str | None = None
    vepl: str | None = None
    duration: float | None = None
    parameters: dict[str, Any] = field(default_factory=dict)
    """Parameter and difficulty-descriptor columns of the suite's index (empty otherwise)."""
    static_pair: bool = False
    """This run is the static twin of run ``pair``: its mission file is the original's twin
    in the same room without humans and dynamic objects (``--pair-static``), same seed."""
    pair: str = ""
    """With ``--pair-static``: the run id of the run with people that this run (the run
    itself, or its static twin) belongs to; empty in an unpaired campaign."""
    variation: bool = True
    """False: `rei run --no-variation` (no seeded start-pose jitter: the exact declared scene)."""
    functions: str | None = None
    """`rei run --functions`: the module of the specification's user functions."""
    record: bool = False
    """`rei run --record`: the run also writes recording.mcap."""
    faults: tuple[str, ...] = ()
    """`rei run --fault`: fault entries as written, added to the mission's own."""
    vepl_parameters: tuple[tuple[str, float], ...] = ()
    """`rei run --param`: the specification's parameter values in place of the file's, sorted
    by name (a resume with other values is another campaign)."""

    def to_json(self) -> dict[str, Any]:
        data = {"run_id": self.run_id, "mission_file": self.mission_file,
                "mission_key": self.mission_key, "group": self.group, "repeat": self.repeat,
                "seed": self.seed, "controller": self.controller, "vepl": self.vepl,
                "duration": self.duration, "parameters": dict(self.parameters)}
        if self.pair:  # unpaired plans keep the shape earlier versions wrote and read
            data.update(static_pair=self.static_pair, pair=self.pair)
        if not self.variation:
            data["variation"] = False
        if self.functions:
            data["functions"] = self.functions
        if self.record:
            data["record"] = True
        if self.faults:
            data["faults"] = list(self.faults)
        if self.vepl_parameters:
            data["vepl_parameters"] = dict(self.vepl_parameters)
        return data

    @staticmethod
    def from_json(data: dict[str, Any]) -> RunSpec:
        if "faults" in data:
            data = {**data, "faults": tuple(data["faults"])}
        if "vepl_parameters" in data:
            data = {**data, "vepl_parameters": parameter_values(data["vepl_parameters"])}
        return RunSpec(**data)

    def run_argv(self, out_dir: str) -> list[str]:
        """The arguments of `rei run` for this run (after the program name)."""
        argv = ["run", self.mission_file, "-o", out_dir, "--seed", str(self.seed)]
        if self.controller:
            argv += ["--controller", self.controller]
        if self.vepl:
            argv += ["--vepl", self.vepl]
        if self.duration is not None:
            argv += ["--duration", _number(self.duration)]
        if not self.variation:
            argv.append("--no-variation")
        if self.functions:
            argv += ["--functions", self.functions]
        if self.record:
            argv.append("--record")
        for fault in self.faults:
            argv += ["--fault", fault]
        return argv + parameter_options(self.vepl_parameters)


@dataclass(frozen=True)
class CampaignPlan:
    version: int
    seed: int
    repeat: int
    runs: tuple[RunSpec, ...]

    def to_json(self) -> dict[str, Any]:
        return {"version": self.version, "seed": self.seed, "repeat": self.repeat,
                "runs": [r.to_json() for r in self.runs]}

    @staticmethod
    def from_json(data: dict[str, Any]) -> CampaignPlan:
        return CampaignPlan(version=int(data["version"]), seed=int(data["seed"]),
                            repeat=int(data["repeat"]),
                            runs=tuple(RunSpec.from_json(r) for r in data["runs"]))


@dataclass(frozen=True)
class _MissionEntry:
    path: Path
    key: str
    group: str
    parameters: dict[str, Any]


def derive_seed(campaign_seed: int, mission_key: str, repeat: int) -> int:
    """A seed per (mission, repeat): independent of order, worker count and the other inputs."""
    digest = hashlib.sha256(f"rei-campaign:{campaign_seed}:{mission_key}:{repeat}".encode())
    return int.from_bytes(digest.digest()[:4], "big") & 0x7FFFFFFF


def _number(value: float) -> str:
    return str(int(value)) if float(value).is_integer() else repr(float(value))


def _cell(text: str) -> Any:
    """Index CSV cells: numbers become numbers (so descriptors can be plotted), others stay."""
    try:
        number = float(text)
    except ValueError:
        return text
    if not math.isfinite(number):
        return text
    return int(number) if number.is_integer() and "." not in text and "e" not in text.lower() \
        else number


def _read_index(path: Path) -> list[_MissionEntry]:
    try:
        reader = csv.DictReader(io.StringIO(bounded_text(path), newline=""))
        fields = reader.fieldnames or []
        rows = list(reader)
    except (UnreadableInput, csv.Error) as exc:
        raise CampaignError(f"{path}: cannot read the suite index: {exc}") from None
    if "mission" not in fields:
        raise CampaignError(f"{path}:1: expected an index CSV with a 'mission' column "
                            f"(as written by `rei-gen rooms`), found columns {fields}")
    entries = []
    for line, row in enumerate(rows, start=2):
        rel = (row.get("mission") or "").strip()
        if not rel:
            raise CampaignError(f"{path}:{line}: the 'mission' column is empty")
        mission = (path.parent / rel).resolve()
        if not mission.is_file():
            raise CampaignError(f"{path}:{line}: mission file '{rel}' does not exist "
                                f"(looked for {mission})")
        params = {k: _cell(v) for k, v in row.items()
                  if k not in ("mission", "room") and k is not None and v is not None}
        group = str(params.get("preset") or path.parent.name)
        entries.append(_MissionEntry(mission, _key(mission), group, params))
    return entries


def _key(path: Path) -> str:
    return f"{path.parent.name}/{path.name}"


def _expand(inputs: list[Path]) -> list[_MissionEntry]:
    entries: list[_MissionEntry] = []
    for given in inputs:
        if given.is_dir():
            found = sorted(given.rglob("*.mission"))
            if not found:
                raise CampaignError(f"{given}: expected a folder with .mission files, found none")
            entries.extend(_MissionEntry(p.resolve(), _key(p.resolve()), given.resolve().name, {})
                           for p in found)
        elif given.suffix == ".csv":
            entries.extend(_read_index(given))
        elif given.suffix == ".mission":
            if not given.is_file():
                raise CampaignError(f"{given}: mission file does not exist")
            entries.append(_MissionEntry(given.resolve(), _key(given.resolve()),
                                         given.resolve().parent.name, {}))
        else:
            what = "another kind of file" if given.exists() else "nothing"
            raise CampaignError(f"{given}: expected a .mission file, a folder or a suite index "
                                f".csv, found {what}")
    return entries


def _ids(entries: list[_MissionEntry]) -> list[str]:
    """Run-id stems: the mission's file stem, or its path when stems collide."""
    stems = [e.path.stem for e in entries]
    out: list[str] = []
    for entry, stem in zip(entries, stems, strict=True):
        name = stem if stems.count(stem) == 1 else entry.key.rsplit(".", 1)[0]
        name = re.sub(r"[^A-Za-z0-9_.-]+", "_", name).strip("_.") or "mission"
        while name in out:  # same folder and file names in two places: number them
            name = f"{name}_{len(out)}"
        out.append(name)
    return out


STATIC = "static"
"""Run ids of static twins are NAME.static.rKK; their files are STATIC_DIR/NAME/."""


def plan_campaign(inputs: list[Path], *, repeat: int = 1, seed: int = 0,
                  controller: str | None = None, vepl: Path | None = None,
                  duration: float | None = None, static_dir: Path | None = None,
                  variation: bool = True, functions: str | None = None,
                  record: bool = False, faults: tuple[str, ...] = (),
                  vepl_parameters: tuple[tuple[str, float], ...] = ()) -> CampaignPlan:
    """Every mission of the inputs, ``repeat`` times, each with its derived seed.

    With ``static_dir`` every run is paired with its static twin (same seed, the mission's
    room without humans and dynamic objects, written into ``static_dir`` by
    ``static_pair.write_static_twins`` before the runs start): ``--pair-static``.
    ``vepl_parameters`` (``--param``) are checked against the specification now (a name it
    does not declare stops the plan, LanguageError), not in each run.
    """
    if repeat < 1:
        raise CampaignError(f"--repeat: expected a count of at least 1, found {repeat}")
    if duration is not None and not (math.isfinite(duration) and duration > 0):
        raise CampaignError(f"--duration: expected a positive number of seconds, found {duration}")
    if vepl is not None and not vepl.is_file():
        raise CampaignError(f"--vepl: file '{vepl}' does not exist")
    entries = _expand(inputs)
    seen: dict[Path, str] = {}
    unique: list[_MissionEntry] = []
    for entry in entries:  # the same mission named twice (file and folder) runs once
        if entry.path not in seen:
            seen[entry.path] = entry.key
            unique.append(entry)
    if not unique:
        raise CampaignError("no missions to run: name .mission files, folders or a suite index")
    vepl_path = str(vepl.resolve()) if vepl is not None else None
    if vepl_parameters:
        load_vepl(vepl, vepl_parameters)
    if functions is not None and Path(functions).is_file():
        functions = str(Path(functions).resolve())  # the runs may start elsewhere
    if functions is not None:
        load_functions(functions, vepl)  # a bad module stops the plan, not each of its runs
    runs = []
    for entry, stem in zip(unique, _ids(unique), strict=True):
        for k in range(repeat):
            number = f"r{k:02d}" if repeat <= 100 else f"r{k:04d}"
            run = RunSpec(
                run_id=f"{stem}.{number}", mission_file=str(entry.path), mission_key=entry.key,
                group=entry.group, repeat=k, seed=derive_seed(seed, entry.key, k),
                controller=controller, vepl=vepl_path, duration=duration,
                parameters=entry.parameters, variation=variation, functions=functions,
                record=record, faults=faults, vepl_parameters=vepl_parameters)
            if static_dir is None:
                runs.append(run)
                continue
            # Twins right after their run: a pair finishes together, also when interrupted.
            twin_file = static_dir.resolve() / stem / entry.path.name
            runs.append(replace(run, pair=run.run_id))
            runs.append(replace(run, run_id=f"{stem}.{STATIC}.{number}",
                                mission_file=str(twin_file), static_pair=True,
                                pair=run.run_id))
    ids = [r.run_id for r in runs]
    if len(set(ids)) != len(ids):
        twice = sorted({i for i in ids if ids.count(i) > 1})[:3]
        raise CampaignError(f"--pair-static: the run ids {twice} are taken by both a mission "
                            f"and a static twin; rename the mission file ending in "
                            f"'.{STATIC}'")
    return CampaignPlan(PLAN_VERSION, seed, repeat, tuple(runs))
