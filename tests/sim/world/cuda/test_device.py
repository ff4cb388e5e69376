"""Choosing the backend: auto takes a GPU only when there is a real one; cuda without one is one
clear error, from the World and from the commands."""

from __future__ import annotations

import pytest

from particlebot.sim.world.cuda import device
from particlebot.sim.world.cuda.device import DeviceError, resolve


def _machine(monkeypatch: pytest.MonkeyPatch, *, simulator: bool, gpu: bool) -> None:
    monkeypatch.setattr(device, "simulated", lambda: simulator)
    monkeypatch.setattr(device, "gpu_present", lambda: gpu and not simulator)


def test_auto_takes_the_gpu_only_when_a_real_one_is_there(monkeypatch: pytest.MonkeyPatch) -> None:
    _machine(monkeypatch, simulator=False, gpu=True)
    assert resolve("auto") == "cuda"
    _machine(monkeypatch, simulator=True, gpu=False)
    assert resolve("auto") == "cpu"  # the simulator is for tests, never chosen by itself
    assert resolve("cuda") == "cuda"
    assert resolve("cpu") == "cpu"


def test_cuda_without_a_gpu_is_one_clear_error(monkeypatch: pytest.MonkeyPatch) -> None:
    _machine(monkeypatch, simulator=False, gpu=False)
    with pytest.raises(DeviceError, match="no CUDA GPU here"):
        resolve("cuda")
    with pytest.raises(DeviceError, match="must be one of auto, cpu, cuda"):
        resolve("tpu")


def test_simulate_and_study_say_so_in_one_line(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str], tmp_path: object
) -> None:
    from particlebot.cli import main

    _machine(monkeypatch, simulator=False, gpu=False)
    assert main(["simulate", "--particles", "3", "--duration", "0.05", "--device", "cuda",
                 "-o", f"{tmp_path}/run"]) != 0  # fmt: skip
    assert main(["study", "dead", "--quick", "--device", "cuda",
                 "--results", f"{tmp_path}/study"]) != 0  # fmt: skip
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if "no CUDA GPU here" in line]
    assert len(lines) == 2
    assert "Traceback" not in err
