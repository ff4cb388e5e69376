// The run state machine: every transition happens at its scheduled millisecond.
#include "coordination.h"

namespace pb {

namespace {

uint8_t state_byte(State s) {
  return static_cast<uint8_t>(s);
}

// Share of the round in which INTENSITY copies go out, leaving the rest for late arrivals.
const uint8_t kBroadcastWindowPercent = 70;

}  // namespace

uint16_t Rng::next() {
  state_ = state_ * 1664525ul + 1013904223ul;
  return static_cast<uint16_t>(state_ >> 16);
}

Coordinator::Coordinator(Rng &rng)
    : rng_(rng),
      motion_(Motion::hold()),
      epoch_start_ms_(0),
      epoch_end_ms_(0),
      next_cycle_ms_(0),
      pause_ms_(0),
      next_broadcast_ms_(0),
      round_(0),
      previous_intensity_(0),
      state_(state_byte(State::IDLE)),
      s_n_(0),
      group_size_(0),
      repeat_(0),
      last_repeat_(0),
      have_previous_(false),
      round_start_pending_(false) {
  config_.run_id = 0;
  config_.method = static_cast<uint8_t>(Method::COUNTING);
  config_.cycle_steps = 1;
  config_.wave_size = 0;
  config_.wave_size_param = 1;
  config_.broadcast_repeats = 1;
  config_.phototaxis = false;
  config_.update_interval_ms = 0;
  config_.round_ms = 0;
}

bool Coordinator::running() const {
  switch (state()) {
    case State::ESTIMATING:
    case State::WAITING:
    case State::CYCLING:
    case State::PAUSED:
    case State::DONE:
      return true;
    default:
      return false;
  }
}

void Coordinator::start(const RunConfig &config, uint32_t now_ms, uint32_t radius_now_um,
                        const Geometry &g) {
  config_ = config;
  if (config_.cycle_steps == 0) config_.cycle_steps = 1;
  if (config_.broadcast_repeats == 0) config_.broadcast_repeats = 1;
  s_n_ = 0;
  group_size_ = 0;
  have_previous_ = false;
  round_ = 0;
  motion_ = radius_now_um > g.r_min_um ? Motion::ramp(now_ms, radius_now_um, g) : Motion::hold();
  begin_round(now_ms);
  round_start_pending_ = false;  // the owner sets up round 0 itself, see start()'s contract
}

void Coordinator::stop(uint32_t now_ms, uint32_t radius_now_um, const Geometry &g) {
  // The console sends STOP in bursts. A copy that finds the particle already stopping or stopped
  // changes nothing: restarting the ramp would only delay the body and the confirmation.
  if (state() == State::STOPPING || state() == State::IDLE) return;
  state_ = state_byte(State::STOPPING);
  round_start_pending_ = false;
  motion_ = Motion::ramp(now_ms, radius_now_um, g);
}

bool Coordinator::identify(uint32_t now_ms) {
  if (state() != State::IDLE) return false;
  state_ = state_byte(State::IDENTIFYING);
  motion_ = Motion::wiggle(now_ms);
  return true;
}

void Coordinator::begin_round(uint32_t at_ms) {
  state_ = state_byte(State::ESTIMATING);
  epoch_start_ms_ = at_ms;
  // Until the round ends the epoch has no known end; keep it one round long for cycle_fits().
  epoch_end_ms_ = at_ms + config_.round_ms;
  round_start_pending_ = true;
  repeat_ = 0;
  last_repeat_ = 0;
  if (config_.method != static_cast<uint8_t>(Method::DIRECT)) schedule_broadcast();
}

void Coordinator::schedule_broadcast() {
  // One copy at a random instant in each of broadcast_repeats equal slots of the window, so the
  // copies spread out and collisions with other particles differ from copy to copy.
  const uint32_t window = config_.round_ms * kBroadcastWindowPercent / 100;
  const uint16_t slot = static_cast<uint16_t>(window / config_.broadcast_repeats);
  next_broadcast_ms_ = epoch_start_ms_ + static_cast<uint32_t>(slot) * repeat_ + rng_.below(slot);
}

void Coordinator::settle_ramp(uint32_t now_ms) {
  // A finished motion becomes kHold, so a motion's start never ages past the 24-day reach of
  // time_reached() and then replays.
  if (motion_.kind != Motion::kHold && motion_.finished(now_ms)) motion_ = Motion::hold();
}

bool Coordinator::cycle_fits(uint32_t start_ms) const {
  return time_reached(epoch_end_ms_, start_ms + period_ms());
}

Coordinator::Event Coordinator::poll(uint32_t now_ms, bool can_broadcast) {
  for (;;) {
    switch (state()) {
      case State::STOPPING:
      case State::IDENTIFYING:
        if (motion_.finished(now_ms)) {
          state_ = state_byte(State::IDLE);
          motion_ = Motion::hold();
        }
        return kNone;
      case State::ESTIMATING:
        settle_ramp(now_ms);
        if (round_start_pending_) {
          round_start_pending_ = false;
          return kRoundStart;
        }
        if (time_reached(now_ms, epoch_start_ms_ + config_.round_ms)) return kRoundEnd;
        if (config_.method != static_cast<uint8_t>(Method::DIRECT) &&
            repeat_ < config_.broadcast_repeats && can_broadcast &&
            time_reached(now_ms, next_broadcast_ms_)) {
          last_repeat_ = repeat_++;
          if (repeat_ < config_.broadcast_repeats) schedule_broadcast();
          return kBroadcast;
        }
        return kNone;
      case State::WAITING:
      case State::PAUSED:
        if (cycle_fits(next_cycle_ms_)) {
          if (!time_reached(now_ms, next_cycle_ms_)) return kNone;
          if (!motion_.finished(next_cycle_ms_)) {
            // Only when round_ms is shorter than the ramp START began with: skip this cycle
            // rather than jump from a half-contracted body to R_min.
            next_cycle_ms_ += period_ms() + pause_ms_;
            continue;
          }
          state_ = state_byte(State::CYCLING);
          motion_ = Motion::cycle(next_cycle_ms_, config_.cycle_steps);
          continue;
        }
        if (!time_reached(now_ms, epoch_end_ms_)) return kNone;
        ++round_;
        motion_ = Motion::hold();
        begin_round(epoch_end_ms_);
        continue;
      case State::CYCLING: {
        const uint32_t end = motion_.start_ms + period_ms();
        if (!time_reached(now_ms, end)) return kNone;
        state_ = state_byte(State::PAUSED);
        next_cycle_ms_ = end + pause_ms_;
        motion_ = Motion::hold();
        continue;
      }
      default:  // IDLE, DONE
        settle_ramp(now_ms);
        return kNone;
    }
  }
}

EpochPlan plan_epoch(const RunConfig &config, uint8_t s_n, uint8_t group_size) {
  uint8_t n_wave = config.wave_size;
  if (n_wave == 0) {
    n_wave =
        config.method == static_cast<uint8_t>(Method::DIRECT) ? config.wave_size_param : group_size;
  }
  if (n_wave == 0) n_wave = 1;
  if (s_n == 0) s_n = 1;
  const uint32_t half_period = static_cast<uint32_t>(config.cycle_steps) * (kStepMs / 2);
  EpochPlan plan;
  plan.pause_ms = static_cast<uint32_t>(n_wave - 1) * half_period;  // eq. 3
  // Eq. 5's t_I = (S_n - 1) T / 2 less whole wave periods T + t_p = (N + 1) T / 2: every cycle
  // keeps eq. 5's phase, and the first starts within one period of the common start.
  uint8_t delays = static_cast<uint8_t>(s_n - 1);
  while (delays > n_wave) delays = static_cast<uint8_t>(delays - n_wave - 1);
  plan.first_cycle_ms = static_cast<uint32_t>(delays) * half_period;
  // Long enough for the latest first cycle, N T / 2 + T, to end inside the epoch.
  plan.epoch_ms = config.round_ms + (n_wave + 2u) * half_period;
  if (config.update_interval_ms > plan.epoch_ms) plan.epoch_ms = config.update_interval_ms;
  return plan;
}

void Coordinator::finish_round(const RoundResult &result) {
  if (state() != State::ESTIMATING) return;
  s_n_ = result.s_n == 0 ? 1 : result.s_n;
  group_size_ = result.group_size;
  const bool brighter = !have_previous_ || result.intensity > previous_intensity_;
  previous_intensity_ = result.intensity;
  have_previous_ = true;
  const EpochPlan plan = plan_epoch(config_, s_n_, group_size_);
  pause_ms_ = plan.pause_ms;
  next_cycle_ms_ = epoch_start_ms_ + config_.round_ms + plan.first_cycle_ms;  // common start + t_I
  epoch_end_ms_ = epoch_start_ms_ + plan.epoch_ms;
  // A ramp begun at START may still run (round_ms < 600 ms): it is left to finish either way.
  state_ = state_byte(config_.phototaxis && !brighter ? State::DONE : State::WAITING);
}

uint16_t Coordinator::cycle_phase_permille(uint32_t now_ms) const {
  if (state() != State::CYCLING || motion_.kind != Motion::kCycle || motion_.steps == 0) return 0;
  const uint32_t k = motion_.step_at(now_ms);
  if (k >= motion_.steps) return 0;
  return static_cast<uint16_t>(k * 1000u / motion_.steps);
}

}  // namespace pb
