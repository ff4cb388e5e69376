"""particlebot.Swarm: a swarm driven from Python (scripts, the console, demo, `particlebot run`)."""

from __future__ import annotations

import contextlib
import dataclasses
import math
import signal
import threading
from collections.abc import Callable, Collection, Iterator
from pathlib import Path
from types import FrameType, TracebackType
from typing import TYPE_CHECKING, Self

from particlebot.fleet import Fleet, FleetError, FleetFileError, load_fleet, updating_fleet
from particlebot.logs.jsonl import JsonlWriter, default_log_path
from particlebot.protocol import (
    BROADCAST_ID,
    PARAM_SPECS,
    UNASSIGNED_ID,
    Method,
    Param,
    ParamResult,
    State,
    Status,
)
from particlebot.radio import Radio, RadioError, ReadOnlyRadioError, open_radio, parse_radio_url
from particlebot.session import Listener, ReceivedFrame, Session
from particlebot.swarm.campaigns import CLOCK_SLACK_S, Campaign, ParamQuery, Verdict, ids_text
from particlebot.swarm.results import (
    IdInUse,
    NotConfirmed,
    ParamReport,
    Particle,
    ParticlesMissing,
    Reply,
    Run,
    StopReport,
    SwarmError,
    Unconfirmed,
    not_confirmed_text,
)
from particlebot.swarm.tracker import STOP_GRACE_S, IdInUseError, Rename, SwarmTracker

if TYPE_CHECKING:
    from particlebot.radio.simulated import SwarmRadio

POLL_S = 0.05
"""How often campaigns advance: a STOP copy goes out at most this late (the burst's copies are
0.1 s apart). On a simulation stepped by its caller, the step between two polls."""
WAIT_PING_S = 1.0
"""wait_for() asks every particle for a STATUS this often, rather than waiting 2 s for each."""
SET_ID_TIMEOUT_S = 5.0
SAMPLE_PING_S = 0.3
"""sample() asks the particles still short of STATUS reports this often, a few at a time: four
replies (52 bytes each) fill about 0.22 s of a 9600-baud link."""
SAMPLE_PINGS = 4
SERVO_PULSES = range(PARAM_SPECS[Param.SERVO_CAL_0].min, PARAM_SPECS[Param.SERVO_CAL_0].max + 1)
"""Pulses a servo may be held at: the servo table's range (the firmware's 500..2500 us)."""
SIMULATED_SCHEMES = ("virtual", "emulated")

METHODS: dict[str, Method] = {
    "a": Method.DIRECT,
    "b": Method.LINEAR,
    "c": Method.NONLINEAR,
    "d": Method.COUNTING,
    **{method.name.lower(): method for method in Method},
}


def method_of(method: str | Method) -> Method:
    """A method from its letter (A-D) or name (counting), any case, or the enum itself."""
    if isinstance(method, Method):
        return method
    found = METHODS.get(str(method).strip().lower())
    if found is None:
        raise ValueError(f"method '{method}' is not A, B, C or D (direct, linear, ...)")
    return found


def method_letter(method: Method) -> str:
    """A, B, C or D, as the paper names the methods."""
    return "ABCD"[int(method)]


def param_of(param: str | int | Param) -> Param:
    """A parameter from its name (cycle_steps, any case), its number, or the enum itself."""
    if isinstance(param, Param):
        return param
    try:
        return Param(param) if isinstance(param, int) else Param[str(param).strip().upper()]
    except (KeyError, ValueError):
        names = ", ".join(p.name.lower() for p in Param)
        raise ValueError(f"no parameter '{param}'; parameters: {names}") from None


def check_value(param: Param, value: int, *, zero_keeps: bool = False) -> int:
    """value if the firmware accepts it for param (0 too where zero_keeps: "keep the stored")."""
    spec = PARAM_SPECS[param]
    if isinstance(value, bool) or not isinstance(value, int):
        raise ValueError(f"{param.name.lower()} must be a whole number, not {value!r}")
    if zero_keeps and value == 0:
        return value
    if not spec.min <= value <= spec.max:
        keep = " (or 0 to keep each particle's stored value)" if zero_keeps else ""
        raise ValueError(f"{param.name.lower()} must be {spec.min}..{spec.max}{keep}, not {value}")
    return value


class Swarm:
    """A swarm of particles reached through one radio, real or simulated.

    What the particles report is kept per particle (`particles()`); commands are repeated until
    each particle confirms them, and the blocking methods (wait_for, set, get, start, stop,
    set_id) return typed reports or raise SwarmError subclasses that say who did not confirm and
    why. Everything is written to the same session log the console writes. Time is the radio's:
    on a simulated radio, sleep(300) is 300 simulated seconds, and at speed=max the simulation is
    stepped by these calls themselves, as fast as it runs, the same way every time for a seed.

    UIs use the send_* methods, which return at once, and call poll() a few times a second.
    """

    def __init__(
        self,
        radio: Radio,
        *,
        log_dir: str | Path | None = "logs",
        log_name: str | None = None,
        fleet: Fleet | str | Path | None = None,
        fsync: bool = False,
        stepped: bool | None = None,
        stop_grace: float = STOP_GRACE_S,
    ) -> None:
        """Takes over an open radio (closed by close()). See open() for the options."""
        self.radio = radio
        try:
            self.fleet_path: Path | None = None
            if isinstance(fleet, str | Path):
                self.fleet_path = Path(fleet)
                fleet = load_fleet(self.fleet_path)
            self.fleet: Fleet | None = fleet
            self.stepped = _decide_stepping(radio, stepped)
            self.session = Session(radio)
            self.log: JsonlWriter | None = None
            if log_dir is not None:
                folder = Path(log_dir)
                path = default_log_path(folder) if log_name is None else folder / log_name
                self.log = JsonlWriter(path, radio=radio.url, fsync=fsync, clock=radio.now)
                self.session.add_listener(self.log)
                if (simulated := _simulated(radio)) is not None:
                    # A simulation knows what no radio can say: where every body is.
                    simulated.add_truth_listener(self.log.write)
            self.tracker = SwarmTracker(
                self.session,
                radio.now,
                roster=None if fleet is None else fleet.roster_ids(),
                quiet_hint=radio.quiet_hint,
                stop_grace=stop_grace,
                # Without a fleet file, a STOP is called confirmed only once the base station
                # has listened for the grace period's length, with or without the grace period.
                listen_s=STOP_GRACE_S,
            )
            self.session.add_listener(self.tracker)
        except BaseException:
            radio.close()
            raise
        self._closed = threading.Event()
        speed = simulated.speed if (simulated := _simulated(radio)) is not None else None
        self.poll_wall_s = POLL_S if speed is None or self.stepped else max(0.001, POLL_S / speed)
        """Wall time between two polls while waiting: POLL_S of the radio's time."""
        if not self.stepped:
            self.session.start()

    @classmethod
    def open(
        cls,
        radio: str | Radio,
        *,
        log_dir: str | Path | None = "logs",
        log_name: str | None = None,
        fleet: Fleet | str | Path | None = None,
        fsync: bool = False,
        stepped: bool | None = None,
        stop_grace: float = STOP_GRACE_S,
    ) -> Swarm:
        """Opens a radio URL (or takes an open Radio) and starts listening.

        radio: serial:///dev/ttyUSB0, xbee:///dev/ttyUSB0, virtual://10?speed=max&loss=0.2,
        emulated://5 (README lists every option). log_dir: where the session log goes (a new
        file named after the date and time, or log_name); None for no log. fleet: the fleet
        file (or a Fleet): its particles are the roster every STOP must hear from. stepped:
        whether calls on this object step a simulated radio (default: at speed=max; a UI that
        polls on a timer wants a paced thread instead, False). stop_grace: seconds after
        opening during which STOP keeps going out whatever has been heard (particles this
        session has not heard of may be moving). Without a fleet, a STOP given within
        STOP_GRACE_S of opening with a shorter grace ends unconfirmed at best (StopReport.verdict).

        Raises RadioError, particlebot.logs.jsonl.LogError or FleetFileError with one line
        saying what to change.
        """
        if isinstance(radio, str):
            # At speed=max the simulation is stepped by this object from the start: no thread
            # of its own ever runs ahead.
            parsed = parse_radio_url(radio)
            flat_out = parsed.scheme in SIMULATED_SCHEMES and math.isinf(parsed.get_speed())
            opened = open_radio(radio, caller_steps=bool(stepped or (stepped is None and flat_out)))
        else:
            opened = radio
        return cls(
            opened,
            log_dir=log_dir,
            log_name=log_name,
            fleet=fleet,
            fsync=fsync,
            stepped=stepped,
            stop_grace=stop_grace,
        )

    # ---- lifecycle -------------------------------------------------------------------------

    def close(self) -> None:
        """Stops listening, closes the radio and the log. Particles keep doing what they do."""
        self._closed.set()
        self.session.close()

    @property
    def closed(self) -> bool:
        return self._closed.is_set()

    def __enter__(self) -> Self:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        """Leaving the block by an exception (Ctrl-C too) while a run goes on (a START and no
        STOP since) sends STOP first, and waits for it to be confirmed; then closes."""
        tracker = self.tracker
        try:
            # Not when a STOP went out since the last START: that one was seen through already.
            if exc_type is not None and not self.closed and tracker.run_active:
                with contextlib.suppress(SwarmError, RadioError):
                    self.stop()
        finally:
            self.close()

    @property
    def log_path(self) -> Path | None:
        return None if self.log is None else self.log.path

    @property
    def url(self) -> str:
        return self.radio.url

    def now(self) -> float:
        """The radio's clock: seconds since the epoch, simulated on simulated radios."""
        return self.radio.now()

    # ---- what is known ---------------------------------------------------------------------

    def particles(self) -> list[Particle]:
        """Every particle heard (and every fleet particle), by id."""
        now = self.now()
        tracker = self.tracker
        return [
            Particle(
                id=row.id,
                radio=row.source,
                state=row.state,
                s_n=row.status.s_n if row.status and row.status.s_n else None,
                run_id=row.status.run_id if row.status else None,
                intensity=row.intensity,
                last_heard=row.last_heard,
                flags=tuple(row.flags(now, tracker.silent_after, tracker.host_hash)),
                status=row.status,
            )
            for row in tracker.rows()
        ]

    def particle(self, particle_id: int) -> Particle | None:
        return next((p for p in self.particles() if p.id == particle_id), None)

    def notes(self) -> list[str]:
        """Messages since the previous call: confirmations, warnings (a reset, a duplicate id,
        a foreign firmware), errors; each also goes into the log."""
        return [f"{note.level}: {note.text}" for note in self.tracker.new_notes()]

    # ---- blocking commands -----------------------------------------------------------------

    def wait_for(
        self,
        count: int | None = None,
        *,
        ids: list[int] | None = None,
        timeout: float = 15.0,
    ) -> list[Particle]:
        """Waits until count particles (or every one of ids; or, with neither, every particle
        of the fleet) answer, asking every particle for a STATUS each second. Returns them;
        ParticlesMissing after timeout seconds (the radio's time)."""
        if count is None and ids is None:
            if self.fleet is None:
                raise ValueError("say how many: wait_for(count=N) or wait_for(ids=[...])")
            ids = self.fleet.roster_ids()
        wanted = None if ids is None else set(ids)
        next_ping = self.now()

        def heard() -> list[int]:
            return [row.id for row in self.tracker.heard_rows() if row.id != UNASSIGNED_ID]

        def enough() -> bool:
            nonlocal next_ping
            present = heard()
            if (wanted is None or wanted <= set(present)) and len(present) >= (count or 0):
                return True
            if self.now() >= next_ping - CLOCK_SLACK_S:
                next_ping = self.now() + WAIT_PING_S
                with contextlib.suppress(ReadOnlyRadioError):
                    self.tracker.ping()
            return False

        if not self._wait(enough, self.now() + timeout):
            present = sorted(set(heard()))
            missing = sorted(wanted - set(present)) if wanted is not None else []
            asked = f"particles {', '.join(map(str, sorted(wanted)))}" if wanted else f"{count}"
            raise ParticlesMissing(
                f"waited {timeout:g} s for {asked}: heard {len(present)} "
                f"({', '.join(map(str, present)) or 'none'})"
                + (f"; missing {', '.join(map(str, missing))}" if missing else ""),
                tuple(present),
                tuple(missing),
            )
        return self.particles()

    def set(
        self, param: str | Param, value: int, *, to: int | None = None, check: bool = True
    ) -> ParamReport:
        """Sets a parameter (stored in each particle's EEPROM) on every particle heard, or on
        particle `to`. Particles that do not answer are asked again by id. Returns each
        particle's answer; NotConfirmed if one refused (BUSY: in a run) or never answered,
        unless check=False."""
        chosen = param_of(param)
        check_value(chosen, value)
        query = self.tracker.set_param(chosen, value, BROADCAST_ID if to is None else to)
        return self._param_report(query, check)

    def get(self, param: str | Param, *, of: int | None = None) -> ParamReport:
        """Reads a parameter from every particle heard (or particle `of`); report.values."""
        chosen = param_of(param)
        query = self.tracker.get_param(chosen, BROADCAST_ID if of is None else of)
        return self._param_report(query, check=False)

    def start(
        self,
        method: str | Method = "D",
        *,
        cycle_steps: int = 0,
        wave_size: int = 0,
        update_interval_s: int = 0,
        phototaxis: bool = False,
    ) -> Run:
        """Starts a run with estimation method A, B, C or D; returns once every particle heard
        reports the run. cycle_steps (20 ms servo steps per cycle), wave_size (N of eq. 3) and
        update_interval_s left 0 keep each particle's stored value (wave_size: automatic).
        NotConfirmed names the particles that did not join, and why."""
        campaign = self.send_start(
            method,
            cycle_steps=cycle_steps,
            wave_size=wave_size,
            update_interval_s=update_interval_s,
            phototaxis=phototaxis,
        )
        self._finish(campaign)
        if not campaign.success:
            unconfirmed = self._unconfirmed(campaign)
            raise NotConfirmed(
                not_confirmed_text(f"START of run {self.tracker.run_id}", unconfirmed),
                unconfirmed,
            )
        if not campaign.confirmed:
            raise NotConfirmed(
                "START went out, but no particle is known to confirm it: wait_for() the "
                "particles first",
                (),
            )
        return Run(
            run_id=self.tracker.run_id,
            method=method_of(method),
            cycle_steps=cycle_steps,
            wave_size=wave_size,
            update_interval_s=update_interval_s,
            phototaxis=phototaxis,
            started_at=campaign.started,
            confirmed_at=campaign.finished_at or self.now(),
            particles=tuple(sorted(self._ids(campaign.confirmed))),
        )

    def stop(self) -> StopReport:
        """STOP, repeated until every particle expected (the fleet's, or those heard lately,
        and never fewer than the largest group seen) reports it stopped, or 10 s pass (longer
        just after opening: see open's stop_grace). Never raises for particles that did not
        confirm: the report names them and says why."""
        campaign = self.tracker.stop()
        self._finish(campaign)
        unconfirmed = self._unconfirmed(campaign)
        never_heard = max(0, campaign.required() - len(campaign.confirmed) - len(unconfirmed))
        return StopReport(
            confirmed=campaign.success and bool(campaign.confirmed),
            verdict=campaign.verdict or Verdict.FAILED,
            stopped=tuple(sorted(self._ids(campaign.confirmed))),
            unconfirmed=unconfirmed,
            never_heard=never_heard,
            seconds=(campaign.finished_at or self.now()) - campaign.started,
            text=campaign.outcome,
        )

    def sleep(self, seconds: float) -> None:
        """Waits seconds of the radio's time (simulated on simulated radios) while commands go
        on being confirmed and everything heard is logged."""
        self._wait(lambda: False, self.now() + seconds)

    def wait_until(self, condition: Callable[[], bool], timeout: float | None) -> bool:
        """Waits until condition() holds (checked every 50 ms) or timeout seconds pass (None:
        for ever)."""
        return self._wait(condition, None if timeout is None else self.now() + timeout)

    def set_id(self, particle_id: int, new_id: int, *, force: bool = False) -> Particle:
        """Gives particle particle_id the id new_id (stored in its EEPROM) and waits for it to
        answer under it; its old row goes, and the fleet file follows. IdInUse if new_id is the
        fleet's or another particle's, unless force (that one is gone)."""
        if particle_id == BROADCAST_ID or not 1 <= new_id <= 253:
            raise ValueError("SET_ID names one particle, and new ids are 1..253")
        sent_at = self.now()
        try:
            self.tracker.set_id(particle_id, new_id, force=force)
        except IdInUseError as exc:
            raise IdInUse(str(exc)) from None

        def answered() -> bool:
            return any(
                row.id == new_id and row.status_time is not None and row.status_time > sent_at
                for row in self.tracker.rows()
            )

        if not self._wait(answered, sent_at + SET_ID_TIMEOUT_S):
            raise NotConfirmed(
                f"particle {particle_id} did not answer as {new_id} within "
                f"{SET_ID_TIMEOUT_S:g} s (its SET_ID or the answer may be lost: try again)",
                (Unconfirmed(particle_id, "no STATUS under the new id"),),
            )
        particle = self.particle(new_id)
        assert particle is not None
        return particle

    def forget(self, particle_id: int) -> bool:
        """Drops a particle that is gone for good: it is no longer expected to confirm STOP."""
        return self.tracker.forget(particle_id) > 0

    def identify(self, particle_id: int | None = None) -> None:
        """Makes an idle particle (or every one) wiggle three times."""
        self.tracker.identify(BROADCAST_ID if particle_id is None else particle_id)

    def ping(self, particle_id: int | None = None) -> None:
        """Asks a particle (or every one) for a STATUS now."""
        self.tracker.ping(BROADCAST_ID if particle_id is None else particle_id)

    def note(self, text: str) -> None:
        """Writes a remark into the session log (and shows it in a console)."""
        self.tracker.note(text)

    def sample(
        self, ids: Collection[int], frames: int = 5, *, timeout: float = 20.0
    ) -> dict[int, list[Status]]:
        """Collects `frames` STATUS reports sent from now on by each particle of ids (PINGing
        those still short, a few at a time), e.g. to average light readings: each report's
        sensors are 50-sample means. ParticlesMissing names who fell short after timeout."""
        wanted = sorted(set(ids))
        if not wanted or frames < 1:
            raise ValueError("sample() needs particle ids and frames >= 1")
        recorder = _StatusRecorder(set(wanted), self.now())
        self.session.add_listener(recorder)
        next_ping = self.now()
        asked: dict[int, int] = dict.fromkeys(wanted, 0)

        def enough() -> bool:
            nonlocal next_ping
            counts = recorder.counts()
            short = [i for i in wanted if counts.get(i, 0) < frames]
            if not short:
                return True
            if self.now() >= next_ping - CLOCK_SLACK_S:
                next_ping = self.now() + SAMPLE_PING_S
                for particle_id in sorted(short, key=lambda i: (asked[i], i))[:SAMPLE_PINGS]:
                    asked[particle_id] += 1
                    with contextlib.suppress(ReadOnlyRadioError):
                        self.tracker.ping(particle_id)
            return False

        try:
            complete = self._wait(enough, self.now() + timeout)
        finally:
            self.session.remove_listener(recorder)
        reports = recorder.reports()
        if not complete:
            short = [i for i in wanted if len(reports.get(i, [])) < frames]
            heard = [i for i in wanted if i not in short]
            raise ParticlesMissing(
                f"waited {timeout:g} s for {frames} STATUS reports from each of particles "
                f"{ids_text(wanted)}: "
                + "; ".join(f"{i} sent {len(reports.get(i, []))}" for i in short),
                tuple(heard),
                tuple(short),
            )
        return {i: reports[i][:frames] for i in wanted}

    def hold_servo(self, particle_id: int, pulse_us: int, seconds: int = 30) -> Particle:
        """Makes a resting particle (IDLE or DONE) hold its servo at pulse_us (servo
        calibration) for seconds (the firmware holds at most 60: send it again to hold longer),
        and returns once its STATUS shows the hold. stop(), start(), identify() and
        release_servo() end a hold. NotConfirmed says why not: it runs (STOP it first), or it
        did not answer."""
        if pulse_us not in SERVO_PULSES:
            raise ValueError(
                f"servo pulses are {SERVO_PULSES.start}..{SERVO_PULSES.stop - 1} us, not {pulse_us}"
            )
        if not 1 <= seconds <= 255:
            raise ValueError(f"a hold lasts 1..255 s (the firmware caps it at 60), not {seconds}")
        return self._servo_hold(particle_id, pulse_us, seconds)

    def release_servo(self, particle_id: int) -> Particle:
        """Ends particle_id's hold (SERVO_HOLD for 0 s): its servo goes straight back to the
        contracted radius's pulse. Returns once its STATUS shows it no longer holding;
        NotConfirmed otherwise (the firmware still ends the hold when its time is up)."""
        return self._servo_hold(particle_id, 0, 0)

    # ---- for UIs: commands that return at once ---------------------------------------------

    def send_start(
        self,
        method: str | Method = "D",
        *,
        cycle_steps: int = 0,
        wave_size: int = 0,
        update_interval_s: int = 0,
        phototaxis: bool = False,
    ) -> Campaign:
        chosen = method_of(method)
        check_value(Param.CYCLE_STEPS, cycle_steps, zero_keeps=True)
        check_value(Param.WAVE_SIZE, wave_size, zero_keeps=True)
        check_value(Param.UPDATE_INTERVAL_S, update_interval_s, zero_keeps=True)
        return self.tracker.start(
            chosen,
            cycle_steps=cycle_steps,
            wave_size=wave_size,
            update_interval_s=update_interval_s,
            phototaxis=phototaxis,
        )

    def send_stop(self) -> Campaign:
        return self.tracker.stop()

    def send_set(self, param: str | Param, value: int, to: int | None = None) -> ParamQuery:
        chosen = param_of(param)
        return self.tracker.set_param(
            chosen, check_value(chosen, value), BROADCAST_ID if to is None else to
        )

    def send_get(self, param: str | Param, of: int | None = None) -> ParamQuery:
        return self.tracker.get_param(param_of(param), BROADCAST_ID if of is None else of)

    def send_set_id(self, particle_id: int, new_id: int, *, force: bool = False) -> None:
        try:
            self.tracker.set_id(particle_id, new_id, force=force)
        except IdInUseError as exc:
            raise IdInUse(str(exc)) from None

    def poll(self) -> None:
        """Advances everything one step: on a simulation stepped here, POLL_S of its time;
        then confirmations, resends and timeouts. RadioError once the radio has failed."""
        if self.stepped:
            radio = _simulated(self.radio)
            assert radio is not None
            try:
                with _interrupts_deferred():
                    radio.advance(POLL_S)
            except RadioError:
                raise
            except Exception as exc:  # the simulation itself failed: say so, in one line
                raise RadioError(f"The simulated swarm stopped ({exc})") from exc
            self.session.pump()
        self.tracker.poll()
        for rename in self.tracker.take_renames():
            self._follow_rename(rename)

    # ---- internals -------------------------------------------------------------------------

    def _servo_hold(self, particle_id: int, pulse_us: int, seconds: int) -> Particle:
        if particle_id in (BROADCAST_ID, UNASSIGNED_ID):
            raise ValueError("SERVO_HOLD names one particle by its id")
        what = f"SERVO_HOLD {pulse_us} us for {seconds} s" if seconds else "the end of the hold"
        campaign = self.tracker.servo_hold(particle_id, pulse_us, seconds)
        self._finish(campaign)
        particle = self.particle(particle_id)
        if campaign.success and campaign.confirmed and particle is not None:
            return particle
        if not campaign.confirmed and not campaign.pending and not campaign.send_failures:
            why = "not heard in this session (wait_for it first)"
        else:
            status = particle.status if particle else None
            running = status is not None and status.state not in (
                State.IDLE,
                State.DONE,
                State.HOLDING,
            )
            if running and status is not None:
                why = f"it is {State(status.state).name}, not at rest: STOP it first"
            else:
                reasons = self._unconfirmed(campaign)
                why = reasons[0].reason if reasons else campaign.outcome
        raise NotConfirmed(
            f"particle {particle_id} did not confirm {what}: {why}",
            (Unconfirmed(particle_id, why),),
        )

    def _wait(self, done: Callable[[], bool], deadline: float | None) -> bool:
        """Polls until done() or the radio's clock passes deadline; True if done()."""
        while True:
            if self.closed:
                raise SwarmError("the swarm was closed")
            if self.session.error is not None:
                raise self.session.error
            if done():
                return True
            if deadline is not None and self.now() >= deadline - CLOCK_SLACK_S:
                return done()
            self.poll()
            if not self.stepped:
                self._closed.wait(self.poll_wall_s)

    def _finish(self, campaign: Campaign) -> None:
        """Waits for a campaign to end; SwarmError if nothing could be sent at all."""
        self._wait(lambda: campaign.done, None)
        if campaign.send_failures and campaign.rounds <= campaign.send_failures:
            raise SwarmError(f"{campaign.name} could not be sent: see the log ({self.url})")

    def _param_report(self, query: ParamQuery, check: bool) -> ParamReport:
        self._wait(lambda: query.done, None)
        replies = {
            particle: Reply(particle, ParamResult(result), value)
            for particle, (result, value) in query.replies.items()
        }
        report = ParamReport(
            param=Param(query.param),
            value=query.value,
            replies=replies,
            missing=tuple(query.missing),
            text=query.summary(round((query.finished_at or self.now()) - query.started, 1)),
        )
        if check and not report.ok:
            if not report.replies and not report.missing:
                raise NotConfirmed(f"{query.head()}: no particle is known to answer", ())
            raise NotConfirmed(
                not_confirmed_text(query.head(), report.unconfirmed), report.unconfirmed
            )
        return report

    def _unconfirmed(self, campaign: Campaign) -> tuple[Unconfirmed, ...]:
        return tuple(Unconfirmed(pid, why) for pid, why in self.tracker.unconfirmed(campaign))

    def _ids(self, keys: Collection[str]) -> list[int]:
        rows = self.tracker.particles
        return [rows[key].id for key in keys if key in rows]

    def _follow_rename(self, rename: Rename) -> None:
        """The fleet's record of a renamed particle moves to its new id (file and memory)."""
        if self.fleet is None:
            return
        try:
            if self.fleet_path is not None:
                with updating_fleet(self.fleet_path) as fleet:
                    moved = _move_record(fleet, rename)
                self.fleet = load_fleet(self.fleet_path)
            else:
                moved = _move_record(self.fleet, rename)
        except (FleetFileError, FleetError, OSError) as exc:
            self.tracker.note(f"The fleet file could not follow the rename: {exc}", "error")
            return
        if moved:
            where = self.fleet_path or "the fleet"
            self.tracker.note(
                f"{where}: particle {rename.old_id}'s record is now particle {rename.new_id}'s"
            )


class _StatusRecorder(Listener):
    """Every STATUS from the particles of ids received after since, in order (sample())."""

    def __init__(self, ids: set[int], since: float) -> None:
        self.ids = ids
        self.since = since
        self._lock = threading.Lock()
        self._reports: dict[int, list[Status]] = {}

    def on_frame(self, received: ReceivedFrame) -> None:
        message = received.frame.message
        sender = received.frame.sender
        if isinstance(message, Status) and sender in self.ids and received.time > self.since:
            with self._lock:
                self._reports.setdefault(sender, []).append(message)

    def counts(self) -> dict[int, int]:
        with self._lock:
            return {particle: len(reports) for particle, reports in self._reports.items()}

    def reports(self) -> dict[int, list[Status]]:
        with self._lock:
            return {particle: list(reports) for particle, reports in self._reports.items()}


def _move_record(fleet: Fleet, rename: Rename) -> bool:
    record = fleet.forget(rename.old_id)
    if record is None:
        return False
    fleet.record(dataclasses.replace(record, id=rename.new_id))
    return True


def _simulated(radio: Radio) -> SwarmRadio | None:
    """The radio as a simulation's, or None. The simulator is imported here, where a Swarm opens,
    rather than at the top, so that `import particlebot` and every --help stay light."""
    from particlebot.radio.simulated import SwarmRadio

    return radio if isinstance(radio, SwarmRadio) else None


def _decide_stepping(radio: Radio, stepped: bool | None) -> bool:
    """Whether Swarm's own calls step the simulation: a simulated radio asked to run as fast as
    possible (speed=max), or given without a thread of its own."""
    simulated = _simulated(radio)
    if simulated is None:
        if stepped:
            raise ValueError(f"{radio.url} is not a simulation: it cannot be stepped")
        return False
    if simulated.stepped_by_caller:
        if stepped is False:
            raise ValueError(f"{radio.url} has no thread to pace it: it must be stepped")
        return True
    flat_out = simulated.speed is not None and math.isinf(simulated.speed)
    if stepped or (stepped is None and flat_out):
        simulated.step_by_caller()
        return True
    return False


@contextlib.contextmanager
def _interrupts_deferred() -> Iterator[None]:
    """Ctrl-C waits for the simulation step under way to end: an emulated particle interrupted
    in the middle of its step would leave its process out of step with the rest."""
    if (
        threading.current_thread() is not threading.main_thread()
        or signal.getsignal(signal.SIGINT) is not signal.default_int_handler
    ):
        yield
        return
    caught: list[int] = []

    def later(signum: int, frame: FrameType | None) -> None:
        caught.append(signum)

    previous = signal.signal(signal.SIGINT, later)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)
    if caught:
        raise KeyboardInterrupt
