// Radio protocol of the particles: constants, enums and message structs with their encoders.
// Generated from shared/protocol.toml by tools/gen_protocol.py; do not edit.
// Definition hash 0xDCF5A94F (kDefinitionHash, sent in every STATUS).
#ifndef PARTICLEBOT_PROTOCOL_GEN_H
#define PARTICLEBOT_PROTOCOL_GEN_H

#include <stdint.h>

#define PB_PROTOCOL_GENERATOR_VERSION 1
// Hand-written code that relies on this header's shape defines the generator version it was
// written against (frame.h does); a header from another generator stops the build here.
#if defined(PB_PROTOCOL_EXPECTED_GENERATOR_VERSION) && \
    PB_PROTOCOL_EXPECTED_GENERATOR_VERSION != PB_PROTOCOL_GENERATOR_VERSION
#error "Regenerate this file with tools/gen_protocol.py (make generate)"
#endif

namespace pb {

const uint32_t kDefinitionHash = 0xDCF5A94FUL;
const uint8_t kSync0 = 0xA5;
const uint8_t kSync1 = 0x5A;
// Payload bytes at most; LEN counts payload bytes only.
const uint8_t kMaxPayload = 48;
// Sync (2), LEN, TYPE, SENDER, SEQ and CRC (2) around the payload.
const uint8_t kFrameOverhead = 8;
const uint8_t kBaseStationId = 0;
const uint8_t kBroadcastId = 255;
// Reported by a particle whose EEPROM holds no id yet.
const uint8_t kUnassignedId = 254;

// What a particle is doing; reported in STATUS.
enum class State : uint8_t {
  // Contracted and waiting for START.
  IDLE = 0,
  // Measuring light and exchanging intensities to estimate S_n.
  ESTIMATING = 1,
  // Waiting out the initial delay t_I = (S_n - 1) * T / 2 after the common start.
  WAITING = 2,
  // Running one expansion-contraction cycle of period T.
  CYCLING = 3,
  // Resting t_p between cycles.
  PAUSED = 4,
  // Moving smoothly back to the contracted state after STOP.
  STOPPING = 5,
  // Phototaxis finished: the measured intensity stopped increasing.
  DONE = 6,
  // Wiggling so a person can see which particle this is.
  IDENTIFYING = 7,
};

// Position-estimation method of SI section S4.
enum class Method : uint8_t {
  // (A) eqs. 14-16 from a reference distance and intensity; no communication.
  DIRECT = 0,
  // (B) eqs. 17-18 from the group's V_max and V_min.
  LINEAR = 1,
  // (C) eqs. 29-30 from the group's V_max and V_min.
  NONLINEAR = 2,
  // (D) Algorithm 4: count distinct stronger intensity levels.
  COUNTING = 3,
};

// Parameters settable with SET_PARAM and persisted in EEPROM.
enum class Param : uint8_t {
  // Servo steps of 20 ms per expansion-contraction cycle (75, 150, 300 in the paper).
  CYCLE_STEPS = 1,
  // N of eq. 3 used when START leaves it automatic and no group is known; pause t_p = (N - 1) * T /
  // 2.
  WAVE_SIZE = 2,
  // Seconds between re-estimations of S_n (the paper used 120-300).
  UPDATE_INTERVAL_S = 3,
  // Default estimation method when START does not name one (enum method).
  METHOD = 4,
  // Method A: r_x, distance of the reference point to the lamp.
  REF_DISTANCE_MM = 5,
  // Method A: V_x, intensity reading at the reference point.
  REF_VALUE = 6,
  // D, the contracted particle diameter used to turn distance into S_n.
  DIAMETER_MM = 7,
  // Method D: readings closer than this count as one level (the paper used 10).
  COUNT_TOLERANCE = 8,
  // Intensity broadcasts per particle per estimation round (the paper used 5).
  BROADCAST_REPEATS = 9,
  // Methods B and C: N_w, number of groups; 0 means one group per particle heard.
  GROUPS = 10,
  // Length of one estimation round; every particle's common start follows it.
  ROUND_MS = 11,
  // Interval between STATUS frames (each is jittered so particles do not collide).
  STATUS_PERIOD_MS = 12,
  // Contracted radius R_min in micrometres.
  RADIUS_MIN_UM = 13,
  // Fully expanded radius in micrometres (R_min + Delta R).
  RADIUS_MAX_UM = 14,
  // Servo pulse (us) at calibration point 0 of 9 (R_min).
  SERVO_CAL_0 = 32,
  // Servo pulse (us) at calibration point 1 of 9.
  SERVO_CAL_1 = 33,
  // Servo pulse (us) at calibration point 2 of 9.
  SERVO_CAL_2 = 34,
  // Servo pulse (us) at calibration point 3 of 9.
  SERVO_CAL_3 = 35,
  // Servo pulse (us) at calibration point 4 of 9.
  SERVO_CAL_4 = 36,
  // Servo pulse (us) at calibration point 5 of 9.
  SERVO_CAL_5 = 37,
  // Servo pulse (us) at calibration point 6 of 9.
  SERVO_CAL_6 = 38,
  // Servo pulse (us) at calibration point 7 of 9.
  SERVO_CAL_7 = 39,
  // Servo pulse (us) at calibration point 8 of 9 (fully expanded).
  SERVO_CAL_8 = 40,
};

// Outcome of SET_PARAM / GET_PARAM, reported in PARAM_VALUE.
enum class ParamResult : uint8_t {
  // Applied (SET) or read (GET).
  OK = 0,
  // No parameter has that number.
  UNKNOWN_PARAM = 1,
  // Value outside the parameter's min..max, or it would make the servo table non-monotonic.
  OUT_OF_RANGE = 2,
  // Refused while running; STOP first.
  BUSY = 3,
};

// Message types, the TYPE byte of a frame.
enum class MessageType : uint8_t {
  START = 0x01,
  STOP = 0x02,
  SET_PARAM = 0x03,
  GET_PARAM = 0x04,
  PING = 0x05,
  IDENTIFY = 0x06,
  SET_ID = 0x07,
  STATUS = 0x20,
  INTENSITY = 0x21,
  PARAM_VALUE = 0x22,
};

// Default and accepted range of one parameter.
struct ParamSpec {
  int32_t default_value;
  int32_t min;
  int32_t max;
};

const uint8_t kParamCount = 23;

namespace detail {
inline bool set_param_spec(ParamSpec *out, int32_t default_value, int32_t min, int32_t max) {
  if (out != 0) {
    out->default_value = default_value;
    out->min = min;
    out->max = max;
  }
  return true;
}
}  // namespace detail

// Looks a parameter up in a switch, so the table lives in flash, not RAM. False for an
// unknown id; out may be null to test whether an id exists.
inline bool param_spec(uint8_t param_id, ParamSpec *out) {
  switch (param_id) {
    case 1:  // CYCLE_STEPS
      return detail::set_param_spec(out, 150, 10, 3000);
    case 2:  // WAVE_SIZE
      return detail::set_param_spec(out, 5, 1, 64);
    case 3:  // UPDATE_INTERVAL_S
      return detail::set_param_spec(out, 180, 10, 3600);
    case 4:  // METHOD
      return detail::set_param_spec(out, 3, 0, 3);
    case 5:  // REF_DISTANCE_MM
      return detail::set_param_spec(out, 280, 10, 10000);
    case 6:  // REF_VALUE
      return detail::set_param_spec(out, 980, 1, 1022);
    case 7:  // DIAMETER_MM
      return detail::set_param_spec(out, 155, 10, 1000);
    case 8:  // COUNT_TOLERANCE
      return detail::set_param_spec(out, 10, 0, 200);
    case 9:  // BROADCAST_REPEATS
      return detail::set_param_spec(out, 5, 1, 20);
    case 10:  // GROUPS
      return detail::set_param_spec(out, 0, 0, 64);
    case 11:  // ROUND_MS
      return detail::set_param_spec(out, 3000, 200, 60000L);
    case 12:  // STATUS_PERIOD_MS
      return detail::set_param_spec(out, 2000, 200, 60000L);
    case 13:  // RADIUS_MIN_UM
      return detail::set_param_spec(out, 77500L, 50000L, 150000L);
    case 14:  // RADIUS_MAX_UM
      return detail::set_param_spec(out, 117500L, 50000L, 150000L);
    case 32:  // SERVO_CAL_0
      return detail::set_param_spec(out, 1000, 500, 2500);
    case 33:  // SERVO_CAL_1
      return detail::set_param_spec(out, 1100, 500, 2500);
    case 34:  // SERVO_CAL_2
      return detail::set_param_spec(out, 1195, 500, 2500);
    case 35:  // SERVO_CAL_3
      return detail::set_param_spec(out, 1285, 500, 2500);
    case 36:  // SERVO_CAL_4
      return detail::set_param_spec(out, 1370, 500, 2500);
    case 37:  // SERVO_CAL_5
      return detail::set_param_spec(out, 1455, 500, 2500);
    case 38:  // SERVO_CAL_6
      return detail::set_param_spec(out, 1545, 500, 2500);
    case 39:  // SERVO_CAL_7
      return detail::set_param_spec(out, 1640, 500, 2500);
    case 40:  // SERVO_CAL_8
      return detail::set_param_spec(out, 1750, 500, 2500);
    default:
      return false;
  }
}

// Payload size of a message type; false for a type this definition does not know.
inline bool message_payload_size(uint8_t type, uint8_t *size) {
  uint8_t bytes;
  switch (type) {
    case 0x01:  // START
      bytes = 8;
      break;
    case 0x02:  // STOP
      bytes = 0;
      break;
    case 0x03:  // SET_PARAM
      bytes = 6;
      break;
    case 0x04:  // GET_PARAM
      bytes = 2;
      break;
    case 0x05:  // PING
      bytes = 1;
      break;
    case 0x06:  // IDENTIFY
      bytes = 1;
      break;
    case 0x07:  // SET_ID
      bytes = 2;
      break;
    case 0x20:  // STATUS
      bytes = 44;
      break;
    case 0x21:  // INTENSITY
      bytes = 6;
      break;
    case 0x22:  // PARAM_VALUE
      bytes = 6;
      break;
    default:
      return false;
  }
  if (size != 0) *size = bytes;
  return true;
}

// Little-endian field access that never depends on the host's byte order or alignment.
namespace wire {
inline void put_u8(uint8_t *out, uint8_t value) {
  out[0] = value;
}
inline void put_u16(uint8_t *out, uint16_t value) {
  out[0] = static_cast<uint8_t>(value);
  out[1] = static_cast<uint8_t>(value >> 8);
}
inline void put_u32(uint8_t *out, uint32_t value) {
  out[0] = static_cast<uint8_t>(value);
  out[1] = static_cast<uint8_t>(value >> 8);
  out[2] = static_cast<uint8_t>(value >> 16);
  out[3] = static_cast<uint8_t>(value >> 24);
}
inline void put_i8(uint8_t *out, int8_t value) {
  put_u8(out, static_cast<uint8_t>(value));
}
inline void put_i16(uint8_t *out, int16_t value) {
  put_u16(out, static_cast<uint16_t>(value));
}
inline void put_i32(uint8_t *out, int32_t value) {
  put_u32(out, static_cast<uint32_t>(value));
}
inline uint8_t get_u8(const uint8_t *in) {
  return in[0];
}
// The casts come before the shifts: AVR's int is 16 bits wide.
inline uint16_t get_u16(const uint8_t *in) {
  return static_cast<uint16_t>(in[0] | static_cast<uint16_t>(static_cast<uint16_t>(in[1]) << 8));
}
inline uint32_t get_u32(const uint8_t *in) {
  return static_cast<uint32_t>(in[0]) | (static_cast<uint32_t>(in[1]) << 8) |
         (static_cast<uint32_t>(in[2]) << 16) | (static_cast<uint32_t>(in[3]) << 24);
}
inline int8_t get_i8(const uint8_t *in) {
  return static_cast<int8_t>(in[0]);
}
inline int16_t get_i16(const uint8_t *in) {
  return static_cast<int16_t>(get_u16(in));
}
inline int32_t get_i32(const uint8_t *in) {
  return static_cast<int32_t>(get_u32(in));
}
}  // namespace wire

// START (from base): Begin coordinated locomotion. START itself is the common start: each particle
// runs one estimation round of ROUND_MS, then waits t_I and cycles. A repeated START with the same
// run_id is ignored, so the console may resend it.
struct StartMessage {
  static const MessageType kType = MessageType::START;
  static const uint8_t kPayloadSize = 8;

  // Distinguishes runs; a particle ignores a START of the run it is already in.
  uint8_t run_id;
  // Estimation method. (enum Method)
  uint8_t method;
  // Steps of 20 ms per cycle, so T = cycle_steps * 20 ms; 0 keeps the stored CYCLE_STEPS.
  uint16_t cycle_steps;
  // N of eq. 3; 0 means automatic (particles heard, else WAVE_SIZE).
  uint8_t wave_size;
  // Seconds between re-estimations; 0 keeps the stored UPDATE_INTERVAL_S.
  uint16_t update_interval_s;
  // 1: Algorithm 3, stop by itself when the intensity stops increasing; 0: run until STOP.
  uint8_t phototaxis;

  // Writes kPayloadSize bytes, little-endian, and returns kPayloadSize.
  uint8_t encode(uint8_t *out) const {
    wire::put_u8(out + 0, run_id);
    wire::put_u8(out + 1, method);
    wire::put_u16(out + 2, cycle_steps);
    wire::put_u8(out + 4, wave_size);
    wire::put_u16(out + 5, update_interval_s);
    wire::put_u8(out + 7, phototaxis);
    return kPayloadSize;
  }
  // False, leaving the fields untouched, unless len == kPayloadSize.
  bool decode(const uint8_t *in, uint8_t len) {
    if (len != kPayloadSize) return false;
    run_id = wire::get_u8(in + 0);
    method = wire::get_u8(in + 1);
    cycle_steps = wire::get_u16(in + 2);
    wave_size = wire::get_u8(in + 4);
    update_interval_s = wire::get_u16(in + 5);
    phototaxis = wire::get_u8(in + 7);
    return true;
  }
};

// STOP (from base): Stop at once: within one servo step the particle starts moving smoothly to the
// contracted state and reports STOPPING, then IDLE.
struct StopMessage {
  static const MessageType kType = MessageType::STOP;
  static const uint8_t kPayloadSize = 0;

  // Writes kPayloadSize bytes, little-endian, and returns kPayloadSize.
  uint8_t encode(uint8_t * /*out*/) const { return kPayloadSize; }
  // False, leaving the fields untouched, unless len == kPayloadSize.
  bool decode(const uint8_t * /*in*/, uint8_t len) { return len == kPayloadSize; }
};

// SET_PARAM (from base): Set one parameter and persist it in EEPROM. Answered by PARAM_VALUE.
struct SetParamMessage {
  static const MessageType kType = MessageType::SET_PARAM;
  static const uint8_t kPayloadSize = 6;

  // Particle id, or broadcast_id for all.
  uint8_t target;
  // Which parameter. (enum Param)
  uint8_t param;
  // New value.
  int32_t value;

  // Writes kPayloadSize bytes, little-endian, and returns kPayloadSize.
  uint8_t encode(uint8_t *out) const {
    wire::put_u8(out + 0, target);
    wire::put_u8(out + 1, param);
    wire::put_i32(out + 2, value);
    return kPayloadSize;
  }
  // False, leaving the fields untouched, unless len == kPayloadSize.
  bool decode(const uint8_t *in, uint8_t len) {
    if (len != kPayloadSize) return false;
    target = wire::get_u8(in + 0);
    param = wire::get_u8(in + 1);
    value = wire::get_i32(in + 2);
    return true;
  }
};

// GET_PARAM (from base): Read one parameter. Answered by PARAM_VALUE.
struct GetParamMessage {
  static const MessageType kType = MessageType::GET_PARAM;
  static const uint8_t kPayloadSize = 2;

  // Particle id, or broadcast_id for all.
  uint8_t target;
  // Which parameter. (enum Param)
  uint8_t param;

  // Writes kPayloadSize bytes, little-endian, and returns kPayloadSize.
  uint8_t encode(uint8_t *out) const {
    wire::put_u8(out + 0, target);
    wire::put_u8(out + 1, param);
    return kPayloadSize;
  }
  // False, leaving the fields untouched, unless len == kPayloadSize.
  bool decode(const uint8_t *in, uint8_t len) {
    if (len != kPayloadSize) return false;
    target = wire::get_u8(in + 0);
    param = wire::get_u8(in + 1);
    return true;
  }
};

// PING (from base): Ask for a STATUS frame now.
struct PingMessage {
  static const MessageType kType = MessageType::PING;
  static const uint8_t kPayloadSize = 1;

  // Particle id, or broadcast_id for all.
  uint8_t target;

  // Writes kPayloadSize bytes, little-endian, and returns kPayloadSize.
  uint8_t encode(uint8_t *out) const {
    wire::put_u8(out + 0, target);
    return kPayloadSize;
  }
  // False, leaving the fields untouched, unless len == kPayloadSize.
  bool decode(const uint8_t *in, uint8_t len) {
    if (len != kPayloadSize) return false;
    target = wire::get_u8(in + 0);
    return true;
  }
};

// IDENTIFY (from base): Make an idle particle wiggle three times so a person can find it; it
// answers with STATUS.
struct IdentifyMessage {
  static const MessageType kType = MessageType::IDENTIFY;
  static const uint8_t kPayloadSize = 1;

  // Particle id, or broadcast_id for all.
  uint8_t target;

  // Writes kPayloadSize bytes, little-endian, and returns kPayloadSize.
  uint8_t encode(uint8_t *out) const {
    wire::put_u8(out + 0, target);
    return kPayloadSize;
  }
  // False, leaving the fields untouched, unless len == kPayloadSize.
  bool decode(const uint8_t *in, uint8_t len) {
    if (len != kPayloadSize) return false;
    target = wire::get_u8(in + 0);
    return true;
  }
};

// SET_ID (from base): Give one particle a new id, stored in EEPROM; it answers with STATUS from the
// new id.
struct SetIdMessage {
  static const MessageType kType = MessageType::SET_ID;
  static const uint8_t kPayloadSize = 2;

  // Current id of the particle to rename (never broadcast_id).
  uint8_t target;
  // New id, 1..253.
  uint8_t new_id;

  // Writes kPayloadSize bytes, little-endian, and returns kPayloadSize.
  uint8_t encode(uint8_t *out) const {
    wire::put_u8(out + 0, target);
    wire::put_u8(out + 1, new_id);
    return kPayloadSize;
  }
  // False, leaving the fields untouched, unless len == kPayloadSize.
  bool decode(const uint8_t *in, uint8_t len) {
    if (len != kPayloadSize) return false;
    target = wire::get_u8(in + 0);
    new_id = wire::get_u8(in + 1);
    return true;
  }
};

// STATUS (from particle): Periodic report of a particle's state, every STATUS_PERIOD_MS and on
// PING.
struct StatusMessage {
  static const MessageType kType = MessageType::STATUS;
  static const uint8_t kPayloadSize = 44;

  // What the particle is doing. (enum State)
  uint8_t state;
  // Estimation method of the current or last run. (enum Method)
  uint8_t method;
  // run_id of the current or last START.
  uint8_t run_id;
  // Actuation sequence index S_n (1 = nearest the light); 0 before the first estimate.
  uint8_t s_n;
  // Particles heard in the last estimation round, itself included.
  uint8_t group_size;
  // Bit k set: sensor k is stuck at 0 or 1023 and left out of the intensity.
  uint8_t sensor_faults;
  // Mean of the healthy sensors' 50-sample averages (0..1023).
  uint16_t intensity;
  // Each sensor's 50-sample average (0..1023), A0..A5.
  uint16_t sensors[6];
  // Position within the current expansion-contraction cycle in 1/1000 of T; 0 outside a cycle.
  uint16_t cycle_phase;
  // Radius commanded now, micrometres.
  uint32_t radius_um;
  // Milliseconds since reset (wraps after 49 days).
  uint32_t uptime_ms;
  // Hash of this protocol definition the firmware was built from.
  uint32_t definition_hash;
  // Frames received intact (saturates at 65535).
  uint16_t rx_frames;
  // Frames dropped for a CRC mismatch.
  uint16_t rx_bad_crc;
  // Frames dropped for a length over max_payload or a truncated body.
  uint16_t rx_bad_length;
  // Bytes skipped while resynchronising on the sync marker.
  uint16_t rx_skipped_bytes;
  // Resets counted in EEPROM (power-on, watchdog, ...), saturating.
  uint8_t resets;
  // MCUSR at the last reset: bit 0 power-on, 1 external, 2 brown-out, 3 watchdog.
  uint8_t last_reset_cause;

  // Writes kPayloadSize bytes, little-endian, and returns kPayloadSize.
  uint8_t encode(uint8_t *out) const {
    wire::put_u8(out + 0, state);
    wire::put_u8(out + 1, method);
    wire::put_u8(out + 2, run_id);
    wire::put_u8(out + 3, s_n);
    wire::put_u8(out + 4, group_size);
    wire::put_u8(out + 5, sensor_faults);
    wire::put_u16(out + 6, intensity);
    for (uint8_t i = 0; i < 6; ++i) {
      wire::put_u16(out + 8 + 2 * i, sensors[i]);
    }
    wire::put_u16(out + 20, cycle_phase);
    wire::put_u32(out + 22, radius_um);
    wire::put_u32(out + 26, uptime_ms);
    wire::put_u32(out + 30, definition_hash);
    wire::put_u16(out + 34, rx_frames);
    wire::put_u16(out + 36, rx_bad_crc);
    wire::put_u16(out + 38, rx_bad_length);
    wire::put_u16(out + 40, rx_skipped_bytes);
    wire::put_u8(out + 42, resets);
    wire::put_u8(out + 43, last_reset_cause);
    return kPayloadSize;
  }
  // False, leaving the fields untouched, unless len == kPayloadSize.
  bool decode(const uint8_t *in, uint8_t len) {
    if (len != kPayloadSize) return false;
    state = wire::get_u8(in + 0);
    method = wire::get_u8(in + 1);
    run_id = wire::get_u8(in + 2);
    s_n = wire::get_u8(in + 3);
    group_size = wire::get_u8(in + 4);
    sensor_faults = wire::get_u8(in + 5);
    intensity = wire::get_u16(in + 6);
    for (uint8_t i = 0; i < 6; ++i) {
      sensors[i] = wire::get_u16(in + 8 + 2 * i);
    }
    cycle_phase = wire::get_u16(in + 20);
    radius_um = wire::get_u32(in + 22);
    uptime_ms = wire::get_u32(in + 26);
    definition_hash = wire::get_u32(in + 30);
    rx_frames = wire::get_u16(in + 34);
    rx_bad_crc = wire::get_u16(in + 36);
    rx_bad_length = wire::get_u16(in + 38);
    rx_skipped_bytes = wire::get_u16(in + 40);
    resets = wire::get_u8(in + 42);
    last_reset_cause = wire::get_u8(in + 43);
    return true;
  }
};

// INTENSITY (from particle): A particle's light reading, broadcast BROADCAST_REPEATS times per
// estimation round for methods B-D.
struct IntensityMessage {
  static const MessageType kType = MessageType::INTENSITY;
  static const uint8_t kPayloadSize = 6;

  // run_id of the START this round belongs to.
  uint8_t run_id;
  // Estimation round number within the run, 0 first.
  uint16_t round;
  // Which of the BROADCAST_REPEATS copies this is, 0 first.
  uint8_t repeat;
  // The sender's intensity for this round (0..1023).
  uint16_t intensity;

  // Writes kPayloadSize bytes, little-endian, and returns kPayloadSize.
  uint8_t encode(uint8_t *out) const {
    wire::put_u8(out + 0, run_id);
    wire::put_u16(out + 1, round);
    wire::put_u8(out + 3, repeat);
    wire::put_u16(out + 4, intensity);
    return kPayloadSize;
  }
  // False, leaving the fields untouched, unless len == kPayloadSize.
  bool decode(const uint8_t *in, uint8_t len) {
    if (len != kPayloadSize) return false;
    run_id = wire::get_u8(in + 0);
    round = wire::get_u16(in + 1);
    repeat = wire::get_u8(in + 3);
    intensity = wire::get_u16(in + 4);
    return true;
  }
};

// PARAM_VALUE (from particle): Answer to SET_PARAM or GET_PARAM.
struct ParamValueMessage {
  static const MessageType kType = MessageType::PARAM_VALUE;
  static const uint8_t kPayloadSize = 6;

  // Which parameter. (enum Param)
  uint8_t param;
  // Outcome. (enum ParamResult)
  uint8_t result;
  // The value now in force (unchanged on failure).
  int32_t value;

  // Writes kPayloadSize bytes, little-endian, and returns kPayloadSize.
  uint8_t encode(uint8_t *out) const {
    wire::put_u8(out + 0, param);
    wire::put_u8(out + 1, result);
    wire::put_i32(out + 2, value);
    return kPayloadSize;
  }
  // False, leaving the fields untouched, unless len == kPayloadSize.
  bool decode(const uint8_t *in, uint8_t len) {
    if (len != kPayloadSize) return false;
    param = wire::get_u8(in + 0);
    result = wire::get_u8(in + 1);
    value = wire::get_i32(in + 2);
    return true;
  }
};

#ifdef PB_PROTOCOL_DEFINE_STATICS
// Out-of-class definitions, emitted once (by frame.cpp), so that binding kType or kPayloadSize
// to a reference (as test macros do) still links.
const MessageType StartMessage::kType;
const uint8_t StartMessage::kPayloadSize;
const MessageType StopMessage::kType;
const uint8_t StopMessage::kPayloadSize;
const MessageType SetParamMessage::kType;
const uint8_t SetParamMessage::kPayloadSize;
const MessageType GetParamMessage::kType;
const uint8_t GetParamMessage::kPayloadSize;
const MessageType PingMessage::kType;
const uint8_t PingMessage::kPayloadSize;
const MessageType IdentifyMessage::kType;
const uint8_t IdentifyMessage::kPayloadSize;
const MessageType SetIdMessage::kType;
const uint8_t SetIdMessage::kPayloadSize;
const MessageType StatusMessage::kType;
const uint8_t StatusMessage::kPayloadSize;
const MessageType IntensityMessage::kType;
const uint8_t IntensityMessage::kPayloadSize;
const MessageType ParamValueMessage::kType;
const uint8_t ParamValueMessage::kPayloadSize;
#endif

}  // namespace pb

#endif  // PARTICLEBOT_PROTOCOL_GEN_H
