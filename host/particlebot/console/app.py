"""The live console (Textual) on the Swarm API: a table of every particle, messages, commands."""

from __future__ import annotations

import contextlib
import threading
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from typing import ClassVar

from rich.console import Group, RenderableType
from rich.padding import Padding
from rich.table import Table
from rich.text import Text
from textual import events
from textual.app import App, ComposeResult
from textual.binding import Binding, BindingType
from textual.containers import Horizontal, Vertical, VerticalScroll
from textual.css.query import NoMatches
from textual.screen import ModalScreen
from textual.widgets import DataTable, Footer, Input, RichLog, Static

from particlebot.console.commands import (
    COMMANDS,
    CommandError,
    Prepared,
    params_entries,
    prepare,
)
from particlebot.protocol import UNASSIGNED_ID
from particlebot.radio import LinkState, RadioError
from particlebot.resets import reset_cause
from particlebot.swarm.api import Swarm
from particlebot.swarm.campaigns import Campaign, ids_text, state_name
from particlebot.swarm.results import SwarmError
from particlebot.swarm.roster import ParticleRow
from particlebot.swarm.tracker import SwarmTracker


@dataclass(frozen=True)
class Column:
    key: str
    label: str
    width: int
    """Columns the widest usual cell takes, with the table's padding."""
    drop_order: int = 0
    """0: always shown; otherwise, on a narrow screen the highest goes first."""


# Shown left to right; on a narrow screen the least needed go first (the hash, whose mismatch is
# also a flag; then the cycle phase; then the run id), so that 80 columns keep everything a
# person acts on: state, S_n, light, faults, resets, silence and the flags.
COLUMNS = [
    Column("id", "ID", 5),
    Column("state", "STATE", 13),
    Column("s_n", "S_n", 5),
    Column("light", "LIGHT", 7),
    Column("phase", "PHASE", 7, drop_order=3),
    Column("run", "RUN", 5, drop_order=2),
    Column("hash", "FW HASH", 10, drop_order=4),
    Column("bad", "BAD RX", 8, drop_order=1),
    Column("resets", "RESETS", 13, drop_order=1),
    Column("heard", "HEARD", 8),
    Column("flags", "FLAGS", 19),
]
"""FLAGS takes whatever width the others leave, at least room for "RESET in run 255"; a longer
list of flags (most urgent first) ends in an ellipsis rather than scroll the table sideways."""
# The table's vertical scrollbar.
SCROLLBAR = 2
# DataTable's padding: one cell either side of each column's content.
CELL_PADDING = 2
# Under the table: the messages pane's border and 8 lines (at least), the command line, the keys.
BELOW_TABLE = 1 + 8 + 1 + 1
# Above it: the status bar.
ABOVE_TABLE = 2
MAP_WIDTH = 42
"""Columns of the top view beside the table (a simulated swarm's world, when there is one)."""
MAP_HEIGHT = 14

WorldMap = Callable[[int, int], Text]
"""world_map(width, height) -> the top view of the swarm in that many characters."""
# Messages kept for the pane (the session log keeps them all).
MESSAGES_KEPT = 1000

# How often the swarm's campaigns are advanced: a STOP copy goes out at most this late, and the
# last of the burst must leave within ~0.35 s of the command for every servo to be contracted
# within 1 s.
POLL_S = 0.05

WELCOME = (
    "Keys: s start  x STOP  p set parameter  i identify  d set id  : command line  ? help  "
    "q quit.  Type 'help' in the command line for every command (forget, setid ... force)."
)
REPLAY_WELCOME = (
    "A replay of a log: the table shows what was heard; nothing can be sent.  Keys: ? help  q quit"
)
READ_ONLY = "This is a replay of a log: nothing can be sent to the particles."
START_HINT = (
    f"{COMMANDS['start'].usage}. Enter alone starts method D; whatever is left out keeps each "
    "particle's stored setting."
)
SET_HINT = f"{COMMANDS['set'].usage}: stored in each particle's EEPROM; 'params' lists them."
KEYS_HELP = [
    (
        "s",
        "start a run: the command line shows 'start '; Enter alone starts method D, and "
        "whatever is left out keeps each particle's stored setting",
    ),
    ("x", "STOP every particle, repeated until each one confirms"),
    ("p", "set a parameter (the command line shows 'set ')"),
    ("i", "identify: the selected particle wiggles three times"),
    ("d", "give the selected particle another id"),
    (":", "the command line: any command below; Enter sends it, Esc goes back to the table"),
    ("?", "this help"),
    ("q", "quit (asks first while particles are in a run)"),
    ("Up Down", "move through the table (PgUp, PgDn: a page) when it has more than fit"),
]
SENDING_ACTIONS = frozenset({"start", "stop", "set_param", "identify", "set_id"})
SENDING_KEYS = frozenset({"s", "x", "p", "i", "d"})
PROMPTING_ACTIONS = frozenset({"start", "set_param", "identify", "set_id", "command"})
"""The actions of the keys that open the command line (priority bindings)."""


def visible_columns(width: int) -> list[Column]:
    """The columns that fit a screen width cells wide."""
    shown = list(COLUMNS)
    droppable = sorted((c for c in COLUMNS if c.drop_order), key=lambda c: -c.drop_order)
    for column in droppable:
        if sum(c.width for c in shown) + SCROLLBAR <= width:
            break
        shown.remove(column)
    return shown


def flags_width(columns: list[Column], width: int) -> int:
    """The FLAGS column's content width: what the other columns leave of a screen width wide."""
    others = sum(c.width for c in columns if c.key != "flags")
    return max(COLUMNS[-1].width, width - SCROLLBAR - others) - CELL_PADDING


def heard_text(age: float) -> str:
    """Seconds since a particle was last heard, in the HEARD column's six cells."""
    return f"{age:.1f}s" if age < 100 else f"{min(age, 99999):.0f}s"


def _looks(cell: Text) -> tuple[str, str]:
    """What a cell shows: its text and its style (Text's == compares the text alone)."""
    return cell.plain, str(cell.style)


def _id_order(cell: Text) -> int:
    """Sort key of an ID cell: its number (every id fits a byte)."""
    return int(cell.plain) if cell.plain.isdigit() else 256


def row_cells(row: ParticleRow, now: float, tracker: SwarmTracker) -> dict[str, Text]:
    """The table cells of one particle, flags styled so they stand out."""
    status = row.status
    silent = row.silent(now, tracker.silent_after) or not row.heard
    mismatch = row.hash_mismatch(tracker.host_hash)
    age = max(0.0, now - row.last_heard)
    flags = row.flags(now, tracker.silent_after, tracker.host_hash)
    dim = "dim" if silent else ""
    resets = ""
    if status is not None:
        resets = f"{status.resets} {reset_cause(status.last_reset_cause)}"
    cells = {
        "id": Text(str(row.id), style="bold"),
        "state": Text(state_name(status.state) if status else "?", style=dim),
        "light": Text("" if row.intensity is None else str(row.intensity), style=dim),
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
        "resets": Text(resets, style="bold red" if row.reset_in_run is not None else dim),
        "heard": Text(
            heard_text(age) if row.heard else "never", style="bold red" if silent else ""
        ),
        "flags": Text(" ".join(flags), style="bold red" if flags else ""),
    }
    return cells


class ConfirmScreen(ModalScreen[str]):
    """A question answered with one key; Escape answers "cancel"."""

    DEFAULT_CSS = """
    ConfirmScreen { align: center middle; }
    #dialog {
        width: 72; max-width: 100%; height: auto;
        border: thick $warning; background: $surface; padding: 1 2;
    }
    #choices { margin-top: 1; }
    """
    BINDINGS: ClassVar[list[BindingType]] = [Binding("escape", "cancel", "Cancel")]

    def __init__(self, question: str, choices: list[tuple[str, str, str]]) -> None:
        """choices: (key, what it does, the answer dismiss() gives)."""
        super().__init__()
        self.question = question
        self.choices = choices

    def compose(self) -> ComposeResult:
        lines = Text("\n").join(
            Text.assemble((f"{key:>3}", "bold"), f"  {text}")
            for key, text, _ in [*self.choices, ("Esc", "cancel", "cancel")]
        )
        with Vertical(id="dialog"):
            yield Static(Text(self.question, style="bold"), id="question")
            yield Static(lines, id="choices")

    def on_key(self, event: events.Key) -> None:
        for key, _, answer in self.choices:
            if event.key == key:
                event.stop()
                self.dismiss(answer)
                return

    def action_cancel(self) -> None:
        self.dismiss("cancel")


def page(*sections: tuple[str, list[tuple[str, str]]]) -> Group:
    """Sections of (term, explanation) for a PageScreen: short terms (keys) in a column of their
    own, long ones (a command's usage) on a line above their explanation, so that the text wraps
    readably at any width."""
    parts: list[RenderableType] = []
    for title, entries in sections:
        parts.append(Text(title, style="bold underline"))
        if all(len(term) <= 8 for term, _ in entries):
            grid = Table.grid(padding=(0, 2))
            grid.add_column(style="bold", no_wrap=True)
            grid.add_column()
            for term, text in entries:
                grid.add_row(term, text)
            parts.append(grid)
        else:
            for term, text in entries:
                parts += [Text(term, style="bold"), Padding(Text(text), (0, 0, 0, 4))]
        parts.append(Text(""))
    return Group(*parts)


def help_page(read_only: bool = False) -> Group:
    """The keys and commands; a replay's leaves out the keys that would send."""
    keys = [(key, text) for key, text in KEYS_HELP if not (read_only and key in SENDING_KEYS)]
    commands = [(entry.usage, entry.summary) for entry in COMMANDS.values()]
    return page(("Keys", keys), ("Commands (type : first)", commands))


class PageScreen(ModalScreen[None]):
    """What is too long for the messages pane (help, params), scrolled on a page of its own."""

    DEFAULT_CSS = """
    PageScreen { align: center middle; }
    #page {
        width: 100%; max-width: 110; height: 100%;
        border: thick $primary; background: $surface; padding: 0 1;
    }
    #page-keys { dock: bottom; height: 1; color: $text-muted; }
    """
    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("escape,q,question_mark", "close", "Close"),
    ]

    def __init__(self, content: RenderableType) -> None:
        super().__init__()
        self.content = content

    def compose(self) -> ComposeResult:
        with Vertical(id="page"):
            yield Static("Up/Down, PgUp/PgDn scroll;  Esc, q or ? closes", id="page-keys")
            with VerticalScroll(id="page-text"):
                yield Static(self.content, id="page-body")

    def on_mount(self) -> None:
        # Focused at once, so that the keys that follow (Down, Esc) reach the page.
        self.set_focus(self.query_one("#page-text", VerticalScroll))

    def action_close(self) -> None:
        self.dismiss(None)


class MessageLog(RichLog):
    """The messages pane. RichLog wraps a line once, at the width it has then; this one keeps
    its messages and wraps them again whenever its width changes, so that a terminal made
    narrower shows them whole rather than cut at its edge."""

    def __init__(self, *, id: str) -> None:
        super().__init__(id=id, wrap=True, markup=False, max_lines=MESSAGES_KEPT)
        self.messages: deque[Text] = deque(maxlen=MESSAGES_KEPT)
        self._wrapped_at = 0
        """The content width the lines shown were wrapped at; 0 before the first layout."""

    def add(self, message: Text) -> None:
        self.messages.append(message)
        if self._wrapped_at:  # else written at the first layout
            self.write(message, width=self._wrapped_at)

    def on_resize(self, event: events.Resize) -> None:
        width = self.scrollable_content_region.width
        if width and width != self._wrapped_at:
            # At the first layout RichLog holds these writes back until its own handler, which
            # runs after this one; the width they carry is the one the pane has.
            self._wrapped_at = width
            self.clear()
            for message in self.messages:
                self.write(message, width=width)


class CommandLine(Input):
    """The command line; while it has the keys, the footer says how to leave it."""

    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("enter", "submit", "Send"),
        Binding("escape", "app.leave_command", "Back to the table"),
    ]


class ConsoleApp(App[int]):
    """Shows what a Swarm knows and sends its commands. `on_tick` (if given) runs with every
    poll (POLL_S) and ends the app when it returns an exit code. `script` (if given) runs on a
    thread of its own, driving the swarm through the blocking API while the console shows it
    (the demo); its return value ends the app. read_only (a replay): nothing can be sent, and
    the keys that send are not offered."""

    TITLE = "particlebot console"
    # The command palette offers nothing here and would take a place in the footer.
    ENABLE_COMMAND_PALETTE = False
    # The table is as tall as its rows, up to what leaves the messages pane its 8 lines (set in
    # _fit_table); the pane takes the rest. It never scrolls sideways: FLAGS ends in an ellipsis.
    CSS = """
    #status {
        height: 2; padding: 0 1; background: $boost; text-wrap: nowrap; text-overflow: ellipsis;
    }
    #table { height: auto; overflow-x: hidden; }
    #messages {
        height: 1fr; min-height: 9; border-top: solid $primary;
        overflow-x: hidden; scrollbar-gutter: stable;
    }
    #command { height: 1; border: none; padding: 0 1; }
    #command:focus { background: $boost; }
    #upper { height: auto; }
    #map { width: 42; height: 14; padding: 0 1; border-left: solid $primary; }
    """
    # The keys that open the command line are priority bindings, handled as they arrive: keys
    # typed right after them (or pasted, or sent by tmux) then reach the command line, not the
    # table. check_action hands them to the command line while it has the keys.
    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("s", "start", "Start", priority=True),
        Binding("x", "stop", "STOP"),
        Binding("p", "set_param", "Set", priority=True),
        Binding("i", "identify", "Identify", priority=True),
        Binding("d", "set_id", "Set id", priority=True),
        Binding("colon", "command", "Command", priority=True),
        Binding("question_mark", "help", "Help"),
        Binding("q", "quit", "Quit"),
        Binding("ctrl+c", "quit", "Quit", show=False, priority=True),
        Binding("escape", "leave_command", "Back", show=False),
    ]

    def __init__(
        self,
        swarm: Swarm,
        *,
        radio_name: str | None = None,
        log_path: str | None = None,
        on_tick: Callable[[], int | None] | None = None,
        script: Callable[[], int] | None = None,
        linger_s: float = 3.0,
        refresh_s: float = 0.25,
        read_only: bool = False,
        world_map: WorldMap | None = None,
    ) -> None:
        """world_map: draws a top view of the swarm beside the table (a simulation's truth)."""
        super().__init__()
        self.swarm = swarm
        self.radio_name = radio_name or swarm.url
        if log_path is None and swarm.log_path is not None:
            log_path = str(swarm.log_path)
        self.log_path = log_path
        self.on_tick = on_tick
        self.script = script
        self.linger_s = linger_s
        self.refresh_s = refresh_s
        self.read_only = read_only
        self.world_map = world_map
        self._rows: dict[str, dict[str, Text]] = {}
        """The cells each row shows now, by row key: only those that changed are redrawn."""
        self._columns: list[Column] = []
        self._flags_width = 0
        self._ending = False
        self._quit_after: Campaign | None = None
        """The STOP that quitting waits for (q then y while particles move)."""

    def compose(self) -> ComposeResult:
        yield Static(id="status")
        if self.world_map is None:
            yield DataTable(id="table", cursor_type="row", zebra_stripes=True)
        else:
            with Horizontal(id="upper"):
                yield DataTable(id="table", cursor_type="row", zebra_stripes=True)
                yield Static(id="map")
        yield MessageLog(id="messages")
        # Not select_on_focus: a prefilled command is completed, not typed over.
        yield CommandLine(
            placeholder="command (Enter sends, Esc goes back to the table; 'help' lists them)",
            id="command",
            select_on_focus=False,
        )
        footer = Footer()
        footer.compact = True
        yield footer

    def on_mount(self) -> None:
        self.query_one("#table", DataTable).focus()
        welcome = REPLAY_WELCOME if self.read_only else WELCOME
        self._write(welcome, "bold")
        self._fit_columns(self.size.width)
        self._fit_table(self.size.height)
        self.refresh_view()
        self.set_interval(self.refresh_s, self.refresh_view)
        self.set_interval(POLL_S, self._tick)
        if self.script is not None:
            threading.Thread(target=self._run_script, name="console-script", daemon=True).start()

    @property
    def model(self) -> SwarmTracker:
        """What the swarm knows: the rows, notes and campaigns the console shows."""
        return self.swarm.tracker

    def _run_script(self) -> None:
        assert self.script is not None
        try:
            code = self.script()
        except (SwarmError, RadioError) as exc:
            if self.swarm.closed:
                return  # the console was left first
            self.model.note(str(exc), "error")
            code = 1
        with contextlib.suppress(RuntimeError):  # the app has ended already
            self.call_from_thread(self._end_after_linger, code)

    def _end_after_linger(self, code: int) -> None:
        if not self._ending:
            self._ending = True
            self.set_timer(self.linger_s, lambda: self.exit(code))

    def on_resize(self, event: events.Resize) -> None:
        self._fit_columns(event.size.width)
        self._fit_table(event.size.height)

    def check_action(self, action: str, parameters: tuple[object, ...]) -> bool | None:
        if action in PROMPTING_ACTIONS and (
            self.screen is not self.screen_stack[0] or isinstance(self.focused, Input)
        ):
            return False  # the key is a letter in the command line, or a dialog is open
        # A replay cannot send: its keys are not offered at all.
        return not (self.read_only and action in SENDING_ACTIONS)

    # ---- periodic --------------------------------------------------------------------------

    def _tick(self) -> None:
        with contextlib.suppress(RadioError):  # the status bar shows a failed radio
            self.swarm.poll()
        if self._quit_after is not None and self._quit_after.done:
            self._stop_before_quit_ended(self._quit_after)
        if self.on_tick is not None and not self._ending:
            code = self.on_tick()
            if code is not None:
                self._end_after_linger(code)

    def refresh_view(self) -> None:
        # A timer may fire while the app is shutting down and its widgets are gone.
        with contextlib.suppress(NoMatches):
            self._refresh_view()

    def _status_text(self) -> Text:
        model = self.model
        link = Text("connected", style="green")
        if model.link is not None and model.link.state in (LinkState.LOST, LinkState.CLOSED):
            link = Text(model.link.state.value.upper(), style="bold red")
        rows = model.rows()
        heard = [row for row in rows if row.heard]
        silent = sum(1 for row in heard if row.silent(model.clock(), model.silent_after))
        if model.roster is None:
            count = f"{len(heard)} particle{'' if len(heard) == 1 else 's'}"
        else:  # the fleet's particles heard (a duplicate id once); strangers are not of them
            members = {row.id for row in heard if row.in_fleet}
            strangers = sum(1 for row in heard if row.in_fleet is False)
            count = f"{len(members)} of {len(model.roster)} fleet particles heard"
            if strangers:
                count += f", {strangers} not in the fleet"
        if silent:
            count += f" ({silent} silent)"
        # Each line is cut rather than wrapped: a wrapped first line would push the counters of
        # bad frames out of the two lines the bar has.
        text = Text.assemble(
            f"{self.radio_name} [",
            link,
            f"]  {count}  log {self.log_path or '(none)'}  host protocol {model.host_hash:08X}\n",
            model.counters_text(),
        )
        return text

    def _fit_columns(self, width: int) -> None:
        if self.world_map is not None:
            width -= MAP_WIDTH
        columns = visible_columns(width)
        flags = flags_width(columns, width)
        if (columns, flags) == (self._columns, self._flags_width):
            return
        self._columns = columns
        self._flags_width = flags
        with contextlib.suppress(NoMatches):
            table = self.query_one("#table", DataTable)
            table.clear(columns=True)
            for column in columns:
                fixed = flags if column.key == "flags" else None
                table.add_column(column.label, key=column.key, width=fixed)
            self._rows.clear()
            self.refresh_view()

    def _fit_table(self, height: int) -> None:
        """At most as tall as leaves the messages pane its 8 lines; more rows scroll."""
        with contextlib.suppress(NoMatches):
            table = self.query_one("#table", DataTable)
            table.styles.max_height = max(3, height - ABOVE_TABLE - BELOW_TABLE)

    def _refresh_view(self) -> None:
        model = self.model
        now = model.clock()
        self.query_one("#status", Static).update(self._status_text())
        if self.world_map is not None:
            # Inside the border and the padding.
            self.query_one("#map", Static).update(self.world_map(MAP_WIDTH - 3, MAP_HEIGHT))
        table = self.query_one("#table", DataTable)
        added = False
        rows = model.rows()
        # A renamed or forgotten particle's row goes.
        for key in set(self._rows) - {row.key for row in rows}:
            table.remove_row(key)
            del self._rows[key]
        for row in rows:
            cells = row_cells(row, now, model)
            cells["flags"].truncate(self._flags_width, overflow="ellipsis")
            shown = self._rows.get(row.key)
            if shown is None:
                table.add_row(*(cells[c.key] for c in self._columns), key=row.key)
                added = True
            else:
                for column in self._columns:
                    if _looks(cells[column.key]) != _looks(shown[column.key]):
                        table.update_cell(row.key, column.key, cells[column.key], update_width=True)
            self._rows[row.key] = cells
        if added:
            # Particles are heard in any order; a person looks them up by id.
            table.sort("id", key=_id_order)
        for note in model.new_notes():
            self._write(note.text, {"error": "bold red", "warning": "yellow"}.get(note.level, ""))

    # ---- actions ---------------------------------------------------------------------------

    def _write(self, text: str | Text, style: str = "") -> None:
        message = text if isinstance(text, Text) else Text(text, style=style)
        self.query_one("#messages", MessageLog).add(message)

    def _prefill(self, text: str, hint: str | None = None) -> None:
        if hint is not None:
            self._write(hint, "dim")
        command = self.query_one("#command", Input)
        command.value = text
        command.cursor_position = len(text)
        # At once, not at the next idle moment as focus() would: keys already on their way
        # (typed fast, pasted) must land in the command line.
        self.screen.set_focus(command)

    def _selected_id(self) -> int | None:
        table = self.query_one("#table", DataTable)
        if table.row_count == 0:
            return None
        row_key, _ = table.coordinate_to_cell_key(table.cursor_coordinate)
        row = self.model.particles.get(str(row_key.value))
        return None if row is None else row.id

    def action_start(self) -> None:
        # Only what a person types changes a particle's stored settings: Enter alone sends the
        # default method with every option left to the particles.
        self._prefill("start ", START_HINT)

    def action_stop(self) -> None:
        self._run("stop")

    def action_set_param(self) -> None:
        self._prefill("set ", SET_HINT)

    def action_identify(self) -> None:
        selected = self._selected_id()
        self._prefill(f"identify {selected if selected is not None else 'all'}")

    def action_set_id(self) -> None:
        selected = self._selected_id()
        self._prefill(f"setid {selected if selected is not None else UNASSIGNED_ID} ")

    def action_command(self) -> None:
        self._prefill("")

    def action_help(self) -> None:
        self.push_screen(PageScreen(help_page(self.read_only)))

    def action_leave_command(self) -> None:
        self.query_one("#table", DataTable).focus()

    async def action_quit(self) -> None:
        """Quits; while particles move, first asks whether to STOP them."""
        if self._quit_after is not None or isinstance(self.screen, ConfirmScreen):
            self.exit(0)  # asked twice: the person means it
            return
        moving = [] if self.read_only else self.model.moving_ids()
        if not moving:
            self.exit(0)
            return

        self._ask_about_run(
            moving,
            "Send STOP before quitting?",
            [
                ("y", "send STOP, then quit once they confirm it", "stop"),
                ("n", "quit and leave them running", "quit"),
            ],
            self._answered_quit,
        )

    def _answered_quit(self, answer: str | None) -> None:
        if answer == "stop":
            self._run("stop")
            self._quit_after = self.model.last("STOP")
            self._write(
                "Quitting once every particle confirms STOP (at most "
                f"{self.model.stop_timeout:.0f} s); q quits at once",
                "yellow",
            )
        elif answer == "quit":
            self.exit(0)

    def _stop_before_quit_ended(self, stop: Campaign) -> None:
        """The STOP that quitting waited for has ended: quits if it was confirmed; otherwise
        says so (the outcome is in the messages) and asks again, for nothing says the
        particles stopped."""
        self._quit_after = None
        if stop.success:
            self.exit(0)
            return
        self._write("STOP was not confirmed: not quitting yet", "bold red")
        self.push_screen(
            ConfirmScreen(
                f"{stop.outcome}. Quit all the same?",
                [
                    ("y", "send STOP again, then quit once they confirm it", "stop"),
                    ("n", "quit, leaving them as they are", "quit"),
                ],
            ),
            self._answered_quit,
        )

    async def on_input_submitted(self, event: Input.Submitted) -> None:
        line = event.value.strip()
        event.input.value = ""
        self.query_one("#table", DataTable).focus()
        if line.lower() in ("quit", "exit", "q"):
            await self.action_quit()
            return
        self._run(line)

    def _run(self, line: str) -> None:
        if not line:
            return
        self._write(f"> {line}", "bold cyan")
        try:
            prepared = prepare(self.swarm, line)
        except CommandError as exc:
            self._write(str(exc), "bold red")
            return
        if prepared is None:
            return
        if self.read_only and prepared.sends:
            self._write(READ_ONLY, "bold red")
            return
        moving = self.model.moving_ids()
        if prepared.name == "start" and moving:

            def answered(answer: str | None) -> None:
                if answer == "restart":
                    self._carry_out(prepared)
                else:
                    self._write("START not sent; the run goes on", "yellow")

            self._ask_about_run(
                moving,
                "Restart with this START?",
                [
                    ("y", "restart: each particle estimates afresh and starts over", "restart"),
                    ("n", "keep the run going", "cancel"),
                ],
                answered,
            )
            return
        self._carry_out(prepared)

    def _ask_about_run(
        self,
        moving: list[int],
        question: str,
        choices: list[tuple[str, str, str]],
        answered: Callable[[str | None], None],
    ) -> None:
        """Asks, naming the particles in a run, what to do about them."""
        many = len(moving) > 1
        who = f"Particle{'s' if many else ''} {ids_text(moving)} {'are' if many else 'is'}"
        self.push_screen(ConfirmScreen(f"{who} in a run. {question}", choices), answered)

    def _carry_out(self, prepared: Prepared) -> None:
        try:
            reply = prepared.run()
        except CommandError as exc:
            self._write(str(exc), "bold red")
            return
        if prepared.name == "help" and reply.count("\n") >= 8:
            self.action_help()  # every command: with the keys, as ? shows them
        elif prepared.name == "params":
            params = ("Parameters (set NAME VALUE [ID|all])", params_entries())
            self.push_screen(PageScreen(page(params)))
        elif reply:
            self._write(reply)
        self.refresh_view()
