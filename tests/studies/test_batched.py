"""A study's runs as GPU ensembles (numba-cuda's simulator): every run finishes, is stored like
the Dask path's, and measures what the same run measures on the CPU."""

from __future__ import annotations

from pathlib import Path

import pytest

from particlebot.sim.world.cuda.device import use_simulator

pytestmark = pytest.mark.skipif(not use_simulator(), reason="needs numba-cuda's simulator")


def test_a_small_dead_study_runs_as_ensembles_and_measures_as_on_the_cpu(tmp_path: Path) -> None:
    from particlebot.studies import seam
    from particlebot.studies.batched import run_batched
    from particlebot.studies.definitions import STUDIES, RawOptions, resolve
    from particlebot.studies.store import ResultStore

    study = STUDIES["dead"]
    options = resolve(
        study,
        RawOptions(sizes="4", values="0,0.5", seeds="2", duration="0.3", skip="0.1"),
    )
    specs = study.specs(options)
    store = ResultStore(tmp_path / "results")
    outcome = run_batched(specs, store, "simulator", batch_particles=8)  # two ensembles
    assert (outcome.ran, outcome.failed) == (len(specs), {})
    finished, _ = store.load_finished("simulator")
    assert set(finished) == {spec.run_id for spec in specs}
    for spec in specs:
        record = finished[spec.run_id]
        assert record.summary["device_cuda"] == 1.0
        cpu = spec.measure.evaluate(spec.setup, seam.simulate(spec.setup))
        # 30 steps: the GPU's other summation order has moved nothing beyond 1e-9 m yet.
        assert record.metrics == pytest.approx(cpu, rel=1e-6, abs=1e-9)
