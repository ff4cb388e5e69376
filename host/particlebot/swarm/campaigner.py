"""The commands the base station repeats until particles confirm them: START, STOP, SERVO_HOLD,
and SET_PARAM / GET_PARAM with their retries."""

from __future__ import annotations

from typing import Protocol

from particlebot.protocol import (
    BROADCAST_ID,
    UNASSIGNED_ID,
    GetParam,
    Identify,
    Message,
    Method,
    ParamResult,
    ParamValue,
    Ping,
    ServoHold,
    SetId,
    SetParam,
    Start,
    State,
    Stop,
)
from particlebot.radio import RadioError, ReadOnlyRadioError
from particlebot.swarm.campaigns import (
    CLOCK_SLACK_S,
    Campaign,
    ParamQuery,
    Verdict,
    ids_text,
    param_name,
    result_text,
)
from particlebot.swarm.model import IdInUseError, SwarmModel, fresh
from particlebot.swarm.roster import OBEYED_STOP_STATES, STOPPED_STATES, ParticleRow

# A particle answers a broadcast SET_PARAM or GET_PARAM in a random one of 10 slots of 60 ms;
# its PARAM_VALUE (15 bytes) then queues behind the others' on the base station's 9600-baud
# link. Two seconds leave room for that and for a radio that repeats a packet.
PARAM_REPLY_TIMEOUT_S = 2.0
PARAM_ATTEMPTS = 10
"""A particle that has not answered a SET or GET is asked again by id, up to nine times."""
PARAM_RETRY_S = 0.5
"""A particle asked by id answers at once (no reply slot): its answer is in within 0.1 s."""
# The firmware's stop ramp lasts at most 600 ms, so a particle must have STOP within ~0.35 s of
# the command for its servo to be contracted within 1 s. Four copies 0.1 s apart reach a
# particle unless all four are lost: 0.16 % of the time at 20 % loss. A copy that reaches a
# particle already STOPPING or IDLE changes nothing (Coordinator::stop in the firmware).
STOP_BURST_S = (0.0, 0.1, 0.2, 0.3)
STOP_TIMEOUT_S = 10.0
# A base station that has just started knows nobody: particles it has not heard yet may be
# moving. For this long after it starts, STOP keeps going out (every stop_interval) and asks
# every particle to answer (a broadcast PING every DISCOVERY_PING_S), whatever it has heard, and
# is never called confirmed before it ends. At 50 % loss a particle then stays unheard with a
# chance of about 1 in 500 (five STATUS reports and ten PINGs, each a quarter to a half likely
# to come through). The grace period does this work, not the largest group seen: at 50 % loss
# particles under-report the group they estimated with (SwarmModel.required_count).
STOP_GRACE_S = 10.0
STOP_AFTER_GRACE_S = 5.0
"""Time left to confirm a STOP given during the grace period, once it is over."""
DISCOVERY_PING_S = 1.0
# PINGs per round: their STATUS replies (52 bytes each) arrive together and queue in the base
# radio's serial buffer, which 9600 baud drains at one reply per ~55 ms.
MAX_PINGS = 4
SERVO_HOLD_TIMEOUT_S = 3.0
"""A SERVO_HOLD sent by id is answered at once with a STATUS; resent every 0.3 s meanwhile."""


class CommandSink(Protocol):
    """Where the tracker's commands go: a Session, or a fake in tests."""

    def send(self, message: Message) -> object: ...

    def note(self, text: str) -> None: ...


class Campaigner:
    """Sends commands and follows each until it is confirmed, fails or is superseded, judging
    the particles' answers in the SwarmModel. Not thread-safe: SwarmTracker holds its lock
    around every call."""

    def __init__(
        self,
        model: SwarmModel,
        sink: CommandSink | None,
        *,
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
    ) -> None:
        """stop_grace: see STOP_GRACE_S. listen_s: how long the base station must have listened
        (before a STOP, or through its grace period) to vouch that no particle it has not heard
        is moving; without a fleet roster, a STOP given sooner ends UNCONFIRMED at best."""
        if not stop_burst or stop_burst[0] != 0.0 or list(stop_burst) != sorted(stop_burst):
            raise ValueError("stop_burst: offsets in seconds, the first 0, in order")
        self.model = model
        self.sink = sink
        self.clock = model.clock
        self.stop_burst = stop_burst
        self.stop_interval = stop_interval
        self.stop_timeout = stop_timeout
        self.grace_until = model.opened_at + stop_grace
        self.listen_s = listen_s
        self.start_interval = start_interval
        self.start_timeout = start_timeout
        self.max_pings = max_pings
        self.param_timeout = param_timeout
        self.param_attempts = param_attempts
        self.param_retry = param_retry
        self.queries: list[ParamQuery] = []
        self.campaigns: list[Campaign] = []
        model.on_param_value = self.on_param_value
        model.on_row_removed = self.drop_key

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
        model = self.model
        self._cancel("STOP")
        self._cancel("START")
        model.run_active = True
        for row in model.particles.values():
            row.reset_in_run = None
        reported = [row.status.run_id for row in model.particles.values() if row.status]
        model.run_id = (max([model.run_id, *reported]) % 255) + 1
        message = Start(
            run_id=model.run_id,
            method=int(method),
            cycle_steps=cycle_steps,
            wave_size=wave_size,
            update_interval_s=update_interval_s,
            phototaxis=int(phototaxis),
        )
        run_id = model.run_id

        def confirms(key: str, since: float) -> bool:
            row = model.particles.get(key)
            return (
                row is not None
                and row.answers_for_itself
                and fresh(row, since)
                and row.status is not None
                and row.status.run_id == run_id
            )

        def needs_command(key: str, since: float) -> bool:
            # It answered but is in another run: it missed START. The copy carries the same
            # run_id, so particles already in the run ignore it.
            row = model.particles.get(key)
            return (
                row is not None
                and fresh(row, since)
                and row.status is not None
                and row.status.run_id != run_id
            )

        now = self.clock()
        return self._launch(
            Campaign(
                name="START",
                command=message,
                started=now,
                burst=(0.0,),
                interval=self.start_interval,
                deadline=now + self.start_timeout,
                pending=model.present_keys(now),
                confirms=confirms,
                needs_command=needs_command,
            )
        )

    def stop(self) -> Campaign:
        """STOP as a burst (stop_burst), then PINGs until every expected particle reports IDLE
        or DONE, or stop_timeout passes. STOP is repeated after the burst only while some
        particle has not answered STOPPING, IDLE or DONE since, and throughout the grace period
        after the base station started.

        It ends CONFIRMED only when the base station knows the swarm: a fleet roster, or
        listen_s of listening before the STOP or through the grace period. A STOP just after
        a restart with no grace period ends UNCONFIRMED even when every particle heard
        confirms it: one not heard yet may still be moving, and the largest group seen is no
        proof of the contrary (see SwarmModel.required_count)."""
        model = self.model
        self._cancel("START")
        self._cancel("STOP")
        model.run_active = False

        def confirms(key: str, since: float) -> bool:
            row = model.particles.get(key)
            return (
                row is not None
                and row.answers_for_itself
                and fresh(row, since)
                and row.state in STOPPED_STATES
            )

        def needs_command(key: str, since: float) -> bool:
            row = model.particles.get(key)
            return row is None or not (fresh(row, since) and row.state in OBEYED_STOP_STATES)

        now = self.clock()
        deadline = now + self.stop_timeout
        if self.grace_until > now:
            deadline = max(deadline, self.grace_until + STOP_AFTER_GRACE_S)
        listened = now - model.opened_at
        knows_swarm = (
            model.roster is not None
            or listened >= self.listen_s
            or self.grace_until - model.opened_at >= self.listen_s
        )
        return self._launch(
            Campaign(
                name="STOP",
                command=Stop(),
                started=now,
                burst=self.stop_burst,
                interval=self.stop_interval,
                deadline=deadline,
                pending=model.expected_keys(now),
                confirms=confirms,
                needs_command=needs_command,
                required=model.required_count,
                hold_until=self.grace_until,
                known=lambda: knows_swarm,
            )
        )

    def servo_hold(self, target: int, pulse_us: int, hold_s: int) -> Campaign:
        """SERVO_HOLD to one particle until its STATUS shows it holding pulse_us (hold_s > 0)
        or no longer holding (hold_s = 0), or SERVO_HOLD_TIMEOUT_S pass. A particle that is
        running answers with its unchanged state: the campaign fails, saying which."""
        model = self.model
        self._cancel("SERVO_HOLD")

        def confirms(key: str, since: float) -> bool:
            row = model.particles.get(key)
            if row is None or not fresh(row, since) or row.status is None:
                return False
            holding = row.status.state == State.HOLDING
            if hold_s == 0:
                return not holding
            return holding and row.status.servo_pulse_us == pulse_us

        def needs_command(key: str, since: float) -> bool:
            return not confirms(key, since)

        now = self.clock()
        return self._launch(
            Campaign(
                name="SERVO_HOLD",
                command=ServoHold(target=target, pulse_us=pulse_us, hold_s=hold_s),
                started=now,
                burst=(0.0,),
                interval=0.3,
                deadline=now + SERVO_HOLD_TIMEOUT_S,
                pending={
                    row.key for row in model.particles.values() if row.id == target and row.heard
                },
                confirms=confirms,
                needs_command=needs_command,
                join_new=False,
            )
        )

    def set_param(
        self, param: int, value: int, target: int = BROADCAST_ID, *, attempts: int | None = None
    ) -> ParamQuery:
        """Sends SET_PARAM; the answers are summarised in one note (see ParamQuery)."""
        message = SetParam(target=target, param=param, value=value)
        return self._query("SET", message, value, attempts)

    def get_param(
        self, param: int, target: int = BROADCAST_ID, *, attempts: int | None = None
    ) -> ParamQuery:
        """Sends GET_PARAM; the answers are summarised in one note (see ParamQuery)."""
        return self._query("GET", GetParam(target=target, param=param), None, attempts)

    def _query(
        self, kind: str, message: SetParam | GetParam, value: int | None, attempts: int | None
    ) -> ParamQuery:
        now = self.clock()
        if message.target == BROADCAST_ID:
            expected = {row.id for row in self.model.heard_rows(now) if row.id != UNASSIGNED_ID}
        else:
            expected = {message.target}
        query = ParamQuery(
            kind,
            message.param,
            value,
            message.target,
            now,
            expected,
            attempts=self.param_attempts if attempts is None else attempts,
            first_wait=self.param_timeout,
            retry_after=self.param_retry,
            last_asked=now,
        )
        if self.send(message):
            self.queries = [*(q for q in self.queries if not q.done), query]
        else:
            query.done = True
            query.finished_at = now
        return query

    def identify(self, target: int = BROADCAST_ID) -> None:
        self.send(Identify(target=target))

    def ping(self, target: int = BROADCAST_ID) -> None:
        self.send(Ping(target=target))

    def set_id(self, target: int, new_id: int, *, force: bool = False) -> None:
        """Sends SET_ID; IdInUseError if new_id is the fleet's or a particle's heard lately
        (force: the other one is gone, or is being renamed too)."""
        model = self.model
        if not force and new_id in model.ids_in_use(self.clock()) and new_id != target:
            where = "the fleet lists it" if new_id in (model.roster or ()) else "it answers"
            raise IdInUseError(
                f"id {new_id} is in use ({where}); two particles with one id cannot be told "
                f"apart. Choose a free id, or force it (setid {target} {new_id} force) if "
                f"particle {new_id} is gone"
            )
        if force and new_id != target and model.remove_rows(new_id):
            model.note(f"Particle {new_id}'s row dropped: SET_ID gives its id to another")
        if self.send(SetId(target=target, new_id=new_id)):
            model.expect_rename(target, new_id, self.clock())

    def last(self, name: str) -> Campaign | None:
        for campaign in reversed(self.campaigns):
            if campaign.name == name:
                return campaign
        return None

    # ---- answers and time ------------------------------------------------------------------

    def on_param_value(self, row: ParticleRow, message: ParamValue, at: float) -> None:
        for query in reversed(self.queries):
            if query.accepts(row.id, message.param):
                query.replies[row.id] = (message.result, message.value)
                # With no particle known when it went out, only the timeout ends a broadcast.
                everyone = bool(query.expected) and query.expected <= set(query.replies)
                if query.target != BROADCAST_ID or everyone:
                    self._conclude_query(query, at)
                return
        # Nobody here asked (another console, a late answer): one line of its own.
        self.model.note(_param_text(row.id, message))

    def drop_key(self, key: str) -> None:
        """A row went (renamed, forgotten): no campaign waits for it any longer."""
        for campaign in self.campaigns:
            campaign.pending.discard(key)
            campaign.confirmed.discard(key)

    def poll(self, at: float) -> None:
        """Advances campaigns: confirmations, resends, timeouts."""
        for campaign in self.campaigns:
            if not campaign.done:
                self._advance(campaign, at)
        for query in self.queries:
            if not query.done and at >= query.next_ask - CLOCK_SLACK_S:
                self._retry_query(query, at)

    # ---- internals -------------------------------------------------------------------------

    def _conclude_query(self, query: ParamQuery, now: float) -> None:
        query.done = True
        query.finished_at = now
        if query.target != BROADCAST_ID and query.replies:
            result, value = query.replies[query.target]
            name = param_name(query.param)
            if query.kind == "SET" and result != ParamResult.OK:
                text = (
                    f"Particle {query.target}: SET {name} = {query.value} refused, "
                    f"{result_text(result)}; it stays {value}"
                )
            else:
                text = f"Particle {query.target}: {name} = {value} ({result_text(result)})"
            self.model.note(text, "info" if result == ParamResult.OK else "warning")
            return
        everyone_ok = query.replies and all(
            result == ParamResult.OK for result, _ in query.replies.values()
        )
        complete = query.expected <= set(query.replies)
        level = "info" if everyone_ok and complete else "warning"
        self.model.note(query.summary(round(now - query.started, 1)), level)

    def _retry_query(self, query: ParamQuery, now: float) -> None:
        """Asks each particle that has not answered again, by id; concludes after the last try."""
        missing = query.missing
        if query.asked >= query.attempts or not missing:
            self._conclude_query(query, now)
            return
        query.asked += 1
        query.last_asked = now
        for particle in missing:
            if query.kind == "SET" and query.value is not None:
                message: Message = SetParam(target=particle, param=query.param, value=query.value)
            else:
                message = GetParam(target=particle, param=query.param)
            if not self.send(message):
                self._conclude_query(query, now)
                return

    def _launch(self, campaign: Campaign) -> Campaign:
        campaign.next_send = campaign.started
        self.campaigns = [*self.campaigns[-7:], campaign]
        self._advance(campaign, campaign.started)
        return campaign

    def _cancel(self, name: str) -> None:
        for campaign in self.campaigns:
            if campaign.name == name and not campaign.done:
                campaign.done = True
                campaign.verdict = Verdict.SUPERSEDED
                campaign.outcome = f"{name} superseded"

    def _advance(self, campaign: Campaign, now: float) -> None:
        particles = self.model.particles
        if campaign.join_new:
            for row in particles.values():
                new = row.heard and row.first_heard > campaign.started
                if new and row.key not in campaign.confirmed:
                    campaign.pending.add(row.key)
        # Judged on each particle's latest STATUS: one that confirmed can fall back. The
        # firmware ignores STOP when STOPPING or IDLE, but a DONE particle that a later copy
        # reaches ramps down again (STOPPING for a moment), and a particle that resets or that
        # another console starts leaves IDLE.
        for key in campaign.pending | campaign.confirmed:
            if key not in particles:
                campaign.pending.discard(key)
                campaign.confirmed.discard(key)
            elif campaign.confirms(key, campaign.started):
                campaign.pending.discard(key)
                campaign.confirmed.add(key)
            else:
                campaign.confirmed.discard(key)
                campaign.pending.add(key)
        # The whole burst goes out even when every known particle has confirmed: particles the
        # base station has not heard of yet have no other chance of getting the command.
        settled = (
            campaign.burst_sent
            and not campaign.pending
            and now >= campaign.hold_until - CLOCK_SLACK_S
            and len(campaign.confirmed) >= campaign.required()
        )
        if now >= campaign.deadline - CLOCK_SLACK_S or settled:
            self._conclude(campaign, now)
        elif now >= campaign.next_send - CLOCK_SLACK_S:
            self._send_round(campaign, now)

    def _conclude(self, campaign: Campaign, now: float) -> None:
        elapsed = now - campaign.started
        required = campaign.required()
        confirmed = len(campaign.confirmed)
        if campaign.pending:
            missing = [self.model.particles[key] for key in campaign.pending]
            shortfall = ""
            if required > confirmed + len(missing):
                shortfall = (
                    f"; {required} were seen together, so "
                    f"{required - confirmed - len(missing)} more never answered"
                )
            self._finish(
                campaign,
                now,
                Verdict.FAILED,
                f"{campaign.name} not confirmed within {campaign.timeout:.0f} s by "
                f"particle(s) {ids_text([row.id for row in missing])} ({confirmed} confirmed"
                f"{shortfall}); check they are switched on and in range, then try again",
            )
        elif confirmed < required:
            self._finish(
                campaign,
                now,
                Verdict.FAILED,
                f"{campaign.name} not confirmed within {campaign.timeout:.0f} s: {confirmed} "
                f"particle(s) confirmed, but {required} were seen together; "
                f"{required - confirmed} never answered (forget ID drops one that is gone)",
            )
        elif not campaign.confirmed:
            # Silence is no answer: with nobody known to obey, nothing says anyone did.
            self._finish(
                campaign, now, Verdict.UNCONFIRMED, f"{campaign.name} sent; nobody confirmed it"
            )
        elif not campaign.known():
            listened = campaign.started - self.model.opened_at
            self._finish(
                campaign,
                now,
                Verdict.UNCONFIRMED,
                f"{campaign.name} confirmed by the {confirmed} particle(s) heard, but the base "
                f"station had listened for only {listened:.1f} s before it: one it has not "
                "heard may still be moving (send it again in a while, or open with the fleet "
                "file)",
            )
        else:
            self._finish(
                campaign,
                now,
                Verdict.CONFIRMED,
                f"{campaign.name} confirmed by all {confirmed} particles in {elapsed:.1f} s",
            )

    def _send_round(self, campaign: Campaign, now: float) -> None:
        index = campaign.rounds
        campaign.rounds += 1
        if campaign.rounds < len(campaign.burst):
            # Offsets from the start, not from this round: a late poll does not delay the rest.
            campaign.next_send = campaign.started + campaign.burst[campaign.rounds]
        else:
            campaign.next_send = now + campaign.interval
        in_burst = index < len(campaign.burst)
        holding = now < campaign.hold_until
        wanted = (
            in_burst
            or holding
            or any(campaign.needs_command(key, campaign.started) for key in campaign.pending)
        )
        if wanted and not self.send(campaign.command, campaign):
            return
        if campaign.burst_sent:
            if holding and now - campaign.last_broadcast_ping >= DISCOVERY_PING_S - CLOCK_SLACK_S:
                campaign.last_broadcast_ping = now
                if not self.send(Ping(target=BROADCAST_ID), campaign):
                    return
            for target in self._ping_targets(campaign):
                if not self.send(Ping(target=target), campaign):
                    return

    def _ping_targets(self, campaign: Campaign) -> list[int]:
        """Ids to PING this round: the pending particles pinged least so far, at most
        max_pings. Unassigned particles share id 254, so one PING asks all of them."""
        particles = self.model.particles
        order = sorted(
            campaign.pending,
            key=lambda key: (campaign.pings.get(key, 0), particles[key].id, key),
        )
        targets: list[int] = []
        for key in order:
            particle_id = particles[key].id
            if particle_id not in targets:
                if len(targets) >= self.max_pings:
                    continue
                targets.append(particle_id)
            campaign.pings[key] = campaign.pings.get(key, 0) + 1
        return targets

    def _finish(
        self, campaign: Campaign, now: float, verdict: Verdict, text: str, *, log: bool = True
    ) -> None:
        campaign.done = True
        campaign.verdict = verdict
        campaign.outcome = text
        campaign.finished_at = now
        if log:
            level = {Verdict.CONFIRMED: "info", Verdict.UNCONFIRMED: "warning"}.get(
                verdict, "error"
            )
            self.model.note(text, level)

    def send(self, message: Message, campaign: Campaign | None = None) -> bool:
        """Sends message; a failure is noted once per campaign (not once per resend), and ends
        the campaign when the radio can never send (a replay)."""
        if self.sink is None:
            error: RadioError = ReadOnlyRadioError("Nothing can be sent: no radio")
        else:
            try:
                self.sink.send(message)
                return True
            except RadioError as exc:
                error = exc
        name = type(message).__name__.upper()
        if campaign is None or not campaign.send_failures:
            self.model.note(f"Could not send {name}: {error}", "error", log=False)
        if campaign is not None:
            campaign.send_failures += 1
            if isinstance(error, ReadOnlyRadioError):
                self._finish(
                    campaign, self.clock(), Verdict.FAILED, f"{campaign.name} not sent", log=False
                )
        return False


def _param_text(particle: int, message: ParamValue) -> str:
    result = result_text(message.result)
    return f"Particle {particle}: {param_name(message.param)} = {message.value} ({result})"
