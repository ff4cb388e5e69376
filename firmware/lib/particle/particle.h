// The whole particle controller: radio protocol, sensing, estimation, schedule and servo target.
#ifndef PARTICLEBOT_PARTICLE_H
#define PARTICLEBOT_PARTICLE_H

#include <stddef.h>
#include <stdint.h>

#include "actuation.h"
#include "coordination.h"
#include "estimation.h"
#include "frame.h"
#include "light_sampler.h"
#include "protocol_gen.h"
#include "settings.h"

namespace pb {

// The Particle's plain bookkeeping, a base so that the constructor zeroes it as one block (member
// by member, the AVR spent about 200 B of flash on it).
struct ParticleState {
  Geometry geometry_;
  uint32_t now_ms_;
  uint32_t boot_ms_;
  uint32_t last_rx_ms_;
  uint32_t next_status_ms_;
  uint32_t ping_reply_ms_;   // when the pending STATUS answering a broadcast request is due
  uint32_t param_reply_ms_;  // when the pending PARAM_VALUE is due
  int32_t param_reply_value_;
  uint32_t radius_um_;
  uint16_t pulse_us_;
  uint16_t hold_pulse_us_;  // SERVO_HOLD's pulse while HOLDING, 0 otherwise
  uint32_t hold_until_ms_;
  uint32_t servo_start_ms_;  // the motion and step radius_um_ was worked out for
  uint16_t servo_step_;
  uint8_t servo_kind_;
  uint16_t round_intensity_;  // the reading this round uses and broadcasts
  uint16_t record_round_;     // which round of record_run_ record_ holds
  uint16_t tx_dropped_;
  uint8_t tx_head_;
  uint8_t tx_count_;
  uint8_t tx_frame_left_;  // bytes of the head frame not taken yet; 0 between frames
  uint8_t record_run_;
  uint8_t seq_;
  uint8_t reset_cause_;
  bool rx_idle_pending_;      // bytes arrived since the last parser timeout
  bool ping_reply_pending_;   // a broadcast PING or IDENTIFY awaits its STATUS
  bool param_reply_pending_;  // a broadcast SET_PARAM or GET_PARAM awaits its PARAM_VALUE
  uint8_t param_reply_param_;
  uint8_t param_reply_result_;
  // Readings still to complete before the round's own: 2 when a round starts mid-reading (that
  // reading mixes in light from before the round), 1 otherwise, 0 once round_intensity_ is set.
  uint8_t readings_awaited_;
};

// Driven identically by firmware/src/main.cpp (hardware) and the C API (PC). It never reads a
// clock or a pin: the owner passes time, ADC conversions and received bytes in, and takes the
// servo pulse and the bytes to transmit out. No call blocks or allocates.
class Particle : private ParticleState {
 public:
  // Bytes of radio output that can wait for Serial1; a frame that does not fit is dropped whole.
  static const uint8_t kTxCapacity = 128;
  // The longest a SERVO_HOLD holds: a servo stalled against the body heats up.
  static const uint8_t kMaxHoldS = 60;
  // A broadcast request that draws a reply (PING, IDENTIFY, SET_PARAM, GET_PARAM) is answered in
  // a random one of this many slots once a round has told the group size (kPingSlotsUnknown
  // before): a swarm answering at once would overflow the base station's 9600-baud radio. A slot
  // holds one STATUS frame on the air (54 B: 56 ms at 9600), and at most kPingSlotsMax slots keep
  // every answer within a second.
  static const uint16_t kPingSlotMs = 60;
  static const uint8_t kPingSlotsUnknown = 10;
  static const uint8_t kPingSlotsMax = 16;

  // reset_cause: MCUSR at boot (reported in STATUS). rng_seed: anything that differs between
  // particles (ADC noise on the real one) so their STATUS and INTENSITY timings spread out.
  Particle(Storage &storage, uint8_t reset_cause, uint32_t rng_seed);

  // Loads the id and settings (defaults and the unassigned id if the EEPROM is blank or corrupt)
  // and counts the reset. Call once before anything else.
  void begin(uint32_t now_ms);

  // Sensor index 0..5 (pin A0..A5) whose ADC conversion is wanted next.
  uint8_t next_sensor() const { return sampler_.next_sensor(); }
  // One 10-bit conversion of that sensor; 50 per sensor make a reading.
  void on_adc_sample(uint8_t sensor, uint16_t raw);
  // A byte from Serial1. Commands act at once (STOP starts the ramp from this instant).
  void on_rx_byte(uint8_t byte, uint32_t now_ms);
  // Runs whatever fell due by now_ms: schedule transitions, broadcasts, STATUS, servo target.
  // Call often (every loop pass); a late call catches up without shifting the schedule.
  // servo_ms is the instant the pulse read afterwards starts to show: main.cpp passes the start
  // of the next 50 Hz frame, so that every frame shows exactly the step due when it begins
  // (sampling the motion at now_ms would let a frame repeat or skip a step whenever a step
  // boundary falls near a frame boundary). The one-argument form samples at now_ms.
  void tick(uint32_t now_ms, uint32_t servo_ms);
  void tick(uint32_t now_ms) { tick(now_ms, now_ms); }

  // Pulse the servo driver must output from its next 50 Hz frame (500..2500 us): the motion's
  // through the calibration table, or the one a SERVO_HOLD set.
  uint16_t servo_pulse_us() const { return hold_pulse_us_ != 0 ? hold_pulse_us_ : pulse_us_; }
  uint32_t radius_um() const { return radius_um_; }
  // Moves up to capacity queued bytes into out; returns how many. Never goes past the end of the
  // frame at the head of the queue, so an owner can tell frames apart (see tx_frame_open()).
  size_t take_tx(uint8_t *out, size_t capacity);
  // True while part of the head frame has been taken and the rest has not. main.cpp hands a
  // frame to Serial1 and then keeps the line silent for kInterFrameGapMs before the next one.
  bool tx_frame_open() const { return tx_frame_left_ > 0; }
  // A transparent XBee sends what its host wrote once RO = 3 character times (3.1 ms at 9600
  // baud) pass without a byte, or at once at 100 bytes. Frames written back to back (two STATUS
  // frames are 108 B) would be cut apart, and every receiver would get other radios' packets
  // between the pieces. So each frame goes out alone: handed over whole, then the line stays
  // silent from its last stop bit for at least this long (counted in whole ms from the ms the
  // owner saw the line drain: 5-6 ms of silence) before the next frame.
  static const uint8_t kInterFrameGapMs = 6;
  uint8_t id() const { return settings_.id(); }

  // ---- inspection, for the PC build and tests ----
  State state() const { return hold_pulse_us_ != 0 ? State::HOLDING : coordinator_.state(); }
  // STATUS payload as it would be sent now (StatusMessage::kPayloadSize bytes into out).
  uint8_t status_payload(uint8_t *out) const;
  size_t tx_pending() const { return tx_count_; }
  uint16_t tx_dropped_frames() const { return tx_dropped_; }
  const Settings &settings() const { return settings_; }
  const Coordinator &coordinator() const { return coordinator_; }

 private:
  void handle_frame(const Frame &frame, uint32_t now_ms);
  void handle_start(const StartMessage &m, uint32_t now_ms);
  ParamResult apply_param(uint8_t param, int32_t value, int32_t *in_force);
  void handle_intensity(uint8_t sender, const IntensityMessage &m);
  // Points record_ at that round of that run, emptying it unless it already holds that round.
  void use_record(uint8_t run_id, uint16_t round);
  void begin_round_record(uint16_t round);
  void finish_round();
  // Copies what the settings say about the stroke and the photocells to where it is used.
  void refresh_from_settings();
  void handle_servo_hold(const ServoHoldMessage &m, uint32_t now_ms);
  void end_hold() { hold_pulse_us_ = 0; }
  void update_servo(uint32_t now_ms, bool table_changed = false);
  uint32_t radius_at(uint32_t now_ms) const;
  void send(MessageType type, const uint8_t *payload, uint8_t len);
  void send_status();
  void send_intensity();
  // Sends PARAM_VALUE now, or in a reply slot when the request was broadcast.
  void reply_param(uint8_t target, uint8_t param, ParamResult result, int32_t value,
                   uint32_t now_ms);
  void send_param_reply();  // the one place PARAM_VALUE is encoded
  // When a reply to a broadcast request is due. Kept out of line: both reply paths call it, and
  // inlined twice it costs about 100 B of flash.
  __attribute__((noinline)) uint32_t reply_slot_ms(uint32_t now_ms);
  void schedule_status(uint32_t now_ms);
  // STATUS now to a request addressed to this id, in a reply slot to a broadcast one.
  void answer_with_status(uint8_t target, uint32_t now_ms);
  bool addressed_to_me(uint8_t target) const;

  Settings settings_;
  LightSampler sampler_;
  FrameParser parser_;
  Rng rng_;
  Coordinator coordinator_;
  IntensityRecord record_;
  uint8_t tx_[kTxCapacity];
};

}  // namespace pb

#endif  // PARTICLEBOT_PARTICLE_H
