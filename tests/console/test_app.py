"""The Textual console through its headless pilot: keys send the right frames, the table fills."""

from __future__ import annotations

import asyncio
from collections.abc import Callable, Coroutine
from typing import Any

import pytest
from textual import events
from textual.geometry import Region
from textual.pilot import Pilot
from textual.widget import Widget
from textual.widgets import DataTable, Input, RichLog, Static

from particlebot.console.app import ConfirmScreen, ConsoleApp, PageScreen, heard_text
from particlebot.fleet import Fleet, ParticleRecord
from particlebot.protocol import DEFINITION_HASH, Method, Start, State, Stop
from particlebot.swarm.api import Swarm
from particlebot.swarm.roster import ParticleRow
from tests.support.fakes import FakeRadio, status_frame, wait_until


def run_app(
    test: Callable[[Pilot[int], FakeRadio], Coroutine[Any, Any, None]],
    size: tuple[int, int] = (140, 40),
    read_only: bool = False,
    fleet: Fleet | None = None,
) -> ConsoleApp:
    radio = FakeRadio()
    # The console takes over particles it knows from the start here: no grace period.
    swarm = Swarm(radio, log_dir=None, stop_grace=0, fleet=fleet)
    app = ConsoleApp(swarm, log_path="logs/test.jsonl", refresh_s=0.05, read_only=read_only)

    async def body() -> None:
        async with app.run_test(size=size) as pilot:
            await test(pilot, radio)

    try:
        asyncio.run(body())
    finally:
        swarm.close()
    return app


def hear_particles(
    radio: FakeRadio, app: ConsoleApp, ids: range = range(1, 4), **fields: int
) -> None:
    values: dict[str, int] = {"state": int(State.CYCLING), **fields}
    for particle in ids:
        radio.inject(status_frame(particle, s_n=particle, **values))

    # Until the model holds these very reports: counting rows is not enough when the particles
    # were heard before (a test that hears them go IDLE then raced the radio's reader).
    def heard(row: ParticleRow) -> bool:
        status = row.status
        return status is not None and all(getattr(status, k) == v for k, v in values.items())

    assert wait_until(lambda: sum(heard(r) for r in app.model.rows() if r.id in ids) == len(ids))


def console(pilot: Pilot[int]) -> ConsoleApp:
    assert isinstance(pilot.app, ConsoleApp)
    return pilot.app


async def refreshed(pilot: Pilot[int]) -> None:
    """Does what the app's two timers do, once each: poll the swarm (frames heard, a STOP
    confirmed, a quit that was waiting for it) and draw what the model knows; then lets the
    screen settle. Waiting for the timers instead failed on a loaded machine: they may not have
    fired yet."""
    app = console(pilot)
    app._tick()
    app.refresh_view()
    await pilot.pause()


def table_text(app: ConsoleApp) -> list[dict[str, str]]:
    """Each row's cells by column key (id, state, s_n, ...)."""
    table = app.query_one(DataTable)
    keys = [str(column.key.value) for column in table.ordered_columns]
    return [
        dict(zip(keys, (str(cell) for cell in table.get_row_at(i)), strict=True))
        for i in range(table.row_count)
    ]


def screen_lines(widget: Widget) -> list[str]:
    """What a widget shows on screen, line by line."""
    region = Region(0, 0, widget.size.width, widget.size.height)
    return [strip.text for strip in widget.render_lines(region)]


async def footer_text(pilot: Pilot[int]) -> str:
    """The bottom line of the screen as drawn (the footer's keys are widgets of their own, laid
    out once the app has settled its key bindings)."""
    for _ in range(50):
        text = pilot.app.screen._compositor.render_strips()[-1].text
        if text.strip():
            break
        await pilot.pause(0.05)
    return text


def log_text(app: ConsoleApp) -> str:
    return "\n".join(str(line.text) for line in app.query_one(RichLog).lines)


async def burst(pilot: Pilot[int], *keys: str) -> None:
    """Keys that arrive together, as when typed fast, pasted or sent by tmux: each is queued
    before the app has handled the one before it (pilot.press waits after every key)."""
    driver = pilot.app._driver
    assert driver is not None
    for key in keys:
        event = events.Key(key, key if len(key) == 1 else None)
        event.set_sender(pilot.app)
        driver.send_message(event)
    await pilot.pause()


def page_lines(app: ConsoleApp) -> list[str]:
    """What the open page shows on screen, line by line."""
    assert isinstance(app.screen, PageScreen)
    return screen_lines(app.screen.query_one("#page-body"))


def test_every_particle_heard_appears_in_the_table_with_its_s_n() -> None:
    async def test(pilot: Pilot[int], radio: FakeRadio) -> None:
        app = console(pilot)
        hear_particles(radio, app)
        await refreshed(pilot)
        rows = table_text(app)
        assert [row["id"] for row in rows] == ["1", "2", "3"]
        assert [row["s_n"] for row in rows] == ["1", "2", "3"]
        assert [row["state"] for row in rows] == ["CYCLING"] * 3
        assert [row["hash"] for row in rows] == [f"{DEFINITION_HASH:08X}"] * 3

    run_app(test)


def test_the_table_lists_particles_by_id_whatever_order_they_are_heard_in() -> None:
    async def test(pilot: Pilot[int], radio: FakeRadio) -> None:
        app = console(pilot)
        for particle in (12, 3, 7):
            radio.inject(status_frame(particle, state=int(State.IDLE)))
            assert wait_until(lambda: particle in {row.id for row in app.model.rows()})  # noqa: B023
            await refreshed(pilot)  # each one is added to the table on its own
        assert [row["id"] for row in table_text(app)] == ["3", "7", "12"]

    run_app(test)


def test_a_foreign_firmware_hash_is_flagged_in_the_table() -> None:
    async def test(pilot: Pilot[int], radio: FakeRadio) -> None:
        app = console(pilot)
        hear_particles(radio, app, definition_hash=0x12345678)
        await refreshed(pilot)
        rows = table_text(app)
        assert len(rows) == 3  # all() of an empty table would pass
        assert all("HASH MISMATCH" in row["flags"] for row in rows)

    run_app(test)


def test_the_x_key_broadcasts_stop_at_once() -> None:
    async def test(pilot: Pilot[int], radio: FakeRadio) -> None:
        app = console(pilot)
        hear_particles(radio, app)
        await pilot.press("x")
        assert wait_until(lambda: len(radio.sent) >= 1)
        # The fake radio's clock stands still: only the first copy of the burst is due.
        assert radio.sent_frames()[0].message == Stop()

    run_app(test)


def test_the_s_key_then_enter_starts_without_touching_stored_settings() -> None:
    async def test(pilot: Pilot[int], radio: FakeRadio) -> None:
        app = console(pilot)
        hear_particles(radio, app, state=int(State.IDLE))
        await pilot.press("s")
        command = app.query_one(Input)
        assert command.has_focus
        await pilot.press("enter")
        assert wait_until(lambda: len(radio.sent) >= 1)
        message = radio.sent_frames()[0].message
        assert isinstance(message, Start)
        assert message.method == Method.COUNTING
        # 0: each particle keeps the cycle and update interval stored with `set`.
        assert (message.cycle_steps, message.update_interval_s, message.wave_size) == (0, 0, 0)
        assert "stored setting" in log_text(app)

    run_app(test)


def test_what_is_typed_after_s_completes_the_start_line() -> None:
    async def test(pilot: Pilot[int], radio: FakeRadio) -> None:
        app = console(pilot)
        hear_particles(radio, app, state=int(State.IDLE))
        await pilot.press("s", "A", "space", "c", "y", "c", "l", "e", "=", "3", "0", "0")
        assert app.query_one(Input).value == "start A cycle=300"
        await pilot.press("enter")
        assert wait_until(lambda: len(radio.sent) >= 1)
        message = radio.sent_frames()[0].message
        assert isinstance(message, Start)
        assert (message.method, message.cycle_steps) == (Method.DIRECT, 300)

    run_app(test)


def test_the_p_key_prefill_sets_nothing_by_itself() -> None:
    async def test(pilot: Pilot[int], radio: FakeRadio) -> None:
        app = console(pilot)
        await pilot.press("p", "enter")
        assert "usage: set PARAM VALUE" in log_text(app)
        assert radio.sent == []

    run_app(test)


def test_typed_commands_run_and_mistakes_are_explained_on_screen() -> None:
    async def test(pilot: Pilot[int], radio: FakeRadio) -> None:
        app = console(pilot)
        # "p" and "i" are key bindings too; in the command line they are just letters.
        await pilot.press("colon", "p", "i", "n", "g", "space", "4", "enter")
        assert wait_until(lambda: len(radio.sent) == 1)
        assert radio.sent_frames()[0].type_name == "PING"
        assert radio.sent_frames()[0].payload == bytes([4])
        await pilot.press("colon")
        app.query_one(Input).value = "setid 3"
        await pilot.press("enter")
        assert "usage: setid ID NEW_ID" in log_text(app)
        assert len(radio.sent) == 1

    run_app(test)


def test_the_keys_are_explained_on_screen() -> None:
    async def test(pilot: Pilot[int], radio: FakeRadio) -> None:
        app = console(pilot)
        await pilot.pause()
        text = log_text(app)
        for hint in ("s start", "x STOP", "p set parameter", "i identify", "d set id", "q quit"):
            assert hint in text
        await pilot.press("question_mark")
        await pilot.pause()
        shown = "\n".join(page_lines(app))
        assert "Keys" in shown and "STOP every particle" in shown
        assert "start [A|B|C|D]" in shown  # the commands follow the keys
        await pilot.press("escape")
        assert not isinstance(app.screen, PageScreen)

    run_app(test)


@pytest.mark.slow
def test_at_80_by_24_help_and_params_open_a_page_that_reads_at_that_width() -> None:
    # In the 8-line messages pane the help showed its last four commands, each summary squeezed
    # into the columns left beside the longest usage.
    async def test(pilot: Pilot[int], radio: FakeRadio) -> None:
        app = console(pilot)
        await pilot.press("question_mark")
        await pilot.pause()
        lines = page_lines(app)
        assert len(lines) >= 18
        assert all(len(line.rstrip()) <= 76 for line in lines)  # inside the page's frame
        start = next(i for i, line in enumerate(lines) if line.startswith("s "))
        # A long explanation wraps under itself, not under the key.
        assert lines[start + 1].startswith(" " * 5) and lines[start + 1].strip()
        await pilot.press("down", "pagedown")  # it scrolls to the commands at the end
        assert app.screen.query_one("#page-text").scroll_y > 0
        await pilot.press("q")  # q closes the page; it does not quit
        assert app.is_running and not isinstance(app.screen, PageScreen)
        await pilot.press("colon", *"params", "enter")
        await pilot.pause()
        assert "cycle_steps (1)" in "\n".join(page_lines(app))
        assert radio.sent == []

    run_app(test, size=(80, 24))


def test_a_replays_help_leaves_out_the_keys_that_send() -> None:
    async def test(pilot: Pilot[int], radio: FakeRadio) -> None:
        app = console(pilot)
        await pilot.press("question_mark")
        await pilot.pause()
        keys = {line.split()[0] for line in page_lines(app) if line[:1] not in (" ", "")}
        assert {"?", "q", ":"} <= keys
        assert not keys & {"s", "x", "p", "i", "d"}

    run_app(test, read_only=True)


def test_keys_typed_fast_after_s_or_colon_land_in_the_command_line() -> None:
    async def test(pilot: Pilot[int], radio: FakeRadio) -> None:
        app = console(pilot)
        hear_particles(radio, app, state=int(State.IDLE))
        command = app.query_one(Input)
        await burst(pilot, "s", "A")
        assert command.value == "start A"  # not the A lost on the table
        await pilot.press("escape")
        command.value = ""
        await burst(pilot, "colon", *"ping 2", "enter")
        assert wait_until(lambda: len(radio.sent) == 1)
        assert radio.sent_frames()[0].type_name == "PING"
        await burst(pilot, "s", "enter")
        assert wait_until(lambda: len(radio.sent) >= 2)
        assert isinstance(radio.sent_frames()[1].message, Start)

    run_app(test)


def test_in_the_command_line_the_keys_are_letters_and_the_footer_says_how_to_leave() -> None:
    async def test(pilot: Pilot[int], radio: FakeRadio) -> None:
        app = console(pilot)
        await pilot.press("colon", *"pids: ?")
        assert app.query_one(Input).value == "pids: ?"
        assert not isinstance(app.screen, PageScreen)
        footer = await footer_text(pilot)
        assert "Send" in footer and "Back" in footer
        await pilot.press("escape")
        assert app.query_one(DataTable).has_focus
        assert "Start" in await footer_text(pilot)

    run_app(test, size=(80, 24))


# ---- a small terminal ---------------------------------------------------------------------------


def test_at_80_by_24_every_row_of_ten_the_counters_and_the_keys_show() -> None:
    async def test(pilot: Pilot[int], radio: FakeRadio) -> None:
        app = console(pilot)
        hear_particles(radio, app, ids=range(1, 11))
        await refreshed(pilot)
        table = app.query_one(DataTable)
        assert table.row_count == 10
        assert table.max_scroll_y == 0  # all ten rows fit, none hidden below
        status = screen_lines(app.query_one("#status", Static))
        assert "10 particles" in status[0]
        assert "frames 10  bad 0" in status[1]
        assert "q Quit" in await footer_text(pilot)
        flags_header = table.ordered_columns[-1]
        assert str(flags_header.label) == "FLAGS"
        assert sum(c.get_render_width(table) for c in table.ordered_columns) <= 80

    run_app(test, size=(80, 24))


def test_at_80_by_24_long_flags_end_in_an_ellipsis_and_the_table_never_scrolls_sideways() -> None:
    async def test(pilot: Pilot[int], radio: FakeRadio) -> None:
        # A horizontal scrollbar took the tenth row, and "RESET in run 2" did not fit.
        app = console(pilot)
        hear_particles(radio, app, ids=range(1, 11), run_id=2, uptime_ms=50_000)
        radio.inject(status_frame(3, state=int(State.IDLE), resets=2, last_reset_cause=0x04))
        again = {"state": int(State.CYCLING), "run_id": 2, "uptime_ms": 50_500}
        radio.inject(status_frame(4, definition_hash=0x1234, sensor_faults=0b101, **again))
        assert wait_until(lambda: app.model.rows()[2].reset_in_run == 2)
        radio.clock.advance(8)  # and all of them silent: one more flag each
        await refreshed(pilot)
        table = app.query_one(DataTable)
        assert table.max_scroll_x == 0 and table.max_scroll_y == 0
        flags = [row["flags"] for row in table_text(app)]
        assert flags[2].startswith("RESET in run 2 ") and flags[2].endswith("…")
        assert flags[3].startswith("SILENT 8s HASH") and flags[3].endswith("…")
        width = table.ordered_columns[-1].get_render_width(table)
        assert all(len(text) <= width - 2 for text in flags)

    run_app(test, size=(80, 24))


def test_the_messages_pane_takes_the_room_the_table_leaves() -> None:
    async def test(pilot: Pilot[int], radio: FakeRadio) -> None:
        app = console(pilot)
        hear_particles(radio, app)
        await refreshed(pilot)
        table, messages = app.query_one(DataTable), app.query_one(RichLog)
        assert table.size.height == 4  # the header and three particles
        assert messages.size.height > 30  # of 50 rows
        hear_particles(radio, app, ids=range(1, 60))
        await refreshed(pilot)
        assert messages.size.height == 8  # at least its 8 lines, and the table scrolls
        assert table.max_scroll_y > 0

    run_app(test, size=(200, 50))


def test_messages_are_wrapped_again_when_the_terminal_narrows() -> None:
    async def test(pilot: Pilot[int], radio: FakeRadio) -> None:
        app = console(pilot)
        await pilot.pause()
        messages = app.query_one(RichLog)
        assert len(messages.lines) == 1  # the welcome, on one line of 200 columns
        await pilot.resize_terminal(80, 24)
        await pilot.pause()
        assert len(messages.lines) == 3
        assert messages.max_scroll_x == 0  # nothing cut at the edge, nothing to scroll to
        assert "q quit." in log_text(app).replace("\n", " ")
        await pilot.resize_terminal(200, 50)
        await pilot.pause()
        assert len(messages.lines) == 1

    run_app(test, size=(200, 50))


def test_seconds_since_heard_fit_their_column_however_long() -> None:
    assert [heard_text(s) for s in (0.04, 99.94, 1234.5, 10**7)] == [
        "0.0s", "99.9s", "1234s", "99999s",
    ]  # fmt: skip


@pytest.mark.slow
def test_at_80_by_24_a_bigger_swarm_scrolls_and_says_how_big_it_is() -> None:
    async def test(pilot: Pilot[int], radio: FakeRadio) -> None:
        app = console(pilot)
        hear_particles(radio, app, ids=range(1, 21))
        await refreshed(pilot)
        table = app.query_one(DataTable)
        assert "20 particles" in screen_lines(app.query_one("#status", Static))[0]
        assert table.max_scroll_y > 0
        await pilot.press(*["down"] * 19)  # to the last particle
        await pilot.pause()
        assert table.cursor_row == 19
        assert table.scroll_y == table.max_scroll_y  # the table scrolled to show it

    run_app(test, size=(80, 24))


def test_a_wide_terminal_shows_every_column() -> None:
    async def test(pilot: Pilot[int], radio: FakeRadio) -> None:
        app = console(pilot)
        hear_particles(radio, app)
        await refreshed(pilot)
        keys = [str(c.key.value) for c in app.query_one(DataTable).ordered_columns]
        assert keys == [
            "id", "state", "s_n", "light", "phase", "run", "hash", "bad", "resets", "heard",
            "flags",
        ]  # fmt: skip

    run_app(test, size=(200, 50))


# ---- resets --------------------------------------------------------------------------------------


def test_a_particle_that_reset_during_the_run_is_flagged_in_the_table() -> None:
    async def test(pilot: Pilot[int], radio: FakeRadio) -> None:
        app = console(pilot)
        hear_particles(radio, app, run_id=2, uptime_ms=50_000)
        radio.inject(status_frame(2, state=int(State.IDLE), resets=2, last_reset_cause=0x04))
        assert wait_until(lambda: app.model.rows()[1].reset_in_run == 2)
        await refreshed(pilot)
        rows = table_text(app)
        assert rows[1]["resets"] == "2 brown-out"
        assert rows[1]["flags"] == "RESET in run 2"
        assert [row["resets"] for row in (rows[0], rows[2])] == ["1 power-on"] * 2
        assert "Particle 2 reset during run 2 (brown-out" in log_text(app)

    run_app(test)


# ---- quitting and restarting while particles move ------------------------------------------------


def known(ids: range) -> Fleet:
    """A fleet file of these particles: the console knows whom a STOP must hear from."""
    fleet = Fleet.new()
    for particle in ids:
        fleet.record(ParticleRecord(particle))
    return fleet


def test_quitting_while_particles_move_asks_and_can_stop_them_first() -> None:
    async def test(pilot: Pilot[int], radio: FakeRadio) -> None:
        app = console(pilot)
        hear_particles(radio, app)
        await pilot.press("q")
        assert isinstance(app.screen, ConfirmScreen)
        assert "Particles 1-3 are in a run" in app.screen.question
        await pilot.press("y")
        assert wait_until(lambda: len(radio.sent) >= 1)
        assert radio.sent_frames()[0].message == Stop()
        assert app.is_running  # until every particle confirms
        radio.clock.advance(0.4)  # the whole burst is due
        # A poll sends one copy of the burst, and the quit waits for the last one: poll until
        # it is out (the app's own timer may have sent some already; relying on it raced).
        stop = app.model.last("STOP")
        assert stop is not None
        for _ in range(len(stop.burst)):
            await refreshed(pilot)
        assert stop.burst_sent and app.is_running
        hear_particles(radio, app, state=int(State.IDLE))
        await refreshed(pilot)
        assert not app.is_running

    app = run_app(test, fleet=known(range(1, 4)))
    assert app.return_value == 0


def test_a_stop_nobody_confirms_does_not_quit_but_asks_again() -> None:
    async def test(pilot: Pilot[int], radio: FakeRadio) -> None:
        app = console(pilot)
        hear_particles(radio, app)
        await pilot.press("q", "y")
        stop = app.model.last("STOP")
        assert stop is not None
        # Nobody answers: at its deadline the STOP ends unconfirmed, and the console stays.
        for _ in range(30):
            radio.clock.advance(0.5)
            await refreshed(pilot)
        assert stop.done and not stop.success
        assert app.is_running and isinstance(app.screen, ConfirmScreen)
        assert stop.outcome in app.screen.question
        assert "STOP was not confirmed: not quitting yet" in log_text(app)
        sent = len(radio.sent)
        await pilot.press("y")  # STOP again, and quit once it is confirmed
        assert wait_until(lambda: len(radio.sent) > sent)
        assert app.is_running
        await pilot.press("q")  # q quits at once
        await pilot.pause()
        assert not app.is_running

    run_app(test)


def test_quitting_while_particles_move_can_leave_them_running_or_be_cancelled() -> None:
    async def test(pilot: Pilot[int], radio: FakeRadio) -> None:
        app = console(pilot)
        hear_particles(radio, app)
        await pilot.press("q")
        await pilot.press("escape")
        assert not isinstance(app.screen, ConfirmScreen) and app.is_running
        await pilot.press("q", "n")
        await pilot.pause()
        assert not app.is_running
        assert radio.sent == []

    run_app(test)


def test_quitting_idle_particles_asks_nothing() -> None:
    async def test(pilot: Pilot[int], radio: FakeRadio) -> None:
        app = console(pilot)
        hear_particles(radio, app, state=int(State.IDLE))
        await pilot.press("q")
        await pilot.pause()
        assert not app.is_running

    run_app(test)


@pytest.mark.slow
def test_start_during_a_run_asks_before_restarting_it() -> None:
    async def test(pilot: Pilot[int], radio: FakeRadio) -> None:
        app = console(pilot)
        hear_particles(radio, app)
        await pilot.press("s", "enter")
        assert isinstance(app.screen, ConfirmScreen)
        await pilot.press("n")
        assert "START not sent" in log_text(app)
        assert radio.sent == []
        await pilot.press("s", "enter", "y")
        assert wait_until(lambda: len(radio.sent) >= 1)
        assert isinstance(radio.sent_frames()[0].message, Start)

    run_app(test)


# ---- a replay ------------------------------------------------------------------------------------


def test_a_replay_offers_no_command_that_sends() -> None:
    async def test(pilot: Pilot[int], radio: FakeRadio) -> None:
        app = console(pilot)
        hear_particles(radio, app)
        await pilot.press("s", "x")
        assert not app.query_one(Input).has_focus  # the keys that send do nothing
        footer = await footer_text(pilot)
        assert "Start" not in footer and "STOP" not in footer and "Quit" in footer
        await pilot.press("colon")
        app.query_one(Input).value = "stop"
        await pilot.press("enter")
        await refreshed(pilot)
        assert log_text(app).count("nothing can be sent") == 2  # the welcome, then once
        assert radio.sent == []
        await pilot.press("q")  # nothing moves in a replay: no question
        await pilot.pause()
        assert not app.is_running

    run_app(test, read_only=True)


# ---- a fleet -------------------------------------------------------------------------------------


def test_with_a_fleet_the_console_shows_who_is_missing_unknown_or_duplicated() -> None:
    fleet = Fleet.new()
    for particle in (1, 2, 3, 4):
        fleet.record(ParticleRecord(particle))

    async def test(pilot: Pilot[int], radio: FakeRadio) -> None:
        app = console(pilot)
        for particle in (1, 2):  # of the fleet's 1-4
            radio.inject(status_frame(particle, state=int(State.CYCLING)))
        radio.inject(status_frame(7, state=int(State.IDLE)))  # not in the fleet
        assert wait_until(lambda: sum(row.heard for row in app.model.rows()) == 3)
        # Two particles 2 on a transparent link: their uptimes cannot be one particle's.
        radio.inject(status_frame(2, state=int(State.CYCLING), uptime_ms=900_000))
        assert wait_until(lambda: any(row.duplicate for row in app.model.rows()))
        await refreshed(pilot)
        flags = {row["id"]: row["flags"] for row in table_text(app)}
        assert flags == {
            "1": "",
            "2": "DUPLICATE",
            "3": "NOT HEARD",
            "4": "NOT HEARD",
            "7": "NOT IN FLEET",
        }
        status = screen_lines(app.query_one("#status", Static))[0]
        assert "2 of 4 fleet particles heard, 1 not in the fleet" in status
        assert "DUPLICATE id 2" in log_text(app)
        await pilot.press("colon")
        app.query_one(Input).value = "forget 4"
        await pilot.press("enter")
        await refreshed(pilot)
        assert [row["id"] for row in table_text(app)] == ["1", "2", "3", "7"]
        status = screen_lines(app.query_one("#status", Static))[0]
        assert "2 of 3 fleet particles heard, 1 not in the fleet" in status

    run_app(test, size=(80, 24), fleet=fleet)
