"""The study progress line: an ETA weighed by cost, runs still going counted by their share."""

from __future__ import annotations

import io

from particlebot.studies.progress import Progress


class FakeClock:
    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


def progress_of(total: int, cost_left: float) -> tuple[Progress, FakeClock, io.StringIO]:
    clock, stream = FakeClock(), io.StringIO()
    return Progress("dead", total, 0, cost_left, stream=stream, clock=clock), clock, stream


def test_the_eta_weighs_finished_runs_by_cost_not_number() -> None:
    progress, clock, _ = progress_of(total=3, cost_left=100.0)
    assert progress.eta_s() is None
    clock.now = 10.0
    progress.advance(10.0, run_id="small")
    # 10 of 100 cost units in 10 s: the 90 left take 90 s, though two of three runs are left.
    assert progress.eta_s() == 90.0
    assert progress.line().startswith("dead: 1/3 runs  [##") and " 10 %" in progress.line()


def test_a_run_still_going_counts_by_its_share_and_a_resumed_run_only_by_what_it_did_now() -> None:
    progress, clock, _ = progress_of(total=2, cost_left=200.0)
    clock.now = 60.0
    progress.running("fresh", 100.0, 0.0, 0.3)
    # Resumed at 50 %: that half was done before, so it is neither work done now nor work left.
    progress.running("resumed", 100.0, 0.5, 0.6)
    done_now = 100 * 0.3 + 100 * (0.6 - 0.5)
    left = 200 - 100 * 0.3 - 100 * 0.6
    assert progress.eta_s() == 60.0 * left / done_now
    assert progress.share_done() == 1 - left / 200
    line = "0/2 runs  [##########..............]  45 %  elapsed 0:01:00  ETA 0:02:45"
    assert progress.line() == "dead: " + line
    clock.now = 70.0  # no news for 10 s: the ETA counts down
    assert progress.eta_s() == 60.0 * left / done_now - 10.0


def test_a_report_that_arrives_after_its_run_ended_is_ignored() -> None:
    progress, clock, _ = progress_of(total=2, cost_left=200.0)
    progress.running("a", 100.0, 0.0, 0.9)
    clock.now = 30.0
    progress.advance(100.0, run_id="a")
    progress.running("a", 100.0, 0.0, 0.95)
    assert progress.in_flight == {}
    assert progress.eta_s() == 30.0
    assert progress.share_done() == 0.5


def test_a_log_gets_a_line_every_interval_and_the_last_one_always() -> None:
    progress, clock, stream = progress_of(total=2, cost_left=2.0)
    progress.show(force=True)
    clock.now = 10.0
    progress.show()  # within the 30 s interval: nothing
    clock.now = 31.0
    progress.show()
    progress.advance(1.0, run_id="a")  # within the interval again: nothing
    progress.advance(1.0, run_id="b")  # the last: always
    lines = stream.getvalue().splitlines()
    assert [line.split("  ")[0] for line in lines] == [
        "dead: 0/2 runs",
        "dead: 0/2 runs",
        "dead: 2/2 runs",
    ]
    assert lines[-1].endswith("ETA 0:00:00") and "100 %" in lines[-1]
