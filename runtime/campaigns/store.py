"""The results store of a campaign: one folder, one record per run, written atomically.

Layout of a campaign folder::

    campaign.json        what was planned (every run), and the provenance of each session
    runs/RUN_ID/         the run's own folder (summary.json, events.csv, trace, run.log, ...)
                         plus record.json, written last: a run folder is complete or absent
    runs/.partial/       runs in progress (discarded on resume: they run again)
    static/NAME/         --pair-static: each mission's static twin (.mission and .room)
    results.parquet      one row per recorded run (rebuilt from the records)
    results.csv          the same rows as CSV

A run becomes recorded by renaming its finished folder into ``runs/`` — one atomic step — so
killing the campaign at any moment leaves every run either recorded once or not at all, and
resuming runs exactly the missing ones. A folder that is not a campaign folder, or whose files
do not parse, is refused with a message, never treated as empty. This module must never run
a mission.
"""

from __future__ import annotations

import errno
import fcntl
import json
import os
import uuid
from collections.abc import Iterator
from pathlib import Path
from typing import IO, Any

from rei.generators.output import OutputTree, remove_tree, write_atomic, write_tree
from rei.runtime.campaigns.errors import CampaignError
from rei.runtime.campaigns.execute import RunResult
from rei.runtime.campaigns.plan import CampaignPlan, RunSpec
from rei.runtime.campaigns.results_table import write_tables
from rei.runtime.campaigns.run_records import RECORD_FORMAT, STORE_VERSION, RunRecord

FORMAT = "rei-campaign"
MANIFEST = "campaign.json"
RUNS = "runs"
PARTIAL = ".partial"
RECORD = "record.json"


def _dumps(data: Any) -> bytes:
    return (json.dumps(data, indent=1, sort_keys=True, allow_nan=False) + "\n").encode()


def _load_json(path: Path, what: str) -> dict[str, Any]:
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        raise CampaignError(f"{path}: {what} is corrupt ({exc}); refusing to use this folder — "
                            f"move it away or choose another -o folder") from exc
    if not isinstance(data, dict):
        raise CampaignError(f"{path}: {what} is corrupt (expected a JSON object)")
    return data


class CampaignStore:
    """An open campaign folder. Use ``CampaignStore.open`` (and close it, or use ``with``)."""

    def __init__(self, root: Path, plan: CampaignPlan, lock: IO[bytes]) -> None:
        self.root = root
        self.plan = plan
        self._lock = lock

    # -- opening ------------------------------------------------------------------------

    @staticmethod
    def open(root: Path, plan: CampaignPlan, provenance: dict[str, Any]) -> CampaignStore:
        """Create the folder for ``plan``, or reopen it to resume the same plan."""
        if root.exists() and not root.is_dir():
            raise CampaignError(f"{root}: expected a campaign folder, found a file")
        manifest = root / MANIFEST
        if root.exists() and any(root.iterdir()) and not manifest.is_file():
            raise CampaignError(
                f"{root}: not a REI campaign folder (it has files but no {MANIFEST}); "
                f"refusing to write into it — choose an empty or new -o folder")
        root.mkdir(parents=True, exist_ok=True)
        if (root / RUNS).is_symlink() or (root / RUNS).exists() and not (root / RUNS).is_dir():
            raise CampaignError(f"{root / RUNS}: expected the folder of the recorded runs, "
                                f"found a link or a file; refusing to write through it")
        lock = _lock(root)
        try:
            if manifest.is_file():
                data = _check_manifest(manifest)
                stored = CampaignPlan.from_json(data["plan"])
                if stored != plan:
                    raise CampaignError(_plan_difference(manifest, stored, plan))
                data["sessions"] = [*data.get("sessions", []), provenance]
            else:
                data = {"format": FORMAT, "version": STORE_VERSION, "plan": plan.to_json(),
                        "sessions": [provenance]}
            (root / RUNS).mkdir(exist_ok=True)
            write_atomic(manifest, _dumps(data))
            store = CampaignStore(root, plan, lock)
            store._discard_partial()
            store.records()  # refuse a folder with broken records now, not at the end
            return store
        except BaseException:
            lock.close()
            raise

    @staticmethod
    def read(root: Path) -> tuple[CampaignPlan, dict[str, Any], list[RunRecord]]:
        """Plan, manifest and records of an existing campaign folder (for `rei report`)."""
        manifest = root / MANIFEST
        if not manifest.is_file():
            raise CampaignError(f"{root}: not a REI campaign folder (no {MANIFEST}); "
                                f"expected the -o folder of `rei campaign`")
        data = _check_manifest(manifest)
        plan = CampaignPlan.from_json(data["plan"])
        return plan, data, _read_records(root, plan)

    def close(self) -> None:
        """Release the folder; attempts that did not finish are discarded (they run again)."""
        self._discard_partial()
        self._lock.close()

    def __enter__(self) -> CampaignStore:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # -- runs ---------------------------------------------------------------------------

    def run_dir(self, run_id: str) -> Path:
        return self.root / RUNS / run_id

    def records(self) -> list[RunRecord]:
        return _read_records(self.root, self.plan)

    def missing(self) -> list[RunSpec]:
        """The planned runs not recorded yet, in plan order."""
        done = {r.spec.run_id for r in self.records()}
        return [s for s in self.plan.runs if s.run_id not in done]

    def new_work_dir(self, run_id: str) -> Path:
        """A fresh folder for one attempt; it becomes the run folder only when recorded."""
        path = self.root / RUNS / PARTIAL / f"{run_id}-{uuid.uuid4().hex[:8]}"
        path.mkdir(parents=True)
        return path

    def record(self, spec: RunSpec, result: RunResult, work_dir: Path) -> RunRecord | None:
        """Make the attempt in ``work_dir`` the run's recorded result (None if interrupted)."""
        if result.status == "interrupted":
            remove_tree(work_dir)
            return None
        if result.files:  # sent back by a worker: checked to stay inside, links not followed
            write_tree(OutputTree(dict(result.files)), work_dir)
        record = RunRecord.from_result(spec, result)
        write_atomic(work_dir / RECORD, _dumps(record.to_json()))
        final = self.run_dir(spec.run_id)
        if final.exists():  # only reachable by running one plan twice at once: keep the first
            remove_tree(work_dir)
            return None
        os.rename(work_dir, final)
        return record

    def _discard_partial(self) -> None:
        partial = self.root / RUNS / PARTIAL
        if partial.exists() or partial.is_symlink():
            remove_tree(partial)

    # -- tables -------------------------------------------------------------------------

    def write_tables(self) -> tuple[Path, Path]:
        return write_tables(self.root, self.records())


def extend_plan(root: Path, plan: CampaignPlan) -> None:
    """Grow the campaign in ``root`` to ``plan``, whose first runs must be the stored plan's
    runs unchanged (`rei search` plans one batch of candidates at a time); create the folder
    and its manifest when there is none. ``CampaignStore.open`` then accepts ``plan``.
    Anything but a longer plan with the same beginning is refused as ``open`` refuses it."""
    manifest = root / MANIFEST
    if root.exists() and not root.is_dir():
        raise CampaignError(f"{root}: expected a campaign folder, found a file")
    root.mkdir(parents=True, exist_ok=True)
    with _lock(root):
        if not manifest.is_file():
            data: dict[str, Any] = {"format": FORMAT, "version": STORE_VERSION,
                                    "plan": plan.to_json(), "sessions": []}
        else:
            data = _check_manifest(manifest)
            stored = CampaignPlan.from_json(data["plan"])
            head = CampaignPlan(plan.version, plan.seed, plan.repeat,
                                plan.runs[:len(stored.runs)])
            if stored == plan:
                return
            if head != stored:
                raise CampaignError(_plan_difference(manifest, stored, head))
            data["plan"] = plan.to_json()
        write_atomic(manifest, _dumps(data))


def _lock(root: Path) -> IO[bytes]:
    path = root / ".lock"
    # Neither truncated nor replaced (another campaign may hold a lock on this very file);
    # a link at the name is removed, never followed.
    try:
        fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_NOFOLLOW | os.O_CLOEXEC, 0o666)
    except OSError as exc:
        if exc.errno != errno.ELOOP:
            raise CampaignError(f"{path}: cannot create the lock file ({exc.strerror})") \
                from exc
        path.unlink()
        fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_NOFOLLOW | os.O_CLOEXEC, 0o666)
    handle = os.fdopen(fd, "wb")
    try:
        fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError as exc:
        handle.close()
        raise CampaignError(f"{root}: another `rei campaign` is writing into this folder") \
            from exc
    return handle


def _check_manifest(manifest: Path) -> dict[str, Any]:
    data = _load_json(manifest, "the campaign manifest")
    if data.get("format") != FORMAT:
        raise CampaignError(f"{manifest}: not a REI campaign manifest (format "
                            f"{data.get('format')!r}, expected {FORMAT!r}); refusing this folder")
    if data.get("version") != STORE_VERSION:
        raise CampaignError(f"{manifest}: campaign format version {data.get('version')!r}, "
                            f"this REI reads version {STORE_VERSION}")
    try:
        CampaignPlan.from_json(data["plan"])
    except (KeyError, TypeError, ValueError) as exc:
        raise CampaignError(f"{manifest}: the stored plan is corrupt ({exc})") from exc
    return data


def _plan_difference(manifest: Path, stored: CampaignPlan, new: CampaignPlan) -> str:
    head = (f"{manifest.parent}: this folder holds a different campaign; resume it with the "
            f"command that started it, or choose another -o folder. ")
    if (stored.seed, stored.repeat) != (new.seed, new.repeat):
        return head + (f"It was planned with --seed {stored.seed} --repeat {stored.repeat}, "
                       f"found --seed {new.seed} --repeat {new.repeat}")
    old_ids = [r.run_id for r in stored.runs]
    new_ids = [r.run_id for r in new.runs]
    if old_ids != new_ids:
        extra = sorted(set(new_ids) - set(old_ids))[:3]
        gone = sorted(set(old_ids) - set(new_ids))[:3]
        return head + f"Runs only in the new command: {extra}; only in the folder: {gone}"
    for a, b in zip(stored.runs, new.runs, strict=True):
        if a != b:
            old, now = a.to_json(), b.to_json()
            fields = [k for k in {**old, **now} if old.get(k) != now.get(k)]
            return head + f"Run {a.run_id} differs in {', '.join(fields)}"
    return head


def required_pass_rate(manifest: dict[str, Any], default: float = 1.0) -> float:
    """The pass rate the latest session of a campaign required (``--pass-rate``), so that
    `rei report DIR` judges the missions as the campaign did; ``default`` for older folders."""
    sessions = manifest.get("sessions") or []
    for session in reversed(sessions):
        value = session.get("pass_rate") if isinstance(session, dict) else None
        if isinstance(value, (int, float)) and not isinstance(value, bool) \
                and 0.0 <= value <= 1.0:
            return float(value)
    return default


def _read_records(root: Path, plan: CampaignPlan) -> list[RunRecord]:
    order = {s.run_id: i for i, s in enumerate(plan.runs)}
    return sorted(_scan_records(root, plan), key=lambda r: order[r.spec.run_id])


def _scan_records(root: Path, plan: CampaignPlan) -> Iterator[RunRecord]:
    planned = {s.run_id: s for s in plan.runs}
    runs = root / RUNS
    if not runs.is_dir():
        return
    for folder in sorted(runs.iterdir()):
        if folder.name.startswith("."):
            continue
        path = folder / RECORD
        if folder.name not in planned:
            raise CampaignError(f"{folder}: a run folder that is not in this campaign's plan; "
                                f"refusing a folder mixed with another campaign")
        if not path.is_file():
            raise CampaignError(f"{folder}: run folder without {RECORD}; it was not written by "
                                f"`rei campaign` (remove it to run that mission again)")
        data = _load_json(path, "the run record")
        try:
            if data.get("format") != RECORD_FORMAT:
                raise ValueError(f"format {data.get('format')!r}")
            record = RunRecord.from_json(data)
        except (KeyError, TypeError, ValueError) as exc:
            raise CampaignError(f"{path}: the run record is corrupt ({exc}); remove the run "
                                f"folder to run it again") from exc
        if record.spec != planned[folder.name]:
            raise CampaignError(f"{path}: recorded for a different plan than {MANIFEST}")
        yield record
