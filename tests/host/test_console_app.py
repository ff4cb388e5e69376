"""The Textual console through its headless pilot: keys send the right frames, the table fills."""

from __future__ import annotations

import asyncio
from collections.abc import Callable, Coroutine
from typing import Any

from textual.pilot import Pilot
from textual.widgets import DataTable, Input, RichLog

from particlebot.console.app import ConsoleApp
from particlebot.console.model import ConsoleModel
from particlebot.protocol import DEFINITION_HASH, Method, Start, State, Stop
from particlebot.session import Session
from tests.host.fakes import FakeRadio, Recorder, status_frame, wait_until


def run_app(test: Callable[[Pilot[int], FakeRadio], Coroutine[Any, Any, None]]) -> None:
    radio = FakeRadio()
    recorder = Recorder()
    session = Session(radio, [recorder])
    model = ConsoleModel(session, radio.now)
    session.add_listener(model)
    session.start()
    app = ConsoleApp(model, radio_name="fake://", log_path="logs/test.jsonl", refresh_s=0.05)

    async def body() -> None:
        async with app.run_test(size=(140, 40)) as pilot:
            await test(pilot, radio)

    try:
        asyncio.run(body())
    finally:
        session.close()


def hear_particles(radio: FakeRadio, app: ConsoleApp, **fields: int) -> None:
    for particle in (1, 2, 3):
        radio.inject(status_frame(particle, state=int(State.CYCLING), s_n=particle, **fields))
    assert wait_until(lambda: len(app.model.rows()) == 3)


def console(pilot: Pilot[int]) -> ConsoleApp:
    assert isinstance(pilot.app, ConsoleApp)
    return pilot.app


async def refreshed(pilot: Pilot[int]) -> None:
    """Lets the app's refresh timer (every 0.05 s here) run at least once."""
    await pilot.pause(0.12)


def table_text(app: ConsoleApp) -> list[list[str]]:
    table = app.query_one(DataTable)
    return [[str(cell) for cell in table.get_row_at(i)] for i in range(table.row_count)]


def log_text(app: ConsoleApp) -> str:
    return "\n".join(str(line.text) for line in app.query_one(RichLog).lines)


def test_every_particle_heard_appears_in_the_table_with_its_s_n() -> None:
    async def test(pilot: Pilot[int], radio: FakeRadio) -> None:
        app = console(pilot)
        hear_particles(radio, app)
        await refreshed(pilot)
        rows = table_text(app)
        assert [row[0] for row in rows] == ["1", "2", "3"]
        assert [row[3] for row in rows] == ["1", "2", "3"]
        assert all(row[1] == "CYCLING" for row in rows)
        assert all(row[6] == f"{DEFINITION_HASH:08X}" for row in rows)

    run_app(test)


def test_the_table_lists_particles_by_id_whatever_order_they_are_heard_in() -> None:
    async def test(pilot: Pilot[int], radio: FakeRadio) -> None:
        app = console(pilot)
        for particle in (12, 3, 7):
            radio.inject(status_frame(particle, state=int(State.IDLE)))
            assert wait_until(lambda: particle in {row.id for row in app.model.rows()})  # noqa: B023
            await refreshed(pilot)  # each one is added to the table on its own
        assert [row[0] for row in table_text(app)] == ["3", "7", "12"]

    run_app(test)


def test_a_foreign_firmware_hash_is_flagged_in_the_table() -> None:
    async def test(pilot: Pilot[int], radio: FakeRadio) -> None:
        app = console(pilot)
        hear_particles(radio, app, definition_hash=0x12345678)
        await refreshed(pilot)
        assert all("HASH MISMATCH" in row[-1] for row in table_text(app))

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


def test_the_s_key_offers_a_start_line_that_enter_sends() -> None:
    async def test(pilot: Pilot[int], radio: FakeRadio) -> None:
        app = console(pilot)
        hear_particles(radio, app)
        await pilot.press("s")
        command = app.query_one(Input)
        assert command.has_focus
        assert command.value.startswith("start D")
        await pilot.press("enter")
        assert wait_until(lambda: len(radio.sent) >= 1)
        message = radio.sent_frames()[0].message
        assert isinstance(message, Start)
        assert (message.method, message.cycle_steps) == (Method.COUNTING, 150)

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
        assert "setid ID NEW_ID" in log_text(app)

    run_app(test)
