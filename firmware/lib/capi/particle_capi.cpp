// PC-side implementation of particle_capi.h: a RAM EEPROM, a simulated ADC and the real Particle.
#include "particle_capi.h"

#include <string.h>

#include <new>

#include "estimation.h"
#include "frame.h"
#include "light_sampler.h"
#include "particle.h"
#include "protocol_gen.h"

static_assert(PB_MAX_FRAME == pb::kMaxPayload + pb::kFrameOverhead, "frame size in the C API");

namespace {

// The ATmega32U4's ADC at the firmware's prescaler: one conversion per 125 us, 8 per ms.
const uint8_t kConversionsPerMs = 8;
// A call that jumps further ahead than this skips the ADC for the excess (nobody simulates
// hours of photocell samples): the logic itself still sees every transition.
const uint32_t kMaxSimulatedMs = 600000;

class RamStorage : public pb::Storage {
 public:
  RamStorage() { memset(bytes_, 0xFF, sizeof bytes_); }
  uint8_t read(uint16_t address) const { return address < PB_EEPROM_SIZE ? bytes_[address] : 0xFF; }
  void write(uint16_t address, uint8_t value) {
    if (address < PB_EEPROM_SIZE) bytes_[address] = value;
  }
  uint8_t *bytes() { return bytes_; }
  const uint8_t *bytes() const { return bytes_; }

 private:
  uint8_t bytes_[PB_EEPROM_SIZE];
};

}  // namespace

struct pb_particle {
  pb_particle(uint8_t reset_cause, uint32_t rng_seed)
      : particle(storage, reset_cause, rng_seed), now_ms(0) {
    memset(adc, 0, sizeof adc);
  }

  RamStorage storage;
  pb::Particle particle;
  uint16_t adc[PB_SENSOR_COUNT];
  uint32_t now_ms;
};

extern "C" {

pb_particle *pb_particle_new(const uint8_t *eeprom, size_t eeprom_len, uint8_t reset_cause,
                             uint32_t rng_seed) {
  pb_particle *p = new (std::nothrow) pb_particle(reset_cause, rng_seed);
  if (p == NULL) return NULL;
  if (eeprom != NULL) {
    memcpy(p->storage.bytes(), eeprom, eeprom_len < PB_EEPROM_SIZE ? eeprom_len : PB_EEPROM_SIZE);
  }
  p->particle.begin(0);
  return p;
}

void pb_particle_free(pb_particle *particle) {
  delete particle;
}

void pb_particle_set_adc(pb_particle *particle, const uint16_t adc[PB_SENSOR_COUNT]) {
  for (uint8_t k = 0; k < PB_SENSOR_COUNT; ++k) particle->adc[k] = adc[k] > 1023 ? 1023 : adc[k];
}

void pb_particle_receive(pb_particle *particle, const uint8_t *bytes, size_t count) {
  for (size_t i = 0; i < count; ++i) particle->particle.on_rx_byte(bytes[i], particle->now_ms);
}

void pb_particle_tick(pb_particle *particle, uint32_t now_ms) {
  pb::Particle &p = particle->particle;
  uint32_t elapsed = now_ms - particle->now_ms;
  if (elapsed > kMaxSimulatedMs) {
    particle->now_ms = now_ms - kMaxSimulatedMs;
    p.tick(particle->now_ms);
    elapsed = kMaxSimulatedMs;
  }
  // Millisecond by millisecond, conversions first, as the main loop interleaves them: every
  // reading and every 20 ms step lands where it would on the particle.
  for (uint32_t i = 0; i < elapsed; ++i) {
    for (uint8_t c = 0; c < kConversionsPerMs; ++c) {
      const uint8_t sensor = p.next_sensor();
      p.on_adc_sample(sensor, particle->adc[sensor]);
    }
    ++particle->now_ms;
    p.tick(particle->now_ms);
  }
  if (elapsed == 0) p.tick(now_ms);
}

void pb_particles_tick(pb_particle *const *particles, size_t count, uint32_t now_ms,
                       uint32_t *radius_um, uint8_t *tx_waiting) {
  for (size_t i = 0; i < count; ++i) {
    pb_particle_tick(particles[i], now_ms);
    radius_um[i] = particles[i]->particle.radius_um();
    tx_waiting[i] = particles[i]->particle.tx_pending() > 0 ? 1 : 0;
  }
}

size_t pb_particle_transmit(pb_particle *particle, uint8_t *out, size_t capacity) {
  return particle->particle.take_tx(out, capacity);
}

uint8_t pb_inter_frame_gap_ms(void) {
  return pb::Particle::kInterFrameGapMs;
}

uint8_t pb_particle_id(const pb_particle *particle) {
  return particle->particle.id();
}

uint16_t pb_particle_servo_pulse_us(const pb_particle *particle) {
  return particle->particle.servo_pulse_us();
}

uint32_t pb_particle_radius_um(const pb_particle *particle) {
  return particle->particle.radius_um();
}

size_t pb_particle_status_payload(const pb_particle *particle, uint8_t *out, size_t capacity) {
  uint8_t payload[pb::StatusMessage::kPayloadSize];
  const uint8_t n = particle->particle.status_payload(payload);
  if (capacity < n) return 0;
  memcpy(out, payload, n);
  return n;
}

size_t pb_particle_eeprom(const pb_particle *particle, uint8_t *out, size_t capacity) {
  const size_t n = capacity < PB_EEPROM_SIZE ? capacity : PB_EEPROM_SIZE;
  memcpy(out, particle->storage.bytes(), n);
  return n;
}

uint32_t pb_definition_hash(void) {
  return pb::kDefinitionHash;
}

uint16_t pb_calibrated_reading(uint16_t raw, uint16_t gamma_milli, uint16_t gain_milli) {
  return pb::calibrated_reading(raw, pb::sensor_calibration(gamma_milli, gain_milli));
}

uint8_t pb_estimate(uint8_t method, uint16_t own_intensity, const uint16_t *others,
                    size_t others_count, int32_t ref_distance_mm, int32_t ref_value,
                    int32_t diameter_mm, int32_t count_tolerance, int32_t groups) {
  pb::EstimationParams p;
  p.ref_distance_mm = ref_distance_mm;
  p.ref_value = ref_value;
  p.diameter_mm = diameter_mm;
  p.count_tolerance = count_tolerance;
  p.groups = groups;
  if (others == NULL) others_count = 0;
  return pb::estimate(method, own_intensity, others, others_count, p);
}

size_t pb_encode_frame(uint8_t type, uint8_t sender, uint8_t seq, const uint8_t *payload,
                       size_t payload_len, uint8_t *out, size_t capacity) {
  if (payload_len > pb::kMaxPayload) return 0;
  return pb::encode_frame(type, sender, seq, payload, static_cast<uint8_t>(payload_len), out,
                          capacity);
}

size_t pb_parse_stream(const uint8_t *input, size_t input_len, uint8_t *out, size_t capacity,
                       uint16_t counters[4]) {
  pb::FrameParser parser;
  size_t written = 0;
  // Copies the frame the parser just accepted into out; false when it does not fit.
  auto emit = [&](const pb::Frame &f) {
    const size_t need = 4u + f.length;
    if (written + need > capacity) return false;
    out[written++] = f.type;
    out[written++] = f.sender;
    out[written++] = f.seq;
    out[written++] = f.length;
    memcpy(out + written, f.payload, f.length);
    written += f.length;
    return true;
  };
  bool fits = true;
  for (size_t i = 0; i < input_len && fits; ++i) {
    if (parser.push(input[i])) fits = emit(parser.frame());
  }
  // The end of the input is treated like the particle's idle timeout: a partial frame counts as
  // truncated, and any frame hidden in its bytes is still found.
  while (fits && parser.timeout()) fits = emit(parser.frame());
  if (counters != NULL) {
    const pb::ParserCounters &c = parser.counters();
    counters[0] = c.frames;
    counters[1] = c.bad_crc;
    counters[2] = c.bad_length;
    counters[3] = c.skipped_bytes;
  }
  return written;
}

uint16_t pb_servo_step_ms(void) {
  return pb::kStepMs;
}

uint16_t pb_adc_full_scale(void) {
  return pb::kAdcMax;
}

uint8_t pb_s_n_max(void) {
  return pb::kMaxSn;
}

void pb_plan_epoch(uint8_t method, uint16_t cycle_steps, uint8_t wave_size, uint8_t wave_size_param,
                   uint32_t update_interval_ms, uint32_t round_ms, uint8_t s_n, uint8_t group_size,
                   uint32_t out[3]) {
  pb::RunConfig c;
  c.run_id = 0;
  c.method = method;
  c.cycle_steps = cycle_steps;
  c.wave_size = wave_size;
  c.wave_size_param = wave_size_param;
  c.broadcast_repeats = 1;
  c.phototaxis = false;
  c.update_interval_ms = update_interval_ms;
  c.round_ms = round_ms;
  const pb::EpochPlan plan = pb::plan_epoch(c, s_n, group_size);
  out[0] = plan.first_cycle_ms;
  out[1] = plan.pause_ms;
  out[2] = plan.epoch_ms;
}

size_t pb_settings_image(uint8_t id, const uint8_t *params, const int32_t *values, size_t count,
                         uint8_t *out, size_t capacity, size_t *refused, uint8_t *result) {
  if (capacity < PB_EEPROM_SIZE) return 0;
  RamStorage storage;
  pb::Settings settings(storage);
  (void)settings.load();  // a blank chip: the defaults and the unassigned id
  if (!settings.set_id(id)) {
    if (refused != NULL) *refused = count;
    return 0;
  }
  for (size_t i = 0; i < count; ++i) {
    const pb::ParamResult r = settings.set(params[i], values[i]);
    if (r != pb::ParamResult::OK) {
      if (refused != NULL) *refused = i;
      if (result != NULL) *result = static_cast<uint8_t>(r);
      return 0;
    }
  }
  memcpy(out, storage.bytes(), PB_EEPROM_SIZE);
  return PB_EEPROM_SIZE;
}

uint16_t pb_frame_timeout_ms(void) {
  return pb::kFrameTimeoutMs;
}

uint16_t pb_ping_slot_ms(void) {
  return pb::Particle::kPingSlotMs;
}

uint8_t pb_ping_slots_unknown(void) {
  return pb::Particle::kPingSlotsUnknown;
}

uint8_t pb_servo_cal_points(void) {
  return pb::kServoCalPoints;
}

uint16_t pb_servo_pulse_min_us(void) {
  return pb::kServoPulseMinUs;
}

uint16_t pb_servo_pulse_max_us(void) {
  return pb::kServoPulseMaxUs;
}

}  // extern "C"
