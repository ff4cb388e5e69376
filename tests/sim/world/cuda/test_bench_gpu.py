"""benchmarks/bench_gpu.py runs end to end on tiny sizes (--smoke: numba-cuda's simulator) and
writes its raw output where it says."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

SCRIPT = Path(__file__).resolve().parents[4] / "benchmarks" / "bench_gpu.py"


@pytest.mark.slow
def test_the_gpu_benchmark_runs_its_smoke_sizes(tmp_path: Path) -> None:
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_ENABLE_CUDASIM"}
    done = subprocess.run(
        [sys.executable, str(SCRIPT), "--smoke", "--out", str(tmp_path)],
        capture_output=True, text=True, env=env, timeout=600, check=False,
    )  # fmt: skip
    assert done.returncode == 0, done.stdout + done.stderr
    assert "SCALED DOWN: 1 of 3 runs built" in done.stdout
    assert "EXTRAPOLATED to all 3 runs" in done.stdout
    (figures,) = tmp_path.glob("gpu-*.json")
    data = json.loads(figures.read_text())
    assert {row["particles"] for row in data["rows"]} == {20, 40}
    assert all(row["gpu_particle_steps_per_s"] > 0 for row in data["rows"])
    assert (data["table_s3"]["runs"], data["table_s3"]["runs_in_row"]) == (1, 3)
