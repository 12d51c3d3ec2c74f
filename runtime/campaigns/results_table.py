"""The results tables of a campaign (results.csv and results.parquet): one flat row per
recorded run, the fixed columns first, then the signal counts, verdicts, margins and
parameters as ``signal:NAME``, ``req:NAME``, ``margin:NAME`` and ``param:NAME`` columns.
Written atomically; this module must never run a mission or change a run's folder.
"""

from __future__ import annotations

import csv
import io
import math
from pathlib import Path
from typing import Any

from rei.generators.output import write_atomic
from rei.runtime.campaigns.run_records import RunRecord, verdict_reason
from rei.runtime.observation.evaluator.margins import RULES, smallest_margin
from rei.runtime.results import failed_verdicts


def record_row(record: RunRecord) -> dict[str, Any]:
    """The flat row of one run (signal counts as ``signal:NAME``, verdicts as ``req:NAME``)."""
    spec, summary = record.spec, record.summary
    row: dict[str, Any] = {
        "run_id": spec.run_id, "mission": summary.mission if summary else Path(
            spec.mission_file).stem,
        "room": summary.room if summary else "", "group": spec.group,
        "mission_file": spec.mission_file, "seed": spec.seed, "repeat": spec.repeat,
        "pair": spec.pair, "static_pair": spec.static_pair,
        "controller": (summary.controller if summary else spec.controller) or "",
        "status": record.status, "outcome": record.outcome, "verdict": record.verdict,
        "passed": record.passed, "reason": record.reason,
        "failed_requirements": " ".join(v.requirement for v in failed_verdicts(summary))
        if summary else "",
        "failure": verdict_reason(record),
        "total_utility": summary.total_utility if summary else None,
        "smallest_margin": smallest_margin(summary.verdicts) if summary else None,
        "duration": summary.duration if summary else None,
        "wall_time": round(record.wall_time, 3), "exit_code": record.exit_code,
    }
    for key, value in sorted(spec.parameters.items()):
        row[f"param:{key}"] = value
    if summary is not None:
        for name, count in sorted(summary.signal_counts.items()):
            row[f"signal:{name}"] = count
        for verdict in summary.verdicts:
            row[f"req:{verdict.requirement}"] = verdict.status
            if verdict.requirement in RULES:
                # the default requirements with a margin: a column each, empty when the run
                # gave none (not judged, or no natural margin in it), so tables line up
                row[f"margin:{verdict.requirement}"] = verdict.margin
    return row


def rows_table(records: list[RunRecord]) -> tuple[list[str], list[dict[str, Any]]]:
    """Columns (fixed ones first, then the union of the dynamic ones) and rows in plan order."""
    rows = [record_row(r) for r in records]
    columns: list[str] = []
    for row in rows:
        for key in row:
            if key not in columns:
                columns.append(key)
    fixed = [c for c in columns if ":" not in c]
    dynamic = sorted(c for c in columns if ":" in c)
    for row in rows:  # missing signals were counted zero times; other gaps stay empty
        for col in dynamic:
            if col not in row:
                row[col] = 0 if col.startswith("signal:") else None
    return fixed + dynamic, rows


def write_tables(root: Path, records: list[RunRecord]) -> tuple[Path, Path]:
    """results.csv and results.parquet, atomically, one row per recorded run."""
    import pyarrow as pa  # noqa: PLC0415  (heavy; only needed when tables are written)
    import pyarrow.parquet as pq  # noqa: PLC0415

    columns, rows = rows_table(records)
    text = io.StringIO()
    writer = csv.DictWriter(text, fieldnames=columns, lineterminator="\n")
    writer.writeheader()
    for row in rows:
        writer.writerow({k: _csv_cell(v) for k, v in row.items()})
    csv_path = root / "results.csv"
    write_atomic(csv_path, text.getvalue().encode())
    arrays = {c: [row.get(c) for row in rows] for c in columns}
    table = pa.table({c: _arrow_column(v) for c, v in arrays.items()}) if columns else \
        pa.table({"run_id": pa.array([], pa.string())})
    sink = pa.BufferOutputStream()
    pq.write_table(table, sink)
    parquet_path = root / "results.parquet"
    write_atomic(parquet_path, sink.getvalue().to_pybytes())
    return csv_path, parquet_path


def _csv_cell(value: Any) -> Any:
    if value is None:
        return ""
    if isinstance(value, float) and not math.isfinite(value):
        return ""
    return value


def _arrow_column(values: list[Any]) -> Any:
    """Mixed columns (a descriptor that is a number in one suite row, text in another) as text."""
    import pyarrow as pa  # noqa: PLC0415

    kinds = {type(v) for v in values if v is not None}
    if kinds <= {int, float} and kinds and not kinds <= {bool}:
        return pa.array([None if v is None else float(v) for v in values], pa.float64()) \
            if float in kinds else pa.array(values, pa.int64())
    if kinds <= {bool}:
        return pa.array(values, pa.bool_())
    return pa.array([None if v is None else str(v) for v in values], pa.string())
