"""CSV export of a session log: one row per frame received or sent, one column per field."""

from __future__ import annotations

import csv
import enum
import io
from collections.abc import Iterable
from pathlib import Path
from typing import TextIO

from particlebot.logs.jsonl import Record, RecordReader, load_log
from particlebot.protocol import Method, Param, ParamResult, State

BASE_COLUMNS = ["t", "direction", "src", "sender", "type", "seq"]

# Fields whose numbers stand for names: the CSV shows the name (CYCLING, not 3), as the console
# does; a number the protocol does not name stays a number.
NAMED_FIELDS: dict[str, type[enum.IntEnum]] = {
    "state": State,
    "method": Method,
    "param": Param,
    "result": ParamResult,
}


def _named(name: str, value: object) -> object:
    names = NAMED_FIELDS.get(name)
    if names is None or isinstance(value, bool) or not isinstance(value, int):
        return value
    try:
        return names(value).name
    except ValueError:
        return value


def _flat_fields(fields: dict[str, object]) -> dict[str, object]:
    flat: dict[str, object] = {}
    for name, value in fields.items():
        if isinstance(value, list):
            for index, item in enumerate(value):
                flat[f"{name}_{index}"] = item
        else:
            flat[name] = _named(name, value)
    return flat


def frame_rows(
    path: Path,
    records: Iterable[tuple[int, Record]],
    types: set[str] | None = None,
    *,
    notes: bool = False,
) -> list[dict[str, object]]:
    """One row per frame received or sent (and per console note with notes=True);
    LogFormatError names a record of the wrong shape."""
    rows: list[dict[str, object]] = []
    for number, record in records:
        kind = record.get("kind")
        if kind == "note" and notes:
            read = RecordReader(path, number, record)
            rows.append({"t": read.number("t"), "direction": "note", "note": read.text("text")})
            continue
        if kind not in ("frame", "tx"):
            continue
        read = RecordReader(path, number, record)
        type_name = read.text("type")
        if types is not None and type_name.upper() not in types:
            continue
        row: dict[str, object] = {
            "t": read.number("t"),
            "direction": "rx" if kind == "frame" else "tx",
            "src": read.optional_text("src"),
            "sender": read.integer("sender"),
            "type": type_name,
            "seq": read.integer("seq"),
        }
        row.update(_flat_fields(read.fields()))
        row["hex"] = read.text("hex")
        if "error" in record:
            row["error"] = record["error"]
        rows.append(row)
    return rows


def export_csv(
    log: Path, out: TextIO, types: Iterable[str] | None = None, *, notes: bool = False
) -> int:
    """Writes log's frames as CSV to out; returns the number of rows. Columns are the base ones,
    then every field in the order first seen (arrays as name_0, name_1, ...), then hex and error,
    then (notes=True) the console's notes, each a row of its own."""
    wanted = {name.upper() for name in types} if types else None
    rows = frame_rows(log, load_log(log), wanted, notes=notes)
    last = ["hex", "error", *(["note"] if notes else [])]
    columns = list(BASE_COLUMNS)
    for row in rows:
        for key in row:
            if key not in columns and key not in last:
                columns.append(key)
    columns += last
    writer = csv.DictWriter(out, fieldnames=columns, restval="", lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    return len(rows)


def export_csv_file(
    log: Path, csv_path: Path, types: Iterable[str] | None = None, *, notes: bool = False
) -> int:
    """Writes the CSV to csv_path, which is only created once the log has been read whole: a log
    that cannot be exported leaves no empty or partial CSV behind."""
    out = io.StringIO()
    rows = export_csv(log, out, types, notes=notes)
    with csv_path.open("w", newline="") as file:
        file.write(out.getvalue())
    return rows
