"""CSV export of a session log: one row per frame received or sent, one column per field."""

from __future__ import annotations

import csv
from collections.abc import Iterable
from pathlib import Path
from typing import TextIO

from particlebot.logs.jsonl import Record, read_log

BASE_COLUMNS = ["t", "direction", "src", "sender", "type", "seq"]


def _flat_fields(record: Record) -> dict[str, object]:
    flat: dict[str, object] = {}
    for name, value in record.get("fields", {}).items():
        if isinstance(value, list):
            for index, item in enumerate(value):
                flat[f"{name}_{index}"] = item
        else:
            flat[name] = value
    return flat


def frame_rows(records: Iterable[Record], types: set[str] | None = None) -> list[dict[str, object]]:
    rows: list[dict[str, object]] = []
    for record in records:
        kind = record.get("kind")
        if kind not in ("frame", "tx"):
            continue
        if types is not None and str(record.get("type", "")).upper() not in types:
            continue
        row: dict[str, object] = {
            "t": record.get("t"),
            "direction": "rx" if kind == "frame" else "tx",
            "src": record.get("src"),
            "sender": record.get("sender"),
            "type": record.get("type"),
            "seq": record.get("seq"),
        }
        row.update(_flat_fields(record))
        row["hex"] = record.get("hex")
        if "error" in record:
            row["error"] = record["error"]
        rows.append(row)
    return rows


def export_csv(log: Path, out: TextIO, types: Iterable[str] | None = None) -> int:
    """Writes log's frames as CSV to out; returns the number of rows. Columns are the base ones,
    then every field in the order first seen (arrays as name_0, name_1, ...), then hex."""
    wanted = {name.upper() for name in types} if types else None
    rows = frame_rows(read_log(log), wanted)
    columns = list(BASE_COLUMNS)
    for row in rows:
        for key in row:
            if key not in columns and key not in ("hex", "error"):
                columns.append(key)
    columns += ["hex", "error"]
    writer = csv.DictWriter(out, fieldnames=columns, restval="", lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    return len(rows)


def export_csv_file(log: Path, csv_path: Path, types: Iterable[str] | None = None) -> int:
    with csv_path.open("w", newline="") as out:
        return export_csv(log, out, types)
