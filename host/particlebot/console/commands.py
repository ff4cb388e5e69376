"""The console's command line: parses what a person types and calls the Swarm API (no UI here)."""

from __future__ import annotations

import shlex
from collections.abc import Callable
from dataclasses import dataclass

from particlebot.errors import ParticlebotError
from particlebot.protocol import BROADCAST_ID, PARAM_SPECS, Method, Param
from particlebot.swarm.api import METHODS, Swarm
from particlebot.swarm.results import SwarmError

METHOD_NAMES: dict[str, Method] = METHODS


class CommandError(ParticlebotError, ValueError):
    """The line could not be understood; the message says how to write it."""


@dataclass(frozen=True)
class Prepared:
    """A command line understood and checked, not yet carried out: the console can ask for a
    confirmation (restarting a run) before run() sends anything."""

    name: str
    run: Callable[[], str]

    @property
    def sends(self) -> bool:
        """Whether it sends to the particles (a replay cannot)."""
        return self.name in SENDING


@dataclass(frozen=True)
class CommandHelp:
    usage: str
    summary: str


COMMANDS: dict[str, CommandHelp] = {
    "start": CommandHelp(
        "start [A|B|C|D] [cycle=STEPS] [wave=N] [update=S] [phototaxis=0|1]",
        "start a run: estimation method A direct, B linear, C nonlinear, D counting (default D); "
        "cycle = servo steps of 20 ms per cycle, wave = N of eq. 3, update = seconds between "
        "re-estimations; left out (or 0), cycle and update keep each particle's stored value "
        "and wave is automatic",
    ),
    "stop": CommandHelp(
        "stop",
        "broadcast STOP several times at once, then again until every known particle reports "
        "it stopped",
    ),
    "set": CommandHelp(
        "set PARAM VALUE [ID|all]", "set a parameter (stored in EEPROM; refused while running)"
    ),
    "get": CommandHelp("get PARAM [ID|all]", "read a parameter"),
    "params": CommandHelp("params", "list the parameters with their ranges and defaults"),
    "identify": CommandHelp("identify ID|all", "make an idle particle wiggle three times"),
    "setid": CommandHelp(
        "setid ID NEW_ID [force]",
        "give the particle with id ID the id NEW_ID (1..253); an id in use (the fleet's, or "
        "answering) is refused unless forced",
    ),
    "forget": CommandHelp(
        "forget ID", "drop a particle that is gone for good: STOP no longer waits for it"
    ),
    "ping": CommandHelp("ping [ID|all]", "ask for a STATUS now"),
    "help": CommandHelp("help [COMMAND]", "show the commands"),
    "quit": CommandHelp("quit", "leave the console (the log is kept)"),
}


def help_text(command: str | None = None) -> str:
    if command is not None:
        entry = COMMANDS.get(command)
        if entry is None:
            raise CommandError(f"No command '{command}'. Commands: {', '.join(COMMANDS)}")
        return f"{entry.usage}\n  {entry.summary}"
    # Usage above its summary: two columns would leave the summaries a sliver of an 80-column
    # screen beside the longest usage.
    return "\n".join(f"{entry.usage}\n    {entry.summary}" for entry in COMMANDS.values())


def params_entries() -> list[tuple[str, str]]:
    """(name and number, range, default and meaning) of every parameter."""
    return [
        (
            f"{param.name.lower()} ({int(param)})",
            f"{spec.min}..{spec.max}, default {spec.default}: {spec.description}",
        )
        for param, spec in PARAM_SPECS.items()
    ]


def params_text() -> str:
    return "\n".join(f"{name}  {text}" for name, text in params_entries())


def parse_param(text: str) -> Param:
    try:
        return Param(int(text, 0)) if text[:1].isdigit() else Param[text.upper()]
    except (KeyError, ValueError):
        raise CommandError(f"No parameter '{text}'; type 'params' for the list") from None


def parse_target(text: str | None, *, allow_all: bool = True) -> int:
    if text is None or text.lower() in ("all", "*"):
        if not allow_all:
            raise CommandError("Name one particle by its id here")
        return BROADCAST_ID
    try:
        value = int(text, 0)
    except ValueError:
        raise CommandError(f"'{text}' is not a particle id (a number, or 'all')") from None
    if not 0 <= value <= 255:
        raise CommandError(f"Particle ids are 1..254, not {value}")
    return value


def _int(text: str, what: str) -> int:
    try:
        return int(text, 0)
    except ValueError:
        raise CommandError(f"{what} must be a whole number, not '{text}'") from None


def _check_range(value: int, param: Param, what: str, zero_ok: bool) -> None:
    spec = PARAM_SPECS[param]
    if zero_ok and value == 0:
        return
    if not spec.min <= value <= spec.max:
        extra = " (or 0 to keep the stored value)" if zero_ok else ""
        raise CommandError(f"{what} must be {spec.min}..{spec.max}{extra}, not {value}")


def _start(swarm: Swarm, args: list[str]) -> Callable[[], str]:
    method = Method.COUNTING
    options = {"cycle": 0, "wave": 0, "update": 0, "phototaxis": 0}
    aliases = {"photo": "phototaxis", "cycle_steps": "cycle", "wave_size": "wave"}
    for arg in args:
        if "=" in arg:
            key, _, value = arg.partition("=")
            key = aliases.get(key.lower(), key.lower())
            if key not in options:
                raise CommandError(f"start takes cycle=, wave=, update=, phototaxis=; not '{key}='")
            options[key] = _int(value, key)
        elif arg.lower() in METHOD_NAMES:
            method = METHOD_NAMES[arg.lower()]
        else:
            raise CommandError(f"Unknown method '{arg}': use A, B, C or D")
    _check_range(options["cycle"], Param.CYCLE_STEPS, "cycle", zero_ok=True)
    _check_range(options["update"], Param.UPDATE_INTERVAL_S, "update", zero_ok=True)
    _check_range(options["wave"], Param.WAVE_SIZE, "wave", zero_ok=True)
    if options["phototaxis"] not in (0, 1):
        raise CommandError("phototaxis must be 0 or 1")

    def send() -> str:
        campaign = swarm.send_start(
            method,
            cycle_steps=options["cycle"],
            wave_size=options["wave"],
            update_interval_s=options["update"],
            phototaxis=bool(options["phototaxis"]),
        )
        return (
            f"START run {swarm.tracker.run_id} method {method.name} sent to "
            f"{len(campaign.pending)} known particle(s); asking each (PING) until it confirms, "
            "resending to any that missed it"
        )

    return send


def _stop(swarm: Swarm, args: list[str]) -> Callable[[], str]:
    def send() -> str:
        campaign = swarm.send_stop()
        expected = max(len(campaign.pending), campaign.required())
        text = (
            f"STOP sent ({len(campaign.burst)} copies in {campaign.burst[-1]:.1f} s); repeating "
            f"until all {expected} expected particle(s) report it"
        )
        if campaign.hold_until > campaign.started:
            text += (
                f", and for {campaign.hold_until - campaign.started:.0f} s whatever is heard "
                "(the console has just started: particles it has not heard yet may be moving)"
            )
        return text

    return send


def _set(swarm: Swarm, args: list[str]) -> Callable[[], str]:
    if len(args) not in (2, 3):
        raise CommandError(f"usage: {COMMANDS['set'].usage}")
    param = parse_param(args[0])
    value = _int(args[1], "VALUE")
    _check_range(value, param, param.name.lower(), zero_ok=False)
    target = parse_target(args[2] if len(args) == 3 else None)

    def send() -> str:
        swarm.send_set(param, value, _one(target))
        return f"SET_PARAM {param.name} = {value} sent to {_target_text(target)}"

    return send


def _get(swarm: Swarm, args: list[str]) -> Callable[[], str]:
    if len(args) not in (1, 2):
        raise CommandError(f"usage: {COMMANDS['get'].usage}")
    param = parse_param(args[0])
    target = parse_target(args[1] if len(args) == 2 else None)

    def send() -> str:
        swarm.send_get(param, _one(target))
        return f"GET_PARAM {param.name} sent to {_target_text(target)}"

    return send


def _identify(swarm: Swarm, args: list[str]) -> Callable[[], str]:
    if len(args) != 1:
        raise CommandError(f"usage: {COMMANDS['identify'].usage}")
    target = parse_target(args[0])

    def send() -> str:
        swarm.identify(_one(target))
        return f"IDENTIFY sent to {_target_text(target)}"

    return send


def _setid(swarm: Swarm, args: list[str]) -> Callable[[], str]:
    force = bool(args) and args[-1].lower() == "force"
    if force:
        args = args[:-1]
    if len(args) != 2:
        raise CommandError(f"usage: {COMMANDS['setid'].usage}")
    target = parse_target(args[0], allow_all=False)
    new_id = _int(args[1], "NEW_ID")
    if target == BROADCAST_ID:
        raise CommandError("SET_ID must name one particle, never broadcast")
    if not 1 <= new_id <= 253:
        raise CommandError(f"NEW_ID must be 1..253, not {new_id}")
    if not force and new_id != target and new_id in swarm.tracker.ids_in_use():
        raise CommandError(
            f"Id {new_id} is in use (the fleet's, or a particle answers with it): choose a free "
            f"one, or 'setid {target} {new_id} force' if particle {new_id} is gone"
        )

    def send() -> str:
        try:
            swarm.send_set_id(target, new_id, force=force)
        except SwarmError as exc:
            raise CommandError(str(exc)) from None
        return f"SET_ID {target} -> {new_id} sent"

    return send


def _forget(swarm: Swarm, args: list[str]) -> Callable[[], str]:
    if len(args) != 1:
        raise CommandError(f"usage: {COMMANDS['forget'].usage}")
    target = parse_target(args[0], allow_all=False)

    def forget() -> str:
        # The swarm notes what it forgot (shown, and logged).
        return "" if swarm.forget(target) else f"No particle {target} to forget"

    return forget


def _one(target: int) -> int | None:
    """The Swarm API's way of saying every particle: None."""
    return None if target == BROADCAST_ID else target


def _ping(swarm: Swarm, args: list[str]) -> Callable[[], str]:
    target = parse_target(args[0] if args else None)

    def send() -> str:
        swarm.ping(_one(target))
        return f"PING sent to {_target_text(target)}"

    return send


def _show(text: Callable[[], str]) -> Callable[[Swarm, list[str]], Callable[[], str]]:
    """A command that only shows text."""
    return lambda swarm, args: text


def _target_text(target: int) -> str:
    return "all particles" if target == BROADCAST_ID else f"particle {target}"


def _help(swarm: Swarm, args: list[str]) -> Callable[[], str]:
    text = help_text(args[0] if args else None)  # an unknown command is an error now
    return lambda: text


# Each handler checks its arguments (CommandError) and returns what carries the command out.
_HANDLERS: dict[str, Callable[[Swarm, list[str]], Callable[[], str]]] = {
    "start": _start,
    "stop": _stop,
    "set": _set,
    "get": _get,
    "identify": _identify,
    "setid": _setid,
    "ping": _ping,
    "forget": _forget,
    "params": _show(params_text),
    "help": _help,
}
SENDING = frozenset({"start", "stop", "set", "get", "identify", "setid", "ping"})


def prepare(swarm: Swarm, line: str) -> Prepared | None:
    """Understands and checks one command line without carrying it out; None for a blank line,
    CommandError if it is not understood. `quit` is the UI's business and is not handled here."""
    try:
        words = shlex.split(line)
    except ValueError as exc:
        raise CommandError(str(exc)) from None
    if not words:
        return None
    name, args = words[0].lower(), words[1:]
    handler = _HANDLERS.get(name)
    if handler is None:
        raise CommandError(f"Unknown command '{name}'. Type 'help' for the list.")
    return Prepared(name, handler(swarm, args))


def execute(swarm: Swarm, line: str) -> str:
    """Runs one command line; returns what to show. CommandError if it is not understood."""
    prepared = prepare(swarm, line)
    return "" if prepared is None else prepared.run()
