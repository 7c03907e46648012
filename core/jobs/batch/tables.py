"""The tables a batch writes: a row per run, a row per combination of parameters (its mean and
standard deviation across seeds), and optionally a row per run and metric (the long format)."""

from __future__ import annotations

import csv
import io
import math
from pathlib import Path
from typing import Any

from ...formats.recording import atomic_path

_RUN_COLUMNS = ["id", "world", "seed", "frames", "status", "error", "seconds", "outputs"]


def _parameters(rows: list[dict[str, Any]]) -> list[str]:
    return sorted({k for row in rows for k in row if k.startswith("parameter.")})


def _metrics(rows: list[dict[str, Any]]) -> list[str]:
    """The metric columns, NAME@FRAME, by frame, then name."""
    return sorted({k for row in rows for k in row if "@" in k}, key=lambda k: (int(k.rsplit("@", 1)[1]), k))


def write_tables(rows: list[dict[str, Any]], out: Path, *, long: bool = False) -> list[Path]:
    """results.csv (and results.parquet where pyarrow is installed), summary.csv, and with ``long``
    results_long.csv: each whole or not at all. The paths written."""
    header = _RUN_COLUMNS[:3] + _parameters(rows) + _RUN_COLUMNS[3:] + _metrics(rows)
    written = [_csv(out / "results.csv", header, rows)]
    parquet = _parquet(out / "results.parquet", header, rows)
    if parquet:
        written.append(parquet)
    elif (out / "results.parquet").is_file():  # an earlier one, written where pyarrow was: stale now
        (out / "results.parquet").unlink()
    summary_header, summary_rows = summary(rows)
    written.append(_csv(out / "summary.csv", summary_header, summary_rows))
    if long:
        written.append(_csv(out / "results_long.csv", *long_rows(rows)))
    return written


def summary(rows: list[dict[str, Any]]) -> tuple[list[str], list[dict[str, Any]]]:
    """A row per world and combination of parameters: how many runs it had and how many failed,
    and each metric's mean and (sample) standard deviation over the seeds of the runs done."""
    parameters, metrics = _parameters(rows), _metrics(rows)
    groups: dict[tuple, list[dict[str, Any]]] = {}
    for row in rows:
        groups.setdefault((row["world"], *(repr(row.get(p)) for p in parameters)), []).append(row)
    header = ["world", *parameters, "runs", "failed"] + [f"{m}.{stat}" for m in metrics for stat in ("mean", "std")]
    table = []
    for members in groups.values():
        done = [r for r in members if r.get("status") == "done"]
        line = {"world": members[0]["world"], **{p: members[0].get(p) for p in parameters}, "runs": len(members), "failed": len(members) - len(done)}
        for metric in metrics:
            values = [float(r[metric]) for r in done if r.get(metric) not in (None, "")]
            line[f"{metric}.mean"] = _round(sum(values) / len(values)) if values else None
            line[f"{metric}.std"] = _round(_std(values)) if len(values) > 1 else None
        table.append(line)
    return header, table


def long_rows(rows: list[dict[str, Any]]) -> tuple[list[str], list[dict[str, Any]]]:
    """A row per run and measurement: its id, world, seed, parameters, metric, frame and value."""
    parameters = _parameters(rows)
    header = ["id", "world", "seed", *parameters, "metric", "frame", "value"]
    table = []
    for row in rows:
        for column in _metrics([row]):
            metric, _, frame = column.rpartition("@")
            table.append({"id": row["id"], "world": row["world"], "seed": row["seed"], **{p: row.get(p) for p in parameters},
                          "metric": metric, "frame": int(frame), "value": row[column]})
    return header, table


def _std(values: list[float]) -> float:
    mean = sum(values) / len(values)
    return math.sqrt(sum((v - mean) ** 2 for v in values) / (len(values) - 1))


def _round(value: float) -> float:
    return round(value, 6)


def _csv(path: Path, header: list[str], rows: list[dict[str, Any]]) -> Path:
    text = io.StringIO()
    writer = csv.DictWriter(text, header, extrasaction="ignore", lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    with atomic_path(path) as temporary:
        temporary.write_text(text.getvalue(), encoding="utf-8")
    return path


def _parquet(path: Path, header: list[str], rows: list[dict[str, Any]]) -> Path | None:
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError:
        return None
    table = pa.Table.from_pylist([{k: row.get(k) for k in header} for row in rows])
    with atomic_path(path) as temporary:
        pq.write_table(table, temporary)
    return path
