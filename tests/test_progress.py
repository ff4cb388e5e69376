"""particlebot.progress: when a progress line shows (by wall clock, whatever the work reports)
and what its ETA says (the work's own rate, not what came before it)."""

from __future__ import annotations

import io

from particlebot.progress import Activity, ProgressBar, clock_text


class FakeClock:
    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


def bar_of(total: float, report_every_s: float = 5.0) -> tuple[ProgressBar, FakeClock, io.StringIO]:
    clock, stream = FakeClock(), io.StringIO()
    bar = ProgressBar("simulate", total, "s simulated", stream, clock, report_every_s, live=False)
    return bar, clock, stream


def test_a_log_gets_a_line_every_few_seconds_of_wall_time_however_often_work_reports() -> None:
    bar, clock, stream = bar_of(total=1000.0)
    # A report every 0.25 s for a minute: twelve lines (one per 5 s), not 240 and not one.
    for tick in range(240):
        clock.now = 0.25 * tick
        bar.update(tick * 0.1)
    assert len(stream.getvalue().splitlines()) == 12


def test_a_log_gets_a_line_by_wall_clock_even_when_the_work_advances_slowly() -> None:
    # A huge swarm: 0.1 simulated s per minute of wall time. The old bar printed at each tenth
    # of the run (every 100 min here); this one every report interval.
    bar, clock, stream = bar_of(total=60.0)
    for minute in range(1, 4):
        clock.now = 60.0 * minute
        bar.update(0.1 * minute)
    assert len(stream.getvalue().splitlines()) == 3


def test_the_eta_comes_from_the_rate_since_the_first_update_not_from_the_start() -> None:
    bar, clock, _ = bar_of(total=100.0)
    clock.now = 150.0  # e.g. kernels compiling before the first step
    bar.update(1.0)
    assert bar.eta_s() is None  # no rate yet
    clock.now = 160.0
    bar.update(11.0)  # 10 units in 10 s: 1 unit/s
    assert bar.eta_s() == 89.0
    clock.now = 165.0  # between updates it counts down
    assert bar.eta_s() == 84.0
    assert "ETA 0:01:24" in bar.line() and "elapsed 0:02:45" in bar.line()


def test_the_last_line_shows_once_and_an_interrupted_bar_says_where_it_stopped() -> None:
    bar, clock, stream = bar_of(total=10.0)
    bar.update(10.0)
    bar.close()
    bar.close()
    assert stream.getvalue().count("100%") == 1
    stopped, clock, stream = bar_of(total=10.0)
    stopped.update(1.0)
    clock.now = 1.0
    stopped.update(4.0)
    stopped.close()
    assert stream.getvalue().splitlines()[-1].startswith("simulate  40%")


def test_a_terminal_gets_one_line_redrawn_in_place() -> None:
    clock, stream = FakeClock(), io.StringIO()
    bar = ProgressBar("track", 3, stream=stream, clock=clock, live=True)
    for done in range(1, 4):
        clock.now = done
        bar.update(done)
    bar.close()
    text = stream.getvalue()
    assert text.count("\r") == 4 and text.count("\n") == 1 and text.endswith("\n")


def test_an_activity_says_how_long_it_has_taken_and_usually_takes() -> None:
    clock, stream = FakeClock(), io.StringIO()
    activity = Activity("compiling", usual_s=150, stream=stream, clock=clock, live=False)
    clock.now = 61.0
    assert activity.line() == "compiling: 0:01:01 (usually about 150 s)"
    assert clock_text(3725) == "1:02:05"
