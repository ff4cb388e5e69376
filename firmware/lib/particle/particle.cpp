// Particle controller: dispatches frames, runs the coordinator and keeps the servo target.
#include "particle.h"

namespace pb {

Particle::Particle(Storage &storage, uint8_t reset_cause, uint32_t rng_seed)
    : ParticleState(), settings_(storage), rng_(rng_seed), coordinator_(rng_) {
  servo_kind_ = 0xFF;  // no motion evaluated yet
  reset_cause_ = reset_cause;
}

void Particle::begin(uint32_t now_ms) {
  now_ms_ = now_ms;
  boot_ms_ = now_ms;
  settings_.load();
  settings_.record_reset(reset_cause_);
  refresh_from_settings();
  update_servo(now_ms, true);
  // The first STATUS announces the particle; spreading it over one period keeps a swarm powered
  // up together from answering all at once.
  const uint16_t period = static_cast<uint16_t>(settings_.get(Param::STATUS_PERIOD_MS));
  next_status_ms_ = now_ms + rng_.below(period);
}

void Particle::on_adc_sample(uint8_t sensor, uint16_t raw) {
  if (!sampler_.on_sample(sensor, raw)) return;
  if (readings_awaited_ > 0 && --readings_awaited_ == 0) round_intensity_ = sampler_.intensity();
}

void Particle::on_rx_byte(uint8_t byte, uint32_t now_ms) {
  now_ms_ = now_ms;
  last_rx_ms_ = now_ms;
  rx_idle_pending_ = true;
  if (parser_.push(byte)) handle_frame(parser_.frame(), now_ms);
}

void Particle::tick(uint32_t now_ms, uint32_t servo_ms) {
  now_ms_ = now_ms;
  if (hold_pulse_us_ != 0 && time_reached(now_ms, hold_until_ms_)) end_hold();
  if (rx_idle_pending_ && time_reached(now_ms, last_rx_ms_ + kFrameTimeoutMs)) {
    rx_idle_pending_ = false;
    while (parser_.timeout()) handle_frame(parser_.frame(), now_ms);
  }
  for (;;) {
    const Coordinator::Event event = coordinator_.poll(now_ms, readings_awaited_ == 0);
    if (event == Coordinator::kNone) break;
    if (event == Coordinator::kRoundStart) {
      begin_round_record(coordinator_.round());
    } else if (event == Coordinator::kBroadcast) {
      send_intensity();
    } else {
      finish_round();
    }
  }
  update_servo(servo_ms);
  if (time_reached(now_ms, next_status_ms_)) {
    send_status();
    schedule_status(now_ms);
  }
  if (ping_reply_pending_ && time_reached(now_ms, ping_reply_ms_)) send_status();
  if (param_reply_pending_ && time_reached(now_ms, param_reply_ms_)) send_param_reply();
}

size_t Particle::take_tx(uint8_t *out, size_t capacity) {
  // send() queues whole frames only, so between frames the head is a sync byte and its LEN
  // byte, two further on, tells how long the frame is.
  if (tx_frame_left_ == 0 && tx_count_ > 0) {
    const uint8_t len = tx_[(tx_head_ + 2) % kTxCapacity];
    tx_frame_left_ = static_cast<uint8_t>(len + kFrameOverhead);
    if (tx_frame_left_ > tx_count_) tx_frame_left_ = tx_count_;  // cannot happen; stay bounded
  }
  size_t n = 0;
  while (n < capacity && tx_frame_left_ > 0) {
    out[n++] = tx_[tx_head_];
    tx_head_ = static_cast<uint8_t>((tx_head_ + 1) % kTxCapacity);
    --tx_count_;
    --tx_frame_left_;
  }
  return n;
}

uint8_t Particle::status_payload(uint8_t *out) const {
  StatusMessage m;
  m.state = static_cast<uint8_t>(state());
  m.method = coordinator_.method();
  m.run_id = coordinator_.run_id();
  m.s_n = coordinator_.s_n();
  m.group_size = coordinator_.group_size();
  m.sensor_faults = sampler_.faults();
  m.intensity = sampler_.intensity();
  for (uint8_t k = 0; k < kSensorCount; ++k) m.sensors[k] = sampler_.mean(k);
  m.cycle_phase = coordinator_.cycle_phase_permille(now_ms_);
  m.radius_um = radius_um_;
  m.uptime_ms = now_ms_ - boot_ms_;
  m.definition_hash = kDefinitionHash;
  const ParserCounters &c = parser_.counters();
  m.rx_frames = c.frames;
  m.rx_bad_crc = c.bad_crc;
  m.rx_bad_length = c.bad_length;
  m.rx_skipped_bytes = c.skipped_bytes;
  m.resets = settings_.resets();
  m.last_reset_cause = settings_.last_reset_cause();
  m.servo_pulse_us = servo_pulse_us();
  return m.encode(out);
}

// ---- received frames ---------------------------------------------------------------------------

bool Particle::addressed_to_me(uint8_t target) const {
  return target == kBroadcastId || target == settings_.id();
}

void Particle::handle_frame(const Frame &frame, uint32_t now_ms) {
  // Our own frames come back from some radio setups; a clash of ids is not ours to resolve.
  if (frame.sender == settings_.id()) return;
  if (frame.type == static_cast<uint8_t>(MessageType::INTENSITY)) {
    IntensityMessage m;
    if (frame.sender != kBaseStationId && m.decode(frame.payload, frame.length)) {
      handle_intensity(frame.sender, m);
    }
    return;
  }
  // Everything else is a command, and only the base station gives commands.
  if (frame.sender != kBaseStationId) return;
  switch (static_cast<MessageType>(frame.type)) {
    case MessageType::START: {
      StartMessage m;
      if (m.decode(frame.payload, frame.length)) handle_start(m, now_ms);
      break;
    }
    case MessageType::STOP: {
      StopMessage m;
      if (m.decode(frame.payload, frame.length)) {
        end_hold();
        coordinator_.stop(now_ms, radius_at(now_ms), geometry_);
        update_servo(now_ms);
      }
      break;
    }
    case MessageType::SET_PARAM: {
      SetParamMessage m;
      if (m.decode(frame.payload, frame.length) && addressed_to_me(m.target)) {
        int32_t in_force = 0;
        const ParamResult result = apply_param(m.param, m.value, &in_force);
        reply_param(m.target, m.param, result, in_force, now_ms);
      }
      break;
    }
    case MessageType::GET_PARAM: {
      GetParamMessage m;
      if (m.decode(frame.payload, frame.length) && addressed_to_me(m.target)) {
        int32_t value = 0;
        const bool known = settings_.get(m.param, &value);
        reply_param(m.target, m.param, known ? ParamResult::OK : ParamResult::UNKNOWN_PARAM, value,
                    now_ms);
      }
      break;
    }
    case MessageType::PING: {
      PingMessage m;
      if (m.decode(frame.payload, frame.length) && addressed_to_me(m.target)) {
        answer_with_status(m.target, now_ms);
      }
      break;
    }
    case MessageType::IDENTIFY: {
      IdentifyMessage m;
      if (m.decode(frame.payload, frame.length) && addressed_to_me(m.target)) {
        end_hold();
        if (!coordinator_.identify(now_ms)) {
          // Not idle (in a run, stopping): no wiggle. The STATUS below carries the state it
          // stays in, which is how the console learns that IDENTIFY was refused.
        }
        answer_with_status(m.target, now_ms);
      }
      break;
    }
    case MessageType::SERVO_HOLD: {
      ServoHoldMessage m;
      // Addressed to one particle only (an id is never the broadcast id); answered at once, so
      // the console sees whether the hold took effect.
      if (m.decode(frame.payload, frame.length) && m.target == settings_.id()) {
        handle_servo_hold(m, now_ms);
        send_status();
      }
      break;
    }
    case MessageType::SET_ID: {
      SetIdMessage m;
      // Never by broadcast: every particle would take the same id.
      if (m.decode(frame.payload, frame.length) && m.target == settings_.id() &&
          m.target != kBroadcastId) {
        if (settings_.set_id(m.new_id)) {
          send_status();  // from the new id
        } else {
          // 0, 254 and 255 are no particle's id: the particle keeps its own, and its STATUS,
          // from that id, tells the console the rename did not happen.
          send_status();
        }
      }
      break;
    }
    default:
      break;  // STATUS and PARAM_VALUE are for the base station; unknown types are ignored
  }
}

void Particle::handle_start(const StartMessage &m, uint32_t now_ms) {
  // The console may resend START to reach every particle; only a new run restarts.
  if (coordinator_.running() && coordinator_.run_id() == m.run_id) return;
  end_hold();
  RunConfig c;
  c.run_id = m.run_id;
  c.method = m.method <= static_cast<uint8_t>(Method::COUNTING)
                 ? m.method
                 : static_cast<uint8_t>(settings_.get(Param::METHOD));
  c.cycle_steps =
      static_cast<uint16_t>(m.cycle_steps == 0 ? settings_.get(Param::CYCLE_STEPS)
                                               : clamp_to_spec(Param::CYCLE_STEPS, m.cycle_steps));
  c.wave_size = m.wave_size;
  c.wave_size_param = static_cast<uint8_t>(settings_.get(Param::WAVE_SIZE));
  c.broadcast_repeats = static_cast<uint8_t>(settings_.get(Param::BROADCAST_REPEATS));
  c.phototaxis = m.phototaxis != 0;
  const uint32_t interval_s = m.update_interval_s == 0
                                  ? static_cast<uint32_t>(settings_.get(Param::UPDATE_INTERVAL_S))
                                  : m.update_interval_s;
  c.update_interval_ms = interval_s * 1000u;
  c.round_ms = static_cast<uint32_t>(settings_.get(Param::ROUND_MS));
  coordinator_.start(c, now_ms, radius_at(now_ms), geometry_);
  // Readings for round 0 may follow in the same burst as START, before the next tick, so the
  // round's bookkeeping starts here rather than at the next poll. The record is emptied even
  // when it names this run: a run stopped earlier may have used the same id.
  record_.clear();
  record_run_ = m.run_id;
  record_round_ = 0;
  begin_round_record(0);
  update_servo(now_ms);
}

ParamResult Particle::apply_param(uint8_t param, int32_t value, int32_t *in_force) {
  *in_force = 0;
  if (!settings_.get(param, in_force)) return ParamResult::UNKNOWN_PARAM;
  // Parameters shape the running schedule and the body's stroke: only change them at rest.
  const State s = coordinator_.state();
  if (s != State::IDLE && s != State::DONE) return ParamResult::BUSY;
  const ParamResult result = settings_.set(param, value);
  if (result == ParamResult::OK) *in_force = value;
  refresh_from_settings();
  update_servo(now_ms_, true);
  return result;
}

void Particle::handle_intensity(uint8_t sender, const IntensityMessage &m) {
  if (!coordinator_.running() || m.run_id != coordinator_.run_id()) return;
  const State s = coordinator_.state();
  const uint16_t round = coordinator_.round();
  // A particle whose clock runs a little fast may begin the next round before this one does:
  // keep its readings for that round instead of losing them.
  const bool current = s == State::ESTIMATING && m.round == round;
  const bool next = (s == State::WAITING || s == State::CYCLING || s == State::PAUSED) &&
                    m.round == static_cast<uint16_t>(round + 1);
  if (!current && !next) return;
  use_record(m.run_id, m.round);
  if (!record_.add(sender, m.intensity)) {
    // A 33rd sender in one round: the record is full and this reading is left out of S_n, as
    // the firmware documents (estimation.h). The group size N then counts at most 32.
  }
}

void Particle::use_record(uint8_t run_id, uint16_t round) {
  if (record_run_ == run_id && record_round_ == round) return;
  record_.clear();
  record_run_ = run_id;
  record_round_ = round;
}

void Particle::begin_round_record(uint16_t round) {
  use_record(coordinator_.run_id(), round);
  readings_awaited_ = sampler_.between_readings() ? 1 : 2;
}

void Particle::finish_round() {
  const uint16_t own = readings_awaited_ == 0 ? round_intensity_ : sampler_.intensity();
  readings_awaited_ = 0;
  const bool ours = record_run_ == coordinator_.run_id() && record_round_ == coordinator_.round();
  const uint8_t heard = ours ? record_.count() : 0;
  EstimationParams p;
  p.ref_distance_mm = settings_.get(Param::REF_DISTANCE_MM);
  p.ref_value = settings_.get(Param::REF_VALUE);
  p.diameter_mm = settings_.get(Param::DIAMETER_MM);
  p.count_tolerance = settings_.get(Param::COUNT_TOLERANCE);
  p.groups = settings_.get(Param::GROUPS);
  RoundResult r;
  r.s_n = estimate(coordinator_.method(), own, record_.readings(), heard, p);
  r.group_size = static_cast<uint8_t>(heard + 1);
  r.intensity = own;
  coordinator_.finish_round(r);
}

// ---- servo -------------------------------------------------------------------------------------

void Particle::refresh_from_settings() {
  geometry_.r_min_um = static_cast<uint32_t>(settings_.get(Param::RADIUS_MIN_UM));
  geometry_.r_max_um = static_cast<uint32_t>(settings_.get(Param::RADIUS_MAX_UM));
  const uint8_t gamma0 = static_cast<uint8_t>(Param::SENSOR_GAMMA_0);
  const uint8_t gain0 = static_cast<uint8_t>(Param::SENSOR_GAIN_0);
  for (uint8_t k = 0; k < kSensorCount; ++k) {
    sampler_.set_calibration(k,
                             static_cast<uint16_t>(settings_.get(static_cast<Param>(gamma0 + k))),
                             static_cast<uint16_t>(settings_.get(static_cast<Param>(gain0 + k))));
  }
}

void Particle::handle_servo_hold(const ServoHoldMessage &m, uint32_t now_ms) {
  // Only at rest: a running particle's servo belongs to the wave. A request that cannot be
  // held (a pulse out of range, hold_s = 0) ends any hold instead: the safe side.
  const State s = coordinator_.state();
  const bool resting = s == State::IDLE || s == State::DONE;
  if (!resting || m.hold_s == 0 || m.pulse_us < kServoPulseMinUs || m.pulse_us > kServoPulseMaxUs) {
    end_hold();
    return;
  }
  const uint8_t seconds = m.hold_s < kMaxHoldS ? m.hold_s : kMaxHoldS;
  hold_pulse_us_ = m.pulse_us;
  hold_until_ms_ = now_ms + seconds * 1000UL;
}

uint32_t Particle::radius_at(uint32_t now_ms) const {
  return coordinator_.motion().radius_um(now_ms, geometry_);
}

void Particle::update_servo(uint32_t now_ms, bool table_changed) {
  // The radius only changes at step boundaries, and working it out costs the AVR about a
  // millisecond of 64-bit arithmetic: evaluate once per step, not on every loop pass.
  const Motion &m = coordinator_.motion();
  const uint16_t step = m.step_at(now_ms);
  if (!table_changed && m.kind == servo_kind_ && m.start_ms == servo_start_ms_ &&
      step == servo_step_) {
    return;
  }
  servo_kind_ = m.kind;
  servo_start_ms_ = m.start_ms;
  servo_step_ = step;
  const uint32_t r = m.radius_um(now_ms, geometry_);
  if (r == radius_um_ && !table_changed) return;
  radius_um_ = r;
  uint16_t table[kServoCalPoints];
  settings_.servo_table(table);
  pulse_us_ = pb::servo_pulse_us(r, geometry_, table);
}

// ---- transmitted frames ------------------------------------------------------------------------

void Particle::send(MessageType type, const uint8_t *payload, uint8_t len) {
  uint8_t frame[kMaxPayload + kFrameOverhead];
  const size_t n = encode_frame(static_cast<uint8_t>(type), settings_.id(), seq_, payload, len,
                                frame, sizeof frame);
  if (n == 0 || n > static_cast<size_t>(kTxCapacity - tx_count_)) {
    // A partial frame would only make the base station resynchronise: drop it whole.
    if (tx_dropped_ < 0xFFFF) ++tx_dropped_;
    return;
  }
  for (size_t i = 0; i < n; ++i) {
    tx_[(tx_head_ + tx_count_) % kTxCapacity] = frame[i];
    ++tx_count_;
  }
  ++seq_;
}

void Particle::send_status() {
  // Any STATUS answers a PING still waiting for its slot.
  ping_reply_pending_ = false;
  uint8_t payload[StatusMessage::kPayloadSize];
  send(MessageType::STATUS, payload, status_payload(payload));
}

void Particle::send_intensity() {
  IntensityMessage m;
  m.run_id = coordinator_.run_id();
  m.round = coordinator_.round();
  m.repeat = coordinator_.broadcast_repeat();
  m.intensity = round_intensity_;
  uint8_t payload[IntensityMessage::kPayloadSize];
  send(MessageType::INTENSITY, payload, m.encode(payload));
}

void Particle::schedule_status(uint32_t now_ms) {
  // +-25 % jitter: particles that started together drift apart instead of colliding every time.
  const uint32_t period = static_cast<uint32_t>(settings_.get(Param::STATUS_PERIOD_MS));
  next_status_ms_ = now_ms + period * (75u + rng_.below(51)) / 100u;
}

uint32_t Particle::reply_slot_ms(uint32_t now_ms) {
  // A group of one tells nothing: method A never listens, and a particle that heard nobody may
  // still share the base station with others.
  uint8_t slots = coordinator_.group_size();
  if (slots <= 1) slots = kPingSlotsUnknown;
  if (slots > kPingSlotsMax) slots = kPingSlotsMax;
  return now_ms + static_cast<uint32_t>(rng_.below(slots)) * kPingSlotMs;
}

void Particle::answer_with_status(uint8_t target, uint32_t now_ms) {
  if (target != kBroadcastId) {
    send_status();
    return;
  }
  // A repeated broadcast PING keeps the slot already drawn: the answer is on its way.
  if (ping_reply_pending_) return;
  ping_reply_ms_ = reply_slot_ms(now_ms);
  ping_reply_pending_ = true;
}

void Particle::reply_param(uint8_t target, uint8_t param, ParamResult result, int32_t value,
                           uint32_t now_ms) {
  // One reply can wait at a time: an earlier one still waiting goes out now rather than be lost.
  if (param_reply_pending_) send_param_reply();
  param_reply_param_ = param;
  param_reply_result_ = static_cast<uint8_t>(result);
  param_reply_value_ = value;
  param_reply_pending_ = true;
  if (target == kBroadcastId) {
    param_reply_ms_ = reply_slot_ms(now_ms);
  } else {
    send_param_reply();
  }
}

void Particle::send_param_reply() {
  param_reply_pending_ = false;
  ParamValueMessage m;
  m.param = param_reply_param_;
  m.result = param_reply_result_;
  m.value = param_reply_value_;
  uint8_t payload[ParamValueMessage::kPayloadSize];
  send(MessageType::PARAM_VALUE, payload, m.encode(payload));
}

}  // namespace pb
