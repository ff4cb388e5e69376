"""What the base station knows of the swarm: its rows, the roster, flags, notes and counters."""

from __future__ import annotations

import re
from collections import deque
from collections.abc import Callable, Iterable
from dataclasses import dataclass

from particlebot.errors import ParticlebotError
from particlebot.protocol import (
    BASE_STATION_ID,
    DEFINITION_HASH,
    UNASSIGNED_ID,
    Intensity,
    ParamValue,
    Status,
)
from particlebot.radio import LinkEvent, LinkState
from particlebot.resets import ADVICE, reset_between, reset_cause
from particlebot.session import ReceivedFrame
from particlebot.swarm.campaigns import Campaign, state_name
from particlebot.swarm.roster import (
    RECENT_S,
    RUN_STATES,
    SILENT_AFTER_S,
    ParticleRow,
    two_clocks,
    two_senders,
)

# Particles send STATUS every 2 s: hearing nothing at all for longer than two of those means the
# link, not the swarm, is the likelier problem.
QUIET_HINT_S = 5.0
RENAME_WINDOW_S = 30.0
"""How long after a SET_ID its new id answering counts as the renamed particle."""
RENAME_SLACK_S = 1.0
"""A STATUS under the old id that arrives this soon after the SET_ID left before it landed."""

_SHARED_SOURCE = re.compile(r"[0-9A-Fa-f]{4}")
"""16-bit XBee addresses: every particle whose radio keeps the factory MY=0 sends from 0000."""


def identifying(source: str | None) -> bool:
    """Whether a packet's source names one radio (a 64-bit address, a simulated node)."""
    return source is not None and not _SHARED_SOURCE.fullmatch(source)


def fresh(row: ParticleRow, since: float) -> bool:
    """Whether row's last STATUS was received after since (one received at the very moment a
    command went out cannot answer it: the command alone takes milliseconds to arrive)."""
    return row.status_time is not None and row.status_time > since


class IdInUseError(ParticlebotError, ValueError):
    """SET_ID to an id another particle has (in the fleet or heard); force=True overrides."""


@dataclass(frozen=True)
class ModelNote:
    time: float
    text: str
    level: str = "info"  # info, warning, error


@dataclass(frozen=True)
class Rename:
    """A particle that now answers under another id (the owner updates the fleet file)."""

    old_id: int
    new_id: int
    source: str | None


class SwarmModel:
    """Per-particle rows from the frames a session delivers, the roster they are checked
    against, the notes shown to the person and the link's counters. Not thread-safe: the
    SwarmTracker that owns it holds its lock around every call.

    roster: the particle ids of the fleet file, or None without one. Every roster particle is
    expected to confirm a STOP (shown as NOT HEARD until it answers); without a roster, every
    particle heard in the last recent_s is, and never fewer than the largest group seen (a weak
    floor: see required_count).
    """

    def __init__(
        self,
        clock: Callable[[], float],
        log: Callable[[str], None] | None,
        *,
        roster: Iterable[int] | None = None,
        host_hash: int = DEFINITION_HASH,
        silent_after: float = SILENT_AFTER_S,
        recent_s: float = RECENT_S,
        quiet_hint: str | None = None,
        quiet_after: float | None = None,
    ) -> None:
        """log: where notes are written besides the notes pane (the session's log), or None.
        quiet_hint: shown once when nothing at all has been heard for quiet_after seconds (what
        to check on this kind of radio: its baud, PAN ID and channel)."""
        self.clock = clock
        self.log = log
        self.host_hash = host_hash
        self.silent_after = silent_after
        self.recent_s = recent_s
        self.quiet_hint = quiet_hint
        self.quiet_after = QUIET_HINT_S if quiet_after is None else quiet_after
        self.opened_at = clock()
        self.run_active = False
        """A START went out and no STOP since."""
        self.run_id = 0
        self.particles: dict[str, ParticleRow] = {}
        self.roster: set[int] | None = None if roster is None else set(roster)
        self.largest_group = 0
        """The most particles known to exist at once: together in an estimation round (the
        group size their STATUS reports) or heard together."""
        self.forgotten = 0
        """Particles removed by hand (forget): each lowers what the largest group asks for."""
        self.notes: deque[ModelNote] = deque(maxlen=500)
        self.notes_written = 0
        self.drops: dict[str, int] = {}
        self.packets = 0
        self.frames = 0
        self.sent = 0
        self.link: LinkEvent | None = None
        self.renames: list[Rename] = []
        """Renames seen and not yet taken by the owner (take_renames)."""
        self.set_ids: dict[int, tuple[int, float]] = {}
        """new id -> (old id, when SET_ID went out)"""
        self.on_param_value: Callable[[ParticleRow, ParamValue, float], None] = (
            lambda row, message, at: None
        )
        """Called with each PARAM_VALUE (the campaigns' queries take them)."""
        self.on_row_removed: Callable[[str], None] = lambda key: None
        """Called with the key of each row removed (campaigns stop waiting for it)."""
        for particle_id in sorted(self.roster or ()):
            self._add_row(str(particle_id), particle_id, None, self.opened_at, heard=False)

    # ---- what the session delivers ---------------------------------------------------------

    def on_frame(self, received: ReceivedFrame) -> None:
        frame = received.frame
        if frame.sender == BASE_STATION_ID:
            return  # another base station, or our own frame echoed
        source = None if received.source is None else str(received.source)
        self.frames += 1
        row = self._row_for(frame.sender, source, received.time)
        if not row.heard:  # a fleet particle heard for the first time
            row.first_heard = received.time
        row.last_heard = max(row.last_heard, received.time)
        row.frames += 1
        message = frame.message
        if isinstance(message, Status):
            self._on_status(row, message, received.time, frame.seq)
        elif isinstance(message, Intensity):
            row.intensity = message.intensity
        elif isinstance(message, ParamValue):
            row.params[message.param] = (message.result, message.value)
            self.on_param_value(row, message, received.time)
        self._count_heard(received.time)

    def on_link(self, event: LinkEvent) -> None:
        self.link = event
        level = "info" if event.state is LinkState.CONNECTED else "warning"
        if event.state is LinkState.CLOSED:
            level = "error" if "closed" not in event.message else "info"
        self.note(event.message, level, log=False)

    def _add_row(
        self, key: str, particle_id: int, source: str | None, at: float, *, heard: bool = True
    ) -> ParticleRow:
        row = ParticleRow(key, particle_id, source, at, at)
        if self.roster is not None:
            row.in_fleet = particle_id in self.roster
        self.particles[key] = row
        if not heard:
            return row
        if particle_id == UNASSIGNED_ID:
            self.note(
                f"A particle without an id answered (id {UNASSIGNED_ID}); give it one "
                f"with: setid {UNASSIGNED_ID} NEW_ID",
                "warning",
            )
        elif row.in_fleet is False:
            self.note(
                f"Particle {particle_id} is not in the fleet file: a particle of another "
                "fleet, or one flashed without it (particlebot flash --id records one)",
                "warning",
            )
        return row

    def _row_for(self, sender: int, source: str | None, at: float) -> ParticleRow:
        """The row a frame belongs to, made if needed; renames and duplicates are seen here."""
        if sender == UNASSIGNED_ID:
            # Unassigned particles all share one id; keep them apart by radio address.
            key = str(sender) if source is None else f"{sender}@{source}"
            row = self.particles.get(key)
            return row if row is not None else self._add_row(key, sender, source, at)
        if identifying(source):
            self._drop_renamed(sender, source, at)
        same_id = [row for row in self.particles.values() if row.id == sender]
        if sender in self.set_ids:
            self._drop_set_id_origin(sender, at)
        for row in same_id:
            if not identifying(source) or not identifying(row.source) or row.source == source:
                if row.source is None:
                    row.source = source
                return row
        key = str(sender) if not same_id else f"{sender}@{source}"
        row = self._add_row(key, sender, source, at)
        if same_id:
            radios = " and ".join(str(other.source) for other in [*same_id, row])
            why = f"radios {radios} both answer as particle {sender}"
            for other in [*same_id, row]:
                other.duplicate = why
                other.told_apart = True
            self._note_duplicate(sender, why)
        return row

    def _note_duplicate(self, particle_id: int, why: str) -> None:
        self.note(
            f"DUPLICATE id {particle_id}: {why}. Switch all but one off, then give it another "
            f"id (setid {particle_id} NEW_ID), switch the next one on, and so on",
            "error",
        )

    def _drop_renamed(self, sender: int, source: str | None, at: float) -> None:
        """A radio that answered as another id before now answers as sender: the particle was
        renamed (by this console, or by `flash` or another console): its old row goes."""
        for row in list(self.particles.values()):
            if row.source == source and row.id != sender:
                self._drop_row(row, sender, at)

    def _drop_set_id_origin(self, new_id: int, at: float) -> None:
        """The new id of a SET_ID sent from here answers (a transparent link shows no radio):
        the old id's row goes, unless it was heard after the SET_ID went out."""
        old_id, sent_at = self.set_ids.pop(new_id)
        if at - sent_at > RENAME_WINDOW_S:
            return
        for row in list(self.particles.values()):
            if row.id == old_id and row.last_heard <= sent_at + RENAME_SLACK_S:
                self._drop_row(row, new_id, at)

    def _drop_row(self, row: ParticleRow, new_id: int, at: float) -> None:
        del self.particles[row.key]
        if row.id != UNASSIGNED_ID:
            self.renames.append(Rename(row.id, new_id, row.source))
        if self.roster is not None and row.id in self.roster:
            # The same particle under its new id: the fleet's record follows it.
            self.roster.discard(row.id)
            self.roster.add(new_id)
            for other in self.particles.values():
                if other.id == new_id:
                    other.in_fleet = True
        self.note(
            f"Particle {row.id} now answers as {new_id}"
            + (f" (radio {row.source})" if row.source else "")
            + f": row {row.id} dropped"
        )
        self.on_row_removed(row.key)
        self._recheck_duplicates(row.id)

    def _recheck_duplicates(self, particle_id: int) -> None:
        """Clears the duplicate flag of an id left with one radio (the other was renamed)."""
        same = [row for row in self.particles.values() if row.id == particle_id]
        if len(same) == 1 and same[0].told_apart:
            same[0].duplicate = None
            same[0].told_apart = False

    def _count_heard(self, now: float) -> None:
        together = sum(
            1
            for row in self.particles.values()
            if row.heard and not row.silent(now, self.silent_after)
        )
        self.largest_group = max(self.largest_group, together)

    def _on_status(self, row: ParticleRow, status: Status, at: float, seq: int) -> None:
        first_mismatch = status.definition_hash != self.host_hash and (
            row.status is None or row.status.definition_hash == self.host_hash
        )
        previous = row.status
        # Particles without an id all answer as 254: nothing to tell apart there.
        if previous is not None and row.status_time is not None and row.id != UNASSIGNED_ID:
            why = two_clocks(previous, row.status_time, status, at)
            if why is None and row.status_seq is not None and not reset_between(previous, status):
                why = two_senders(row.status_seq, row.status_time, seq, at)
            if why is not None and not row.duplicate:
                row.duplicate = f"two particles answer as {row.id}: {why}"
                row.told_apart = False
                self._note_duplicate(row.id, row.duplicate)
            elif why is None and reset_between(previous, status):
                self._on_reset(row, previous, status)
        row.status = status
        row.status_time = at
        row.status_seq = seq
        row.intensity = status.intensity
        if status.state in RUN_STATES:
            self.largest_group = max(self.largest_group, status.group_size)
        if first_mismatch:
            self.note(
                f"Particle {row.id} runs firmware built from protocol "
                f"0x{status.definition_hash:08X}, this host from 0x{self.host_hash:08X}: reflash "
                "it (or update the host) before trusting its fields.",
                "warning",
            )

    def _on_reset(self, row: ParticleRow, before: Status, after: Status) -> None:
        cause = reset_cause(after.last_reset_cause)
        why = f"{cause}: {ADVICE[cause]}" if cause in ADVICE else cause
        if before.state in RUN_STATES or self.run_active:
            run = before.run_id if before.state in RUN_STATES else self.run_id
            row.reset_in_run = run
            self.note(
                f"Particle {row.id} reset during run {run} ({why}); it is "
                f"{state_name(after.state)} now, out of the run",
                "error",
            )
        else:
            self.note(f"Particle {row.id} reset ({why})", "warning")

    # ---- views -----------------------------------------------------------------------------

    def rows(self) -> list[ParticleRow]:
        return sorted(self.particles.values(), key=lambda row: (row.id, row.key))

    def heard_rows(self, at: float) -> list[ParticleRow]:
        """Particles that have reported a STATUS and are not silent."""
        return [
            row
            for row in self.rows()
            if row.status is not None and not row.silent(at, self.silent_after)
        ]

    def moving_ids(self) -> list[int]:
        """Ids of the particles whose latest STATUS shows them in a run (estimating, waiting,
        cycling or pausing), silent ones included: nothing says they stopped."""
        return sorted({row.id for row in self.particles.values() if row.moving})

    def ids_in_use(self, now: float) -> set[int]:
        """Ids the fleet lists or a particle answered with lately."""
        heard = {
            row.id
            for row in self.particles.values()
            if row.heard and now - row.last_heard <= self.recent_s
        }
        return heard | (self.roster or set())

    def present_keys(self, now: float) -> set[str]:
        """Particles that answer now: START waits for these."""
        return {
            row.key
            for row in self.particles.values()
            if row.heard and not row.silent(now, self.silent_after)
        }

    def expected_keys(self, now: float) -> set[str]:
        """Particles that must confirm a STOP: the fleet's and those heard lately."""
        return {
            row.key
            for row in self.particles.values()
            if (not row.heard and self.roster is not None and row.id in self.roster)
            or (row.heard and now - row.last_heard <= self.recent_s)
        }

    def new_notes(self) -> list[ModelNote]:
        """Notes added since the previous call (for a UI that appends them to a log pane)."""
        fresh_count = self.notes_written
        total = len(self.notes)
        count = min(fresh_count, total)
        self.notes_written = 0
        return list(self.notes)[total - count :]

    def take_renames(self) -> list[Rename]:
        renames, self.renames = self.renames, []
        return renames

    def counters_text(self) -> str:
        drops = self.drops
        bad = drops.get("bad_crc", 0) + drops.get("bad_length", 0) + drops.get("truncated", 0)
        return (
            f"frames {self.frames}  bad {bad} (crc {drops.get('bad_crc', 0)}, "
            f"len {drops.get('bad_length', 0)}, cut {drops.get('truncated', 0)})  "
            f"noise {drops.get('skipped', 0)}B  unknown "
            f"{drops.get('unknown_type', 0) + drops.get('bad_payload', 0)}  sent {self.sent}"
        )

    def required_count(self) -> int:
        """How many particles a STOP needs confirmed at least: the largest group seen, less the
        particles forgotten by hand. A weak floor: at 50 % loss particles under-report the
        group they estimated with (7-9 of 10 typically, some 0-5), and a base station that has
        just started has seen no group at all. What a STOP may claim rests on the grace period
        and on how long the base station has listened (see Campaigner.stop), not on this."""
        return max(0, self.largest_group - self.forgotten)

    def unconfirmed(self, campaign: Campaign) -> list[tuple[int, str]]:
        """(particle id, why it has not confirmed) for each particle the campaign waits for."""
        reasons: list[tuple[int, str]] = []
        for key in sorted(campaign.pending, key=lambda k: (self._id_of(k), k)):
            row = self.particles.get(key)
            if row is None:
                continue
            reasons.append((row.id, self._why_pending(campaign, row)))
        return reasons

    def _id_of(self, key: str) -> int:
        row = self.particles.get(key)
        return 256 if row is None else row.id

    def _why_pending(self, campaign: Campaign, row: ParticleRow) -> str:
        if not row.answers_for_itself:
            return f"duplicate id: {row.duplicate}; their answers cannot be told apart"
        if not row.heard:
            return "in the fleet, never heard in this session"
        if not fresh(row, campaign.started):
            ago = campaign.started - row.last_heard
            when = f"{ago:.0f} s before the command" if ago >= 0 else "only since"
            return f"no STATUS since the command (last heard {when})"
        if campaign.name == "START" and row.status is not None:
            return f"reports run {row.status.run_id}, not run {self.run_id}"
        return f"reports {state_name(row.status.state) if row.status else '?'}"

    # ---- what the person does to the rows ---------------------------------------------------

    def expect_rename(self, old_id: int, new_id: int, at: float) -> None:
        """A SET_ID went out: the new id answering soon is the same particle."""
        self.set_ids[new_id] = (old_id, at)

    def forget(self, particle_id: int) -> int:
        """Removes every row of this id (and takes it off this session's roster): a particle
        that is gone for good. Returns how many rows went; one heard again comes back."""
        removed = self.remove_rows(particle_id)
        if self.roster is not None:
            self.roster.discard(particle_id)
        if removed:
            self.note(
                f"Particle {particle_id} forgotten: no longer expected (it comes back if "
                "it is heard again)"
            )
        return removed

    def remove_rows(self, particle_id: int) -> int:
        keys = [row.key for row in self.particles.values() if row.id == particle_id]
        for key in keys:
            del self.particles[key]
            self.on_row_removed(key)
        if keys:
            self.forgotten += 1
        return len(keys)

    def check_quiet(self, at: float) -> None:
        """Shows the quiet hint once, when nothing at all has been heard for quiet_after."""
        quiet = self.packets == 0 and at - self.opened_at >= self.quiet_after
        if self.quiet_hint is not None and quiet:
            hint = f"Nothing heard for {self.quiet_after:g} s. {self.quiet_hint}"
            self.note(hint, "warning")
            self.quiet_hint = None

    def note(self, text: str, level: str = "info", *, log: bool = True) -> None:
        """Shows text to the person (and writes it to the log)."""
        self.notes.append(ModelNote(self.clock(), text, level))
        self.notes_written += 1
        if log and self.log is not None:
            self.log(text)
