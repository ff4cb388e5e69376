// Radio protocol of the particles: constants, enums and message structs with their encoders.
// Generated from shared/protocol.toml by tools/gen_protocol.py; do not edit.
// Definition hash 0xF1AAC96B (kDefinitionHash, sent in every STATUS).
#ifndef PARTICLEBOT_PROTOCOL_GEN_H
#define PARTICLEBOT_PROTOCOL_GEN_H

#include <stdint.h>
#include <string.h>

#ifdef __AVR__
#include <avr/pgmspace.h>
#endif

#define PB_PROTOCOL_GENERATOR_VERSION 2
// Hand-written code that relies on this header's shape defines the generator version it was
// written against (frame.h does); a header from another generator stops the build here.
#if defined(PB_PROTOCOL_EXPECTED_GENERATOR_VERSION) && \
    PB_PROTOCOL_EXPECTED_GENERATOR_VERSION != PB_PROTOCOL_GENERATOR_VERSION
#error "Regenerate this file with tools/gen_protocol.py (make generate)"
#endif

// A function whose bool result must not be dropped (a failed decode or lookup, a refused
// change). GCC warns even when the result is cast to void: test it.
#ifndef PB_MUST_USE
#define PB_MUST_USE __attribute__((warn_unused_result))
#endif

namespace pb {

const uint32_t kDefinitionHash = 0xF1AAC96BUL;
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
  // Holding the servo at the pulse a SERVO_HOLD asked for (servo calibration), until its time runs
  // out, STOP, START or IDENTIFY.
  HOLDING = 8,
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
  // Methods B and C: N_w, number of groups; 0 means one group per row of particles toward the lamp
  // (the rows method A counts between the group's strongest and weakest readings).
  GROUPS = 10,
  // Length of one estimation round; every particle's common start follows it.
  ROUND_MS = 11,
  // Interval between STATUS frames (each is jittered so particles do not collide).
  STATUS_PERIOD_MS = 12,
  // Contracted radius R_min in micrometres.
  RADIUS_MIN_UM = 13,
  // Fully expanded radius in micrometres (R_min + Delta R).
  RADIUS_MAX_UM = 14,
  // Photocell A0's gamma (eq. 7) in thousandths; 1000 means gamma = 1, the law eq. 14 assumes.
  SENSOR_GAMMA_0 = 16,
  // Photocell A1's gamma (eq. 7) in thousandths.
  SENSOR_GAMMA_1 = 17,
  // Photocell A2's gamma (eq. 7) in thousandths.
  SENSOR_GAMMA_2 = 18,
  // Photocell A3's gamma (eq. 7) in thousandths.
  SENSOR_GAMMA_3 = 19,
  // Photocell A4's gamma (eq. 7) in thousandths.
  SENSOR_GAMMA_4 = 20,
  // Photocell A5's gamma (eq. 7) in thousandths.
  SENSOR_GAMMA_5 = 21,
  // Photocell A0's gain in thousandths: the factor on its gamma-corrected resistance ratio; 1000
  // leaves it.
  SENSOR_GAIN_0 = 22,
  // Photocell A1's gain in thousandths.
  SENSOR_GAIN_1 = 23,
  // Photocell A2's gain in thousandths.
  SENSOR_GAIN_2 = 24,
  // Photocell A3's gain in thousandths.
  SENSOR_GAIN_3 = 25,
  // Photocell A4's gain in thousandths.
  SENSOR_GAIN_4 = 26,
  // Photocell A5's gain in thousandths.
  SENSOR_GAIN_5 = 27,
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
  // Value outside the parameter's min..max.
  OUT_OF_RANGE = 2,
  // Refused while running; STOP first.
  BUSY = 3,
  // Inside min..max, but the nine SERVO_CAL pulses would no longer rise (or fall) from point 0 to
  // point 8: change the neighbouring points first.
  SERVO_TABLE_NOT_MONOTONIC = 4,
  // Inside min..max, but RADIUS_MIN_UM would no longer be below RADIUS_MAX_UM.
  RADIUS_MIN_NOT_BELOW_MAX = 5,
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
  SERVO_HOLD = 0x08,
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

const uint8_t kParamCount = 35;

// The parameter table lives in flash on the AVR (read through avr/pgmspace.h): 13 bytes a
// parameter, where a switch statement took about 37.
namespace detail {
struct ParamEntry {
  uint8_t id;
  ParamSpec spec;
};
#ifdef __AVR__
#define PB_PROTOCOL_FLASH PROGMEM
#else
#define PB_PROTOCOL_FLASH
#endif
const ParamEntry kParams[kParamCount] PB_PROTOCOL_FLASH = {
    // CYCLE_STEPS
    {1, {150, 10, 3000}},
    // WAVE_SIZE
    {2, {5, 1, 64}},
    // UPDATE_INTERVAL_S
    {3, {180, 10, 3600}},
    // METHOD
    {4, {3, 0, 3}},
    // REF_DISTANCE_MM
    {5, {280, 10, 10000}},
    // REF_VALUE
    {6, {980, 1, 1022}},
    // DIAMETER_MM
    {7, {155, 10, 1000}},
    // COUNT_TOLERANCE
    {8, {10, 0, 200}},
    // BROADCAST_REPEATS
    {9, {5, 1, 20}},
    // GROUPS
    {10, {0, 0, 64}},
    // ROUND_MS
    {11, {3000, 200, 60000L}},
    // STATUS_PERIOD_MS
    {12, {2000, 200, 60000L}},
    // RADIUS_MIN_UM
    {13, {77500L, 50000L, 150000L}},
    // RADIUS_MAX_UM
    {14, {117500L, 50000L, 150000L}},
    // SENSOR_GAMMA_0
    {16, {1000, 250, 4000}},
    // SENSOR_GAMMA_1
    {17, {1000, 250, 4000}},
    // SENSOR_GAMMA_2
    {18, {1000, 250, 4000}},
    // SENSOR_GAMMA_3
    {19, {1000, 250, 4000}},
    // SENSOR_GAMMA_4
    {20, {1000, 250, 4000}},
    // SENSOR_GAMMA_5
    {21, {1000, 250, 4000}},
    // SENSOR_GAIN_0
    {22, {1000, 100, 10000}},
    // SENSOR_GAIN_1
    {23, {1000, 100, 10000}},
    // SENSOR_GAIN_2
    {24, {1000, 100, 10000}},
    // SENSOR_GAIN_3
    {25, {1000, 100, 10000}},
    // SENSOR_GAIN_4
    {26, {1000, 100, 10000}},
    // SENSOR_GAIN_5
    {27, {1000, 100, 10000}},
    // SERVO_CAL_0
    {32, {1000, 500, 2500}},
    // SERVO_CAL_1
    {33, {1100, 500, 2500}},
    // SERVO_CAL_2
    {34, {1195, 500, 2500}},
    // SERVO_CAL_3
    {35, {1285, 500, 2500}},
    // SERVO_CAL_4
    {36, {1370, 500, 2500}},
    // SERVO_CAL_5
    {37, {1455, 500, 2500}},
    // SERVO_CAL_6
    {38, {1545, 500, 2500}},
    // SERVO_CAL_7
    {39, {1640, 500, 2500}},
    // SERVO_CAL_8
    {40, {1750, 500, 2500}},
};
#undef PB_PROTOCOL_FLASH
}  // namespace detail

// Default and range of a parameter. False for an unknown id; out may be null to test
// whether an id exists.
PB_MUST_USE inline bool param_spec(uint8_t param_id, ParamSpec *out) {
  for (uint8_t i = 0; i < kParamCount; ++i) {
#ifdef __AVR__
    if (pgm_read_byte(&detail::kParams[i].id) != param_id) continue;
    if (out != 0) memcpy_P(out, &detail::kParams[i].spec, sizeof *out);
#else
    if (detail::kParams[i].id != param_id) continue;
    if (out != 0) *out = detail::kParams[i].spec;
#endif
    return true;
  }
  return false;
}

// Payload size of a message type; false for a type this definition does not know.
PB_MUST_USE inline bool message_payload_size(uint8_t type, uint8_t *size) {
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
    case 0x08:  // SERVO_HOLD
      bytes = 4;
      break;
    case 0x20:  // STATUS
      bytes = 46;
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

// Each message struct below is packed, its fields in wire order: on a little-endian machine (the
// AVR, x86, ARM) its bytes are the payload, so encoding and decoding are one memcpy. A generic
// table-driven codec and per-field shifts both cost the particle more flash (measured in README).
// A packed field binds only to a const reference or a copy (test macros take references).
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ != __ORDER_LITTLE_ENDIAN__
#error "The message structs are the wire layout only on a little-endian machine"
#endif

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
    memcpy(out, this, kPayloadSize);
    return kPayloadSize;
  }
  // False, leaving the fields untouched, unless len == kPayloadSize.
  PB_MUST_USE bool decode(const uint8_t *in, uint8_t len) {
    if (len != kPayloadSize) return false;
    memcpy(this, in, kPayloadSize);
    return true;
  }
} __attribute__((packed));
static_assert(sizeof(StartMessage) == StartMessage::kPayloadSize, "packed wire layout");

// STOP (from base): Stop at once: within one servo step the particle starts moving smoothly to the
// contracted state and reports STOPPING, then IDLE.
struct StopMessage {
  static const MessageType kType = MessageType::STOP;
  static const uint8_t kPayloadSize = 0;
  // Writes kPayloadSize (no) bytes and returns kPayloadSize.
  uint8_t encode(uint8_t * /*out*/) const { return kPayloadSize; }
  // False unless len == kPayloadSize.
  PB_MUST_USE bool decode(const uint8_t * /*in*/, uint8_t len) { return len == kPayloadSize; }
} __attribute__((packed));

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
    memcpy(out, this, kPayloadSize);
    return kPayloadSize;
  }
  // False, leaving the fields untouched, unless len == kPayloadSize.
  PB_MUST_USE bool decode(const uint8_t *in, uint8_t len) {
    if (len != kPayloadSize) return false;
    memcpy(this, in, kPayloadSize);
    return true;
  }
} __attribute__((packed));
static_assert(sizeof(SetParamMessage) == SetParamMessage::kPayloadSize, "packed wire layout");

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
    memcpy(out, this, kPayloadSize);
    return kPayloadSize;
  }
  // False, leaving the fields untouched, unless len == kPayloadSize.
  PB_MUST_USE bool decode(const uint8_t *in, uint8_t len) {
    if (len != kPayloadSize) return false;
    memcpy(this, in, kPayloadSize);
    return true;
  }
} __attribute__((packed));
static_assert(sizeof(GetParamMessage) == GetParamMessage::kPayloadSize, "packed wire layout");

// PING (from base): Ask for a STATUS frame now.
struct PingMessage {
  static const MessageType kType = MessageType::PING;
  static const uint8_t kPayloadSize = 1;

  // Particle id, or broadcast_id for all.
  uint8_t target;

  // Writes kPayloadSize bytes, little-endian, and returns kPayloadSize.
  uint8_t encode(uint8_t *out) const {
    memcpy(out, this, kPayloadSize);
    return kPayloadSize;
  }
  // False, leaving the fields untouched, unless len == kPayloadSize.
  PB_MUST_USE bool decode(const uint8_t *in, uint8_t len) {
    if (len != kPayloadSize) return false;
    memcpy(this, in, kPayloadSize);
    return true;
  }
} __attribute__((packed));
static_assert(sizeof(PingMessage) == PingMessage::kPayloadSize, "packed wire layout");

// IDENTIFY (from base): Make an idle particle wiggle three times so a person can find it; it
// answers with STATUS.
struct IdentifyMessage {
  static const MessageType kType = MessageType::IDENTIFY;
  static const uint8_t kPayloadSize = 1;

  // Particle id, or broadcast_id for all.
  uint8_t target;

  // Writes kPayloadSize bytes, little-endian, and returns kPayloadSize.
  uint8_t encode(uint8_t *out) const {
    memcpy(out, this, kPayloadSize);
    return kPayloadSize;
  }
  // False, leaving the fields untouched, unless len == kPayloadSize.
  PB_MUST_USE bool decode(const uint8_t *in, uint8_t len) {
    if (len != kPayloadSize) return false;
    memcpy(this, in, kPayloadSize);
    return true;
  }
} __attribute__((packed));
static_assert(sizeof(IdentifyMessage) == IdentifyMessage::kPayloadSize, "packed wire layout");

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
    memcpy(out, this, kPayloadSize);
    return kPayloadSize;
  }
  // False, leaving the fields untouched, unless len == kPayloadSize.
  PB_MUST_USE bool decode(const uint8_t *in, uint8_t len) {
    if (len != kPayloadSize) return false;
    memcpy(this, in, kPayloadSize);
    return true;
  }
} __attribute__((packed));
static_assert(sizeof(SetIdMessage) == SetIdMessage::kPayloadSize, "packed wire layout");

// SERVO_HOLD (from base): Servo calibration: make one resting particle (IDLE or DONE) hold its
// servo at pulse_us for hold_s seconds, so a person can measure the radius that pulse gives. It
// answers at once with STATUS: state HOLDING and servo_pulse_us = pulse_us when the hold took
// effect, its unchanged state otherwise (running, or a pulse outside 500..2500 us). A new
// SERVO_HOLD moves the pulse and restarts the time; hold_s = 0, STOP, START or IDENTIFY end the
// hold, and the servo goes straight back to the pulse of the contracted radius. Never persisted.
struct ServoHoldMessage {
  static const MessageType kType = MessageType::SERVO_HOLD;
  static const uint8_t kPayloadSize = 4;

  // Id of the particle to hold (a broadcast is ignored).
  uint8_t target;
  // Servo pulse to hold, microseconds (500..2500).
  uint16_t pulse_us;
  // Seconds to hold, at most 60 (larger values hold 60) so that a forgotten hold cannot overheat
  // the servo; resend to hold longer. 0 ends a hold.
  uint8_t hold_s;

  // Writes kPayloadSize bytes, little-endian, and returns kPayloadSize.
  uint8_t encode(uint8_t *out) const {
    memcpy(out, this, kPayloadSize);
    return kPayloadSize;
  }
  // False, leaving the fields untouched, unless len == kPayloadSize.
  PB_MUST_USE bool decode(const uint8_t *in, uint8_t len) {
    if (len != kPayloadSize) return false;
    memcpy(this, in, kPayloadSize);
    return true;
  }
} __attribute__((packed));
static_assert(sizeof(ServoHoldMessage) == ServoHoldMessage::kPayloadSize, "packed wire layout");

// STATUS (from particle): Periodic report of a particle's state, every STATUS_PERIOD_MS and on
// PING.
struct StatusMessage {
  static const MessageType kType = MessageType::STATUS;
  static const uint8_t kPayloadSize = 46;

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
  // Mean of the healthy sensors' 50-sample averages after each one's calibration (SENSOR_GAMMA_k,
  // SENSOR_GAIN_k) (0..1023).
  uint16_t intensity;
  // Each sensor's 50-sample average as read, before calibration (0..1023), A0..A5.
  uint16_t sensors[6];
  // Position within the current expansion-contraction cycle in 1/1000 of T; 0 outside a cycle.
  uint16_t cycle_phase;
  // Radius the motion commands now, micrometres (while HOLDING, the motion's contracted radius: the
  // servo then gets servo_pulse_us directly).
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
  // Servo pulse going out now, microseconds (through the SERVO_CAL table, or the one a SERVO_HOLD
  // set).
  uint16_t servo_pulse_us;

  // Writes kPayloadSize bytes, little-endian, and returns kPayloadSize.
  uint8_t encode(uint8_t *out) const {
    memcpy(out, this, kPayloadSize);
    return kPayloadSize;
  }
  // False, leaving the fields untouched, unless len == kPayloadSize.
  PB_MUST_USE bool decode(const uint8_t *in, uint8_t len) {
    if (len != kPayloadSize) return false;
    memcpy(this, in, kPayloadSize);
    return true;
  }
} __attribute__((packed));
static_assert(sizeof(StatusMessage) == StatusMessage::kPayloadSize, "packed wire layout");

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
    memcpy(out, this, kPayloadSize);
    return kPayloadSize;
  }
  // False, leaving the fields untouched, unless len == kPayloadSize.
  PB_MUST_USE bool decode(const uint8_t *in, uint8_t len) {
    if (len != kPayloadSize) return false;
    memcpy(this, in, kPayloadSize);
    return true;
  }
} __attribute__((packed));
static_assert(sizeof(IntensityMessage) == IntensityMessage::kPayloadSize, "packed wire layout");

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
    memcpy(out, this, kPayloadSize);
    return kPayloadSize;
  }
  // False, leaving the fields untouched, unless len == kPayloadSize.
  PB_MUST_USE bool decode(const uint8_t *in, uint8_t len) {
    if (len != kPayloadSize) return false;
    memcpy(this, in, kPayloadSize);
    return true;
  }
} __attribute__((packed));
static_assert(sizeof(ParamValueMessage) == ParamValueMessage::kPayloadSize, "packed wire layout");

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
const MessageType ServoHoldMessage::kType;
const uint8_t ServoHoldMessage::kPayloadSize;
const MessageType StatusMessage::kType;
const uint8_t StatusMessage::kPayloadSize;
const MessageType IntensityMessage::kType;
const uint8_t IntensityMessage::kPayloadSize;
const MessageType ParamValueMessage::kType;
const uint8_t ParamValueMessage::kPayloadSize;
#endif

}  // namespace pb

#endif  // PARTICLEBOT_PROTOCOL_GEN_H
