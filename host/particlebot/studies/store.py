"""A study's results folder: one JSON file per finished run, written atomically, read to resume."""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from particlebot.fileio import finished_files, write_text
from particlebot.studies.spec import RunRecord, RunSpec


@dataclass
class LoadReport:
    """What load_finished() found besides usable results."""

    unreadable: list[Path] = field(default_factory=list)
    """Files that are not a complete result (a disk problem; a crash cannot leave one, since
    results are renamed into place whole): their runs are run again."""
    other_runner: int = 0
    """Results another runner made (the stand-in's, say): not counted as done."""


class ResultStore:
    """results/ROOT/runs/RUN_ID.json for finished runs and failed/RUN_ID.json for runs that
    raised (retried on the next invocation). The folder is a cache keyed by run id: studies with
    other options can share it, and a run is never done twice."""

    def __init__(self, root: Path) -> None:
        self.root = root
        self.runs = root / "runs"
        self.failed = root / "failed"

    def prepare(self) -> None:
        """Creates the folders (an error here is the user's path: say it before any work)."""
        self.runs.mkdir(parents=True, exist_ok=True)
        self.failed.mkdir(parents=True, exist_ok=True)

    def load_finished(self, runner: str) -> tuple[dict[str, RunRecord], LoadReport]:
        report = LoadReport()
        records: dict[str, RunRecord] = {}
        for path in finished_files(self.runs, "*.json"):
            try:
                record = RunRecord.from_json(json.loads(path.read_text()))
            except (OSError, ValueError, TypeError):
                report.unreadable.append(path)
                continue
            if record.runner != runner:
                report.other_runner += 1
                continue
            records[record.run_id] = record
        return records, report

    def load_failures(self) -> dict[str, str]:
        """run id -> error of the runs that failed last time and have not finished since."""
        failures = {}
        for path in finished_files(self.failed, "*.json"):
            try:
                data = json.loads(path.read_text())
                failures[str(data["run_id"])] = str(data["error"])
            except (OSError, ValueError, KeyError, TypeError):
                continue
        return failures

    def write(self, record: RunRecord) -> Path:
        path = self.runs / f"{record.run_id}.json"
        write_json_atomically(path, record.to_json())
        (self.failed / f"{record.run_id}.json").unlink(missing_ok=True)
        return path

    def write_failure(self, spec: RunSpec, error: str) -> Path:
        path = self.failed / f"{spec.run_id}.json"
        write_json_atomically(path, {"run_id": spec.run_id, "cell": spec.cell_dict, "error": error})
        return path

    def write_document(self, name: str, data: dict[str, Any]) -> Path:
        path = self.root / name
        write_json_atomically(path, data)
        return path


def write_json_atomically(path: Path, data: dict[str, Any]) -> None:
    """Whole or not at all (particlebot.fileio): a result a crash cut short never looks done."""
    write_text(path, json.dumps(data, indent=1) + "\n")
