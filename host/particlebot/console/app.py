"""The live console (Textual): a table of every particle heard, messages, and a command line."""

from __future__ import annotations

import contextlib
from collections.abc import Callable
from typing import ClassVar

from rich.text import Text
from textual.app import App, ComposeResult
from textual.binding import Binding, BindingType
from textual.css.query import NoMatches
from textual.widgets import DataTable, Footer, Input, RichLog, Static

from particlebot.console.commands import CommandError, execute, help_text
from particlebot.console.model import ConsoleModel, ParticleRow, state_name
from particlebot.protocol import UNASSIGNED_ID
from particlebot.radio import LinkState

COLUMNS = [
    ("id", "ID"),
    ("state", "STATE"),
    ("intensity", "INTENSITY"),
    ("s_n", "S_n"),
    ("phase", "PHASE"),
    ("run", "RUN"),
    ("hash", "FW HASH"),
    ("bad", "BAD RX"),
    ("heard", "HEARD"),
    ("flags", "FLAGS"),
]

# How often the model's campaigns are advanced: a STOP copy goes out at most this late, and the
# last of the burst must leave within ~0.35 s of the command for every servo to be contracted
# within 1 s.
POLL_S = 0.05

WELCOME = (
    "Keys: s start  x STOP  p set parameter  i identify  d set id  : command line  ? help  "
    "q quit.  Type 'help' in the command line for every command."
)


def _id_order(cell: Text) -> int:
    """Sort key of an ID cell: its number (every id fits a byte)."""
    return int(cell.plain) if cell.plain.isdigit() else 256


def row_cells(row: ParticleRow, now: float, model: ConsoleModel) -> dict[str, Text]:
    """The table cells of one particle, flags styled so they stand out."""
    status = row.status
    silent = row.silent(now, model.silent_after)
    mismatch = row.hash_mismatch(model.host_hash)
    age = max(0.0, now - row.last_heard)
    flags: list[str] = []
    if silent:
        flags.append(f"SILENT {age:.0f}s")
    if mismatch:
        flags.append("HASH MISMATCH")
    if row.id == UNASSIGNED_ID:
        flags.append("NO ID")
    if status is not None and status.sensor_faults:
        bad = [str(k) for k in range(6) if status.sensor_faults >> k & 1]
        flags.append("SENSOR A" + ",A".join(bad))
    dim = "dim" if silent else ""
    cells = {
        "id": Text(str(row.id), style="bold"),
        "state": Text(state_name(status.state) if status else "?", style=dim),
        "intensity": Text("" if row.intensity is None else str(row.intensity), style=dim),
        "s_n": Text(str(status.s_n) if status and status.s_n else "-", style=dim),
        "phase": Text(
            f"{status.cycle_phase / 1000:.2f}" if status and status.cycle_phase else "-", style=dim
        ),
        "run": Text(str(status.run_id) if status else "", style=dim),
        "hash": Text(
            f"{status.definition_hash:08X}" if status else "",
            style="bold red" if mismatch else dim,
        ),
        "bad": Text(str(row.bad_frames) if row.bad_frames is not None else "", style=dim),
        "heard": Text(f"{age:.1f}s", style="bold red" if silent else ""),
        "flags": Text(" ".join(flags), style="bold red" if flags else ""),
    }
    return cells


class ConsoleApp(App[int]):
    """Shows a ConsoleModel and sends its commands. `on_tick` (if given) runs with every poll
    of the model (POLL_S) and ends the app when it returns an exit code (the demo's script uses
    this)."""

    TITLE = "particlebot console"
    CSS = """
    #status { height: 2; padding: 0 1; background: $boost; }
    #table { height: 1fr; }
    #messages { height: 9; border-top: solid $primary; }
    #command { dock: bottom; }
    """
    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("s", "start", "Start"),
        Binding("x", "stop", "STOP"),
        Binding("p", "set_param", "Set param"),
        Binding("i", "identify", "Identify"),
        Binding("d", "set_id", "Set id"),
        Binding("colon", "command", "Command"),
        Binding("question_mark", "help", "Help"),
        Binding("q", "quit", "Quit"),
        Binding("ctrl+c", "quit", "Quit", show=False, priority=True),
        Binding("escape", "leave_command", "Back", show=False),
    ]

    def __init__(
        self,
        model: ConsoleModel,
        *,
        radio_name: str,
        log_path: str | None,
        on_tick: Callable[[], int | None] | None = None,
        linger_s: float = 3.0,
        refresh_s: float = 0.25,
    ) -> None:
        super().__init__()
        self.model = model
        self.radio_name = radio_name
        self.log_path = log_path
        self.on_tick = on_tick
        self.linger_s = linger_s
        self.refresh_s = refresh_s
        self._rows: set[str] = set()
        self._ending = False

    def compose(self) -> ComposeResult:
        yield Static(id="status")
        yield DataTable(id="table", cursor_type="row", zebra_stripes=True)
        yield RichLog(id="messages", wrap=True, markup=False)
        yield Input(
            placeholder="command (Enter sends, Esc goes back to the table; 'help' lists them)",
            id="command",
        )
        yield Footer()

    def on_mount(self) -> None:
        table = self.query_one("#table", DataTable)
        for key, label in COLUMNS:
            table.add_column(label, key=key)
        table.focus()
        self.query_one("#messages", RichLog).write(Text(WELCOME, style="bold"))
        self.refresh_view()
        self.set_interval(self.refresh_s, self.refresh_view)
        self.set_interval(POLL_S, self._tick)

    # ---- periodic --------------------------------------------------------------------------

    def _tick(self) -> None:
        self.model.poll()
        if self.on_tick is not None and not self._ending:
            code = self.on_tick()
            if code is not None:
                self._ending = True
                self.set_timer(self.linger_s, lambda: self.exit(code))

    def refresh_view(self) -> None:
        # A timer may fire while the app is shutting down and its widgets are gone.
        with contextlib.suppress(NoMatches):
            self._refresh_view()

    def _refresh_view(self) -> None:
        model = self.model
        now = model.clock()
        link = Text("connected", style="green")
        if model.link is not None and model.link.state in (LinkState.LOST, LinkState.CLOSED):
            link = Text(model.link.state.value.upper(), style="bold red")
        status = self.query_one("#status", Static)
        status.update(
            Text.assemble(
                f"radio {self.radio_name} [",
                link,
                f"]   log {self.log_path or '(none)'}   host protocol {model.host_hash:08X}\n",
                model.counters_text(),
            )
        )
        table = self.query_one("#table", DataTable)
        added = False
        for row in model.rows():
            cells = row_cells(row, now, model)
            if row.key not in self._rows:
                table.add_row(*(cells[key] for key, _ in COLUMNS), key=row.key)
                self._rows.add(row.key)
                added = True
            else:
                for key, _ in COLUMNS:
                    table.update_cell(row.key, key, cells[key], update_width=True)
        if added:
            # Particles are heard in any order; a person looks them up by id.
            table.sort("id", key=_id_order)
        log = self.query_one("#messages", RichLog)
        for note in model.new_notes():
            style = {"error": "bold red", "warning": "yellow"}.get(note.level, "")
            log.write(Text(note.text, style=style))

    # ---- actions ---------------------------------------------------------------------------

    def _prefill(self, text: str) -> None:
        command = self.query_one("#command", Input)
        command.value = text
        command.cursor_position = len(text)
        command.focus()

    def _selected_id(self) -> int | None:
        table = self.query_one("#table", DataTable)
        if table.row_count == 0:
            return None
        row_key, _ = table.coordinate_to_cell_key(table.cursor_coordinate)
        row = self.model.particles.get(str(row_key.value))
        return None if row is None else row.id

    def action_start(self) -> None:
        self._prefill("start D cycle=150 wave=0 update=0 phototaxis=0")

    def action_stop(self) -> None:
        self._run("stop")

    def action_set_param(self) -> None:
        self._prefill("set cycle_steps 150 all")

    def action_identify(self) -> None:
        selected = self._selected_id()
        self._prefill(f"identify {selected if selected is not None else 'all'}")

    def action_set_id(self) -> None:
        selected = self._selected_id()
        self._prefill(f"setid {selected if selected is not None else UNASSIGNED_ID} ")

    def action_command(self) -> None:
        self._prefill("")

    def action_help(self) -> None:
        self.query_one("#messages", RichLog).write(help_text())

    def action_leave_command(self) -> None:
        self.query_one("#table", DataTable).focus()

    def on_input_submitted(self, event: Input.Submitted) -> None:
        line = event.value.strip()
        event.input.value = ""
        self.query_one("#table", DataTable).focus()
        if line.lower() in ("quit", "exit", "q"):
            self.exit(0)
            return
        self._run(line)

    def _run(self, line: str) -> None:
        log = self.query_one("#messages", RichLog)
        if not line:
            return
        log.write(Text(f"> {line}", style="bold cyan"))
        try:
            reply = execute(self.model, line)
        except CommandError as exc:
            log.write(Text(str(exc), style="bold red"))
            return
        if reply:
            log.write(reply)
        self.refresh_view()
