"""What the base station knows of the swarm, and the commands it repeats until confirmed (no UI):
a thin facade that owns the lock over the swarm model and the command campaigns.

The session's receive thread delivers frames (on_frame, ...) while the caller's thread (the
console's timer, a script) reads views, gives commands and polls: every call takes one lock.
The work is done by SwarmModel (particlebot.swarm.model: rows, roster, flags, notes) and
Campaigner (particlebot.swarm.campaigner: START, STOP, SERVO_HOLD, SET/GET and their retries).
"""

from __future__ import annotations

import threading
from collections import deque
from collections.abc import Callable, Iterable

from particlebot.protocol import BROADCAST_ID, DEFINITION_HASH, Method
from particlebot.radio import LinkEvent, Packet
from particlebot.session import Dropped, Listener, ReceivedFrame, SentFrame
from particlebot.swarm.campaigner import (
    DISCOVERY_PING_S,
    MAX_PINGS,
    PARAM_ATTEMPTS,
    PARAM_REPLY_TIMEOUT_S,
    PARAM_RETRY_S,
    SERVO_HOLD_TIMEOUT_S,
    STOP_AFTER_GRACE_S,
    STOP_BURST_S,
    STOP_GRACE_S,
    STOP_TIMEOUT_S,
    Campaigner,
    CommandSink,
)
from particlebot.swarm.campaigns import Campaign, ParamQuery
from particlebot.swarm.model import (
    QUIET_HINT_S,
    RENAME_SLACK_S,
    RENAME_WINDOW_S,
    IdInUseError,
    ModelNote,
    Rename,
    SwarmModel,
    identifying,
)
from particlebot.swarm.roster import RECENT_S, SILENT_AFTER_S, ParticleRow

__all__ = [
    "DISCOVERY_PING_S",
    "MAX_PINGS",
    "PARAM_ATTEMPTS",
    "PARAM_REPLY_TIMEOUT_S",
    "PARAM_RETRY_S",
    "QUIET_HINT_S",
    "RENAME_SLACK_S",
    "RENAME_WINDOW_S",
    "SERVO_HOLD_TIMEOUT_S",
    "STOP_AFTER_GRACE_S",
    "STOP_BURST_S",
    "STOP_GRACE_S",
    "STOP_TIMEOUT_S",
    "Campaign",
    "CommandSink",
    "IdInUseError",
    "ModelNote",
    "Rename",
    "SwarmTracker",
    "identifying",
]


class SwarmTracker(Listener):
    """Per-particle state from the frames a session delivers, and the commands given to them.

    roster: the particle ids of the fleet file, or None without one. Every roster particle is
    expected to confirm a STOP (shown as NOT HEARD until it answers); without a roster, every
    particle heard in the last recent_s is, and never fewer than the largest group seen.
    """

    def __init__(
        self,
        sink: CommandSink | None,
        clock: Callable[[], float],
        *,
        roster: Iterable[int] | None = None,
        host_hash: int = DEFINITION_HASH,
        silent_after: float = SILENT_AFTER_S,
        recent_s: float = RECENT_S,
        stop_burst: tuple[float, ...] = STOP_BURST_S,
        stop_interval: float = 0.5,
        stop_timeout: float = STOP_TIMEOUT_S,
        stop_grace: float = 0.0,
        listen_s: float = 0.0,
        start_interval: float = 0.5,
        start_timeout: float = 8.0,
        max_pings: int = MAX_PINGS,
        param_timeout: float = PARAM_REPLY_TIMEOUT_S,
        param_attempts: int = PARAM_ATTEMPTS,
        param_retry: float = PARAM_RETRY_S,
        quiet_hint: str | None = None,
        quiet_after: float | None = None,
    ) -> None:
        """stop_grace: how long after it starts STOP is held open (see STOP_GRACE_S; 0 for a
        tracker that takes over a known swarm, as tests do). listen_s: how long it must have
        listened to call a STOP confirmed without a fleet roster (0: the caller knows the
        swarm; Swarm gives STOP_GRACE_S). quiet_hint: shown once when nothing at all has been
        heard for quiet_after seconds (what to check on this kind of radio: its baud, PAN ID
        and channel)."""
        self.sink = sink
        self._model = SwarmModel(
            clock,
            None if sink is None else sink.note,
            roster=roster,
            host_hash=host_hash,
            silent_after=silent_after,
            recent_s=recent_s,
            quiet_hint=quiet_hint,
            quiet_after=quiet_after,
        )
        self._campaigns = Campaigner(
            self._model,
            sink,
            stop_burst=stop_burst,
            stop_interval=stop_interval,
            stop_timeout=stop_timeout,
            stop_grace=stop_grace,
            listen_s=listen_s,
            start_interval=start_interval,
            start_timeout=start_timeout,
            max_pings=max_pings,
            param_timeout=param_timeout,
            param_attempts=param_attempts,
            param_retry=param_retry,
        )
        self._lock = threading.RLock()

    # ---- what the session delivers (its receive thread) -------------------------------------

    def on_packet(self, packet: Packet) -> None:
        with self._lock:
            self._model.packets += 1

    def on_frame(self, received: ReceivedFrame) -> None:
        with self._lock:
            self._model.on_frame(received)
        # Campaigns advance in poll(), on the caller's thread: commands never go out from the
        # receive thread, which must keep reading the radio.

    def on_dropped(self, dropped: Dropped) -> None:
        with self._lock:
            reason = dropped.event.reason.value
            self._model.drops[reason] = self._model.drops.get(reason, 0) + 1

    def on_sent(self, sent: SentFrame) -> None:
        with self._lock:
            self._model.sent += 1

    def on_link(self, event: LinkEvent) -> None:
        with self._lock:
            self._model.on_link(event)

    # ---- state (read it under no lock only where a stale value does no harm) -----------------

    @property
    def clock(self) -> Callable[[], float]:
        return self._model.clock

    @property
    def particles(self) -> dict[str, ParticleRow]:
        return self._model.particles

    @property
    def roster(self) -> set[int] | None:
        return self._model.roster

    @property
    def largest_group(self) -> int:
        return self._model.largest_group

    @property
    def run_id(self) -> int:
        return self._model.run_id

    @property
    def run_active(self) -> bool:
        """A START went out and no STOP since."""
        return self._model.run_active

    @property
    def host_hash(self) -> int:
        return self._model.host_hash

    @property
    def silent_after(self) -> float:
        return self._model.silent_after

    @property
    def quiet_hint(self) -> str | None:
        return self._model.quiet_hint

    @property
    def link(self) -> LinkEvent | None:
        return self._model.link

    @property
    def drops(self) -> dict[str, int]:
        return self._model.drops

    @property
    def notes(self) -> deque[ModelNote]:
        return self._model.notes

    @property
    def opened_at(self) -> float:
        return self._model.opened_at

    @property
    def grace_until(self) -> float:
        return self._campaigns.grace_until

    @property
    def campaigns(self) -> list[Campaign]:
        return self._campaigns.campaigns

    @property
    def queries(self) -> list[ParamQuery]:
        return self._campaigns.queries

    @property
    def stop_timeout(self) -> float:
        return self._campaigns.stop_timeout

    @property
    def start_timeout(self) -> float:
        return self._campaigns.start_timeout

    @property
    def param_timeout(self) -> float:
        return self._campaigns.param_timeout

    @property
    def param_attempts(self) -> int:
        return self._campaigns.param_attempts

    @property
    def param_retry(self) -> float:
        return self._campaigns.param_retry

    # ---- views -----------------------------------------------------------------------------

    def rows(self) -> list[ParticleRow]:
        with self._lock:
            return self._model.rows()

    def heard_rows(self, now: float | None = None) -> list[ParticleRow]:
        """Particles that have reported a STATUS and are not silent."""
        at = self.clock() if now is None else now
        with self._lock:
            return self._model.heard_rows(at)

    def moving_ids(self) -> list[int]:
        """Ids of the particles whose latest STATUS shows them in a run (estimating, waiting,
        cycling or pausing), silent ones included: nothing says they stopped."""
        with self._lock:
            return self._model.moving_ids()

    def ids_in_use(self) -> set[int]:
        """Ids the fleet lists or a particle answered with lately."""
        now = self.clock()
        with self._lock:
            return self._model.ids_in_use(now)

    def new_notes(self) -> list[ModelNote]:
        """Notes added since the previous call (for a UI that appends them to a log pane)."""
        with self._lock:
            return self._model.new_notes()

    def take_renames(self) -> list[Rename]:
        with self._lock:
            return self._model.take_renames()

    def last(self, name: str) -> Campaign | None:
        with self._lock:
            return self._campaigns.last(name)

    def counters_text(self) -> str:
        with self._lock:
            return self._model.counters_text()

    def required_count(self) -> int:
        """How many particles a STOP needs confirmed at least (SwarmModel.required_count)."""
        with self._lock:
            return self._model.required_count()

    def unconfirmed(self, campaign: Campaign) -> list[tuple[int, str]]:
        """(particle id, why it has not confirmed) for each particle the campaign waits for."""
        with self._lock:
            return self._model.unconfirmed(campaign)

    # ---- commands --------------------------------------------------------------------------

    def start(
        self,
        method: Method,
        *,
        cycle_steps: int = 0,
        wave_size: int = 0,
        update_interval_s: int = 0,
        phototaxis: bool = False,
    ) -> Campaign:
        with self._lock:
            return self._campaigns.start(
                method,
                cycle_steps=cycle_steps,
                wave_size=wave_size,
                update_interval_s=update_interval_s,
                phototaxis=phototaxis,
            )

    def stop(self) -> Campaign:
        """STOP until every expected particle confirms it (see Campaigner.stop)."""
        with self._lock:
            return self._campaigns.stop()

    def servo_hold(self, target: int, pulse_us: int, hold_s: int) -> Campaign:
        """SERVO_HOLD to one particle until its STATUS shows it done (Campaigner.servo_hold)."""
        with self._lock:
            return self._campaigns.servo_hold(target, pulse_us, hold_s)

    def set_param(
        self, param: int, value: int, target: int = BROADCAST_ID, *, attempts: int | None = None
    ) -> ParamQuery:
        """Sends SET_PARAM; the answers are summarised in one note (see ParamQuery)."""
        with self._lock:
            return self._campaigns.set_param(param, value, target, attempts=attempts)

    def get_param(
        self, param: int, target: int = BROADCAST_ID, *, attempts: int | None = None
    ) -> ParamQuery:
        """Sends GET_PARAM; the answers are summarised in one note (see ParamQuery)."""
        with self._lock:
            return self._campaigns.get_param(param, target, attempts=attempts)

    def identify(self, target: int = BROADCAST_ID) -> None:
        with self._lock:
            self._campaigns.identify(target)

    def set_id(self, target: int, new_id: int, *, force: bool = False) -> None:
        """Sends SET_ID; IdInUseError if new_id is the fleet's or a particle's heard lately
        (force: the other one is gone, or is being renamed too)."""
        with self._lock:
            self._campaigns.set_id(target, new_id, force=force)

    def forget(self, particle_id: int) -> int:
        """Removes every row of this id (and takes it off this session's roster): a particle
        that is gone for good. Returns how many rows went; one heard again comes back."""
        with self._lock:
            return self._model.forget(particle_id)

    def ping(self, target: int = BROADCAST_ID) -> None:
        with self._lock:
            self._campaigns.ping(target)

    def note(self, text: str, level: str = "info") -> None:
        """Shows text to the person (and writes it to the log)."""
        with self._lock:
            self._model.note(text, level)

    def poll(self, now: float | None = None) -> None:
        """Advances campaigns: confirmations, resends, timeouts. Call a few times a second."""
        at = self.clock() if now is None else now
        with self._lock:
            self._campaigns.poll(at)
            self._model.check_quiet(at)
