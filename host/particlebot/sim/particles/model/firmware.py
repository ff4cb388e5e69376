"""The `firmware` controller: what our particle firmware does, vectorised over the whole swarm.

Each particle runs the firmware's run schedule from one START at `start_s` (SI Algorithms 2 and
3, as firmware/lib/coordination implements them): an estimation round of ROUND_MS, S_n from the
round's readings by method A, B, C or D (firmware/lib/estimation, integer arithmetic included,
see estimation.py), then cycles of eq. 4 in servo steps of 20 ms, the first one eq. 5's
t_I = (S_n - 1) T/2 after the common start less whole wave periods T + t_p, pauses
t_p = (N - 1) T/2 (eq. 3), and a new round every epoch. With phototaxis a particle whose
intensity did not increase since its last round stops for good (state DONE).

What the model idealises, and nothing else:
- The radio: every particle hears every other particle's INTENSITY broadcast in every round, so
  the group is the whole swarm (less the particles that finished phototaxis). The firmware's
  record of 32 senders is lifted, and an automatic wave size N is the swarm's size, saturated at
  255 as the firmware's one-byte group size would be; choose `wave_size` for large swarms.
- The clock: all particles hear START at the same instant and their clocks do not drift, so the
  rounds of the whole swarm stay in step.
- The light: a particle's six photocells read the same value (the world's eq. 11 reading), each
  conversion rounded to the nearest count, taken at the start of each round.
- Sensor noise, if asked for, as Fig. S20 states it: an error in the distance the reading implies.

Everything the firmware defines comes from the protocol's parameter defaults or through the C
API (the servo step, full-scale reading, S_n's ceiling, N_w's cap); tests/sim/particles compare
S_n with pb_estimate, the schedule with pb_plan_epoch and the radius with a NativeParticle.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numba
import numpy as np
import numpy.typing as npt

from particlebot.firmware.native import FirmwareConstants, firmware_constants
from particlebot.options import Bounds, check_fields
from particlebot.protocol import PARAM_SPECS, Method, Param
from particlebot.sim.particles.model.controller import (
    BoolArray,
    Controller,
    FloatArray,
    WorldView,
)
from particlebot.sim.particles.model.estimation import (
    EstimationParams,
    GroupEstimator,
    IntArray,
    check_in_spec,
)

_DEFAULT_METHOD = Method(PARAM_SPECS[Param.METHOD].default)
# START carries the wave size in one byte; 0 means automatic.
_WAVE_SIZE_MAX = 255
# Offsets of the first cycle are 0..N half periods; one more class is "contracted, no cycle".
_IDLE_CLASS = _WAVE_SIZE_MAX + 1


@dataclass(frozen=True)
class FirmwareSettings:
    """A run as the console starts it (START's fields) with the particles' stored parameters.

    Defaults are the protocol's parameter defaults; wave_size 0 is START's automatic N (the
    group heard for methods B-D, WAVE_SIZE for method A).
    """

    method: Method = _DEFAULT_METHOD
    cycle_steps: int = PARAM_SPECS[Param.CYCLE_STEPS].default
    wave_size: int = 0
    wave_size_param: int = PARAM_SPECS[Param.WAVE_SIZE].default
    update_interval_s: int = PARAM_SPECS[Param.UPDATE_INTERVAL_S].default
    round_ms: int = PARAM_SPECS[Param.ROUND_MS].default
    phototaxis: bool = False
    estimation: EstimationParams = field(default_factory=EstimationParams)
    # Standard deviation of each particle's distance estimate, in contracted diameters (the x
    # axis of Fig. S20), drawn afresh for every particle in every round; see noisy_readings().
    noise_diameters: float = 0.0
    # Simulated time at which every particle receives START.
    start_s: float = 0.0

    def __post_init__(self) -> None:
        if not isinstance(self.method, Method):
            raise ValueError(f"method must be one of {', '.join(m.name for m in Method)}")
        check_in_spec("cycle_steps", self.cycle_steps, Param.CYCLE_STEPS)
        check_in_spec("wave_size_param", self.wave_size_param, Param.WAVE_SIZE)
        check_in_spec("update_interval_s", self.update_interval_s, Param.UPDATE_INTERVAL_S)
        check_in_spec("round_ms", self.round_ms, Param.ROUND_MS)
        if isinstance(self.wave_size, bool) or not isinstance(self.wave_size, int):
            raise ValueError(f"wave_size must be an integer, not {self.wave_size!r}")
        if not 0 <= self.wave_size <= _WAVE_SIZE_MAX:
            raise ValueError(f"wave_size = {self.wave_size} is outside 0..{_WAVE_SIZE_MAX}")
        check_fields(
            self,
            {
                "noise_diameters": Bounds(minimum=0, maximum=1e6),
                "start_s": Bounds(minimum=0, maximum=1e8),  # the scenarios' longest run
            },
        )


@dataclass(frozen=True)
class EpochPlans:
    """One epoch's schedule for every particle, as the firmware's plan_epoch() gives it (ms)."""

    first_cycle_ms: IntArray  # after the common start, per particle
    pause_ms: int  # t_p
    epoch_ms: int  # from this round's start to the next one's
    wave_size: int  # N


def plan_epochs(
    settings: FirmwareSettings, s_n: IntArray, group_size: int, step_ms: int
) -> EpochPlans:
    """The firmware's plan_epoch() (coordination.cpp) for a swarm whose members all heard
    group_size particles, themselves included."""
    n_wave = settings.wave_size
    if n_wave == 0:
        n_wave = settings.wave_size_param if settings.method is Method.DIRECT else group_size
    n_wave = min(max(n_wave, 1), _WAVE_SIZE_MAX)
    half_period = settings.cycle_steps * (step_ms // 2)
    delays = (np.maximum(s_n, 1) - 1) % (n_wave + 1)  # eq. 5 less whole wave periods
    epoch = max(settings.update_interval_s * 1000, settings.round_ms + (n_wave + 2) * half_period)
    return EpochPlans(
        first_cycle_ms=delays * half_period,
        pause_ms=(n_wave - 1) * half_period,  # eq. 3
        epoch_ms=epoch,
        wave_size=n_wave,
    )


def noisy_readings(
    readings: FloatArray,
    sigma_m: float,
    rng: np.random.Generator,
    params: EstimationParams,
    full_scale: int,
) -> FloatArray:
    """Readings whose distance estimates err by a Gaussian of sigma_m metres.

    A reading V implies a ground distance D_n from the point under the lamp through the
    firmware's calibration (eqs. 14-15 with r_x = REF_DISTANCE_MM, V_x = REF_VALUE: exactly
    what method A computes before dividing by D). Each particle's D_n gets an independent error
    N(0, sigma_m^2) and the reading becomes the one that implies the new distance (a negative
    distance mirrors to a positive one, as a ground distance does). When the world's lamp is at
    height r_x and reads V_x under it, D_n is the true ground distance to the lamp's foot and the
    error is the distance-estimation error of Fig. S20. Unlit particles (V = 0) stay dark;
    rounding the result to whole counts adds the sensor's own quantisation on top.
    """
    if sigma_m <= 0:
        return readings
    r_x = params.ref_distance_mm / 1000.0
    k = (full_scale - params.ref_value) / params.ref_value
    noisy = np.array(readings, dtype=np.float64)
    lit = noisy > 0
    v = np.minimum(noisy[lit], full_scale)
    ratio = (full_scale - v) / (v * k)  # (r_n / r_x)^2, eq. 14
    ground = r_x * np.sqrt(np.maximum(ratio - 1.0, 0.0))  # eq. 15
    ground = ground + rng.normal(0.0, sigma_m, ground.shape)
    noisy[lit] = full_scale / (1.0 + k * (1.0 + (ground / r_x) ** 2))
    return noisy


@numba.njit(cache=True)
def _class_tables(
    now_ms: int,
    first_ms: int,
    half_period_ms: int,
    wave_period_ms: int,
    epoch_end_ms: int,
    classes: int,
    step_ms: int,
    profile: FloatArray,
    r_min: float,
    stroke: float,
    radius: FloatArray,
    phase: FloatArray,
) -> None:
    """Radius and phase at now_ms of offset classes 0..classes - 1, class c's cycles starting c
    half periods after first_ms and every wave period after that; the rest stay as they are."""
    steps = profile.shape[0]
    period = steps * step_ms
    for c in range(classes):
        since = now_ms - (first_ms + c * half_period_ms)
        if since < 0:
            continue
        cycle_start = now_ms - since % wave_period_ms
        # A cycle only runs if it ends inside the epoch (the body is contracted at every
        # boundary), exactly as the firmware's coordinator decides.
        if now_ms - cycle_start >= period or cycle_start + period > epoch_end_ms:
            continue
        k = (now_ms - cycle_start) // step_ms
        radius[c] = r_min + stroke * profile[k]
        phase[c] = k / steps


@numba.njit(cache=True)
def _gather(table: FloatArray, classes: npt.NDArray[np.uint16], out: FloatArray) -> None:
    """out[i] = table[classes[i]]: one pass, 2 bytes read and 8 written per particle."""
    for i in range(classes.shape[0]):
        out[i] = table[classes[i]]


class FirmwareController(Controller):
    """The firmware's run, vectorised: every particle's servo target at every world step.

    Particles that share a first-cycle offset move identically, so a step works out the radius
    of at most N + 2 offset classes and gathers it into the swarm's array; the light is read and
    S_n estimated only at round starts.
    """

    def __init__(self, settings: FirmwareSettings | None = None) -> None:
        self.settings = settings if settings is not None else FirmwareSettings()
        self._constants: FirmwareConstants | None = None
        self._rng = np.random.default_rng()
        self._start_ms = round(self.settings.start_s * 1000.0)
        self._round = -1
        self._epoch_start_ms = 0
        self._next_round_ms = self._start_ms
        self._plans: EpochPlans | None = None
        self._classes = np.zeros(0, dtype=np.uint16)
        self._s_n = np.zeros(0, dtype=np.int64)
        self._done = np.zeros(0, dtype=np.bool_)
        self._previous = np.zeros(0, dtype=np.int64)
        self._radius_table = np.zeros(_IDLE_CLASS + 1)
        self._phase_table = np.full(_IDLE_CLASS + 1, np.nan)
        self._table_key = (-1, 0.0, 0.0)  # (ms, r_min, r_max) the tables hold

    # ---- the Controller contract ------------------------------------------------------------

    def bind(self, count: int, rng: np.random.Generator) -> None:
        constants = firmware_constants()
        self._constants = constants
        self._estimator = GroupEstimator(self.settings.estimation, constants)
        self._step_ms = constants.servo_step_ms
        steps = self.settings.cycle_steps
        # Eq. 4 at each servo step k of a cycle: (1 - cos(2 pi k / n)) / 2 = sin^2(pi k / n).
        self._profile = np.sin(np.pi * np.arange(steps) / steps) ** 2
        self._rng = rng
        self._round = -1
        self._next_round_ms = self._start_ms
        self._plans = None
        self._classes = np.full(count, _IDLE_CLASS, dtype=np.uint16)
        self._s_n = np.zeros(count, dtype=np.int64)
        self._done = np.zeros(count, dtype=np.bool_)
        self._previous = np.zeros(count, dtype=np.int64)
        self._table_key = (-1, 0.0, 0.0)

    def command(self, view: WorldView, out: FloatArray) -> None:
        now_ms = round(view.t * 1000.0)
        while now_ms >= self._next_round_ms:
            self._begin_round(view, self._next_round_ms)
        self._fill_tables(now_ms, view.r_min, view.r_max)
        _gather(self._radius_table, self._classes, out)

    def phase(self, view: WorldView) -> FloatArray:
        self._fill_tables(round(view.t * 1000.0), view.r_min, view.r_max)
        phase = self._phase_table[self._classes]
        phase[~view.acting()] = np.nan
        return phase

    # ---- inspection --------------------------------------------------------------------------

    @property
    def round(self) -> int:
        """The current estimation round (0 first), -1 before START."""
        return self._round

    @property
    def s_n(self) -> IntArray:
        """Each particle's S_n from its last round (0 before the first)."""
        return self._s_n.copy()

    @property
    def done(self) -> BoolArray:
        """Particles that finished phototaxis (state DONE)."""
        return self._done.copy()

    @property
    def plans(self) -> EpochPlans | None:
        """The current epoch's schedule (None before START)."""
        return self._plans

    # ---- the schedule ------------------------------------------------------------------------

    def _begin_round(self, view: WorldView, at_ms: int) -> None:
        if self._constants is None:
            raise RuntimeError("bind() must be called before command()")
        settings = self.settings
        self._round += 1
        self._epoch_start_ms = at_ms
        members = ~self._done
        readings = noisy_readings(
            view.light_readings(),
            settings.noise_diameters * 2.0 * view.r_min,
            self._rng,
            settings.estimation,
            self._constants.adc_full_scale,
        )
        intensities = self._estimator.intensities(readings)
        group = int(np.count_nonzero(members))
        if group > 0:
            self._s_n[members] = self._estimator.estimate(settings.method, intensities[members])
        plans = plan_epochs(
            settings, self._s_n, min(group, _WAVE_SIZE_MAX), self._constants.servo_step_ms
        )
        if settings.phototaxis:
            # Algorithm 3: carry on only while the intensity increased since the last round.
            brighter = intensities > self._previous if self._round > 0 else members
            self._done |= members & ~brighter
        self._previous[members] = intensities[members]
        self._classes[:] = plans.first_cycle_ms // (settings.cycle_steps * (self._step_ms // 2))
        self._classes[self._done] = _IDLE_CLASS
        self._plans = plans
        self._next_round_ms = at_ms + plans.epoch_ms
        self._table_key = (-1, 0.0, 0.0)

    def _fill_tables(self, now_ms: int, r_min: float, r_max: float) -> None:
        """Radius and phase at now_ms of every offset class (class c starts c half periods after
        the common start)."""
        if self._table_key == (now_ms, r_min, r_max):
            return
        self._table_key = (now_ms, r_min, r_max)
        self._radius_table.fill(r_min)
        self._phase_table.fill(np.nan)
        plans = self._plans
        if plans is None or now_ms < self._epoch_start_ms:
            return
        half_period = self.settings.cycle_steps * (self._step_ms // 2)
        _class_tables(
            now_ms,
            self._epoch_start_ms + self.settings.round_ms,
            half_period,
            2 * half_period + plans.pause_ms,
            self._epoch_start_ms + plans.epoch_ms,
            plans.wave_size + 1,
            self._step_ms,
            self._profile,
            r_min,
            r_max - r_min,
            self._radius_table,
            self._phase_table,
        )
