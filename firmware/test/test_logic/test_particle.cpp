// Unit tests of the Particle controller: command handling, replies and the transmit queue.
#include <doctest.h>
#include <string.h>

#include "frame.h"
#include "particle.h"
#include "protocol_gen.h"

namespace {

class RamStorage : public pb::Storage {
 public:
  RamStorage() { memset(bytes, 0xFF, sizeof bytes); }
  uint8_t read(uint16_t address) const { return bytes[address]; }
  void write(uint16_t address, uint8_t value) { bytes[address] = value; }
  uint8_t bytes[pb::kEepromSize];
};

// A particle on the bench: a RAM EEPROM, constant light, and a base station to talk to it.
struct Bench {
  explicit Bench(uint32_t seed = 99) : particle(storage, 1, seed), now(0), seq(0) {
    particle.begin(0);
    advance(50);  // a first reading
  }

  void advance(uint32_t ms) {
    for (uint32_t i = 0; i < ms; ++i) {
      for (int k = 0; k < 8; ++k) particle.on_adc_sample(particle.next_sensor(), 600);
      particle.tick(++now);
    }
  }

  template <typename M>
  void send(const M &m, uint8_t sender = pb::kBaseStationId) {
    uint8_t payload[pb::kMaxPayload];
    const uint8_t n = m.encode(payload);
    uint8_t frame[pb::kMaxPayload + pb::kFrameOverhead];
    const size_t len = pb::encode_frame(static_cast<uint8_t>(M::kType), sender, seq++, payload, n,
                                        frame, sizeof frame);
    for (size_t i = 0; i < len; ++i) particle.on_rx_byte(frame[i], now);
  }

  // Frames queued for the radio, drained and parsed back; returns how many.
  int drain(pb::Frame *out, int capacity) {
    pb::FrameParser parser;
    uint8_t buffer[256];
    int n = 0;
    for (;;) {
      const size_t got = particle.take_tx(buffer, sizeof buffer);
      if (got == 0) break;
      for (size_t i = 0; i < got; ++i) {
        if (parser.push(buffer[i]) && n < capacity) out[n++] = parser.frame();
      }
    }
    CHECK(parser.counters().bad_crc == 0);
    CHECK(parser.counters().skipped_bytes == 0);
    return n;
  }

  RamStorage storage;
  pb::Particle particle;
  uint32_t now;
  uint8_t seq;
};

pb::StatusMessage status_of(const pb::Frame &f) {
  pb::StatusMessage s;
  REQUIRE(f.type == static_cast<uint8_t>(pb::MessageType::STATUS));
  REQUIRE(s.decode(f.payload, f.length));
  return s;
}

}  // namespace

TEST_CASE("a PING to its id is answered at once with a STATUS carrying the definition hash") {
  Bench b;
  pb::Frame frames[4];
  b.drain(frames, 4);  // whatever STATUS went out at boot
  pb::PingMessage ping;
  ping.target = pb::kUnassignedId;
  b.send(ping);
  REQUIRE(b.drain(frames, 4) == 1);
  CHECK(frames[0].sender == pb::kUnassignedId);
  const pb::StatusMessage s = status_of(frames[0]);
  CHECK(s.definition_hash == pb::kDefinitionHash);
  CHECK(s.state == static_cast<uint8_t>(pb::State::IDLE));
  CHECK(s.intensity == 600);
  CHECK(s.radius_um == 77500);
  CHECK(s.rx_frames == 1);
  CHECK(s.resets == 1);
  CHECK(s.last_reset_cause == 1);
}

TEST_CASE("commands from other particles, to other ids or from itself are ignored") {
  Bench b;
  pb::Frame frames[4];
  b.drain(frames, 4);
  // Addressed to its id, so that an answer would come at once (a broadcast's is delayed).
  pb::PingMessage ping;
  ping.target = pb::kUnassignedId;
  b.send(ping, 17);  // another particle
  ping.target = 9;   // another id
  b.send(ping);
  ping.target = pb::kUnassignedId;
  b.send(ping, pb::kUnassignedId);  // its own id
  CHECK(b.drain(frames, 4) == 0);
  pb::StopMessage stop;
  pb::StartMessage start;
  memset(&start, 0, sizeof start);
  start.run_id = 3;
  start.method = static_cast<uint8_t>(pb::Method::COUNTING);
  b.send(start, 17);
  CHECK(b.particle.state() == pb::State::IDLE);
  b.send(start);
  CHECK(b.particle.state() == pb::State::ESTIMATING);
  b.send(stop);
  CHECK(b.particle.state() == pb::State::STOPPING);
}

TEST_CASE("SET_PARAM is refused while running and applied at rest, GET_PARAM reads back") {
  Bench b;
  pb::Frame frames[4];
  b.drain(frames, 4);
  pb::SetParamMessage set;
  set.target = pb::kUnassignedId;  // its own id: answered at once
  set.param = static_cast<uint8_t>(pb::Param::CYCLE_STEPS);
  set.value = 75;
  pb::StartMessage start;
  memset(&start, 0, sizeof start);
  start.run_id = 1;
  start.method = static_cast<uint8_t>(pb::Method::COUNTING);
  b.send(start);
  b.send(set);
  REQUIRE(b.drain(frames, 4) == 1);
  pb::ParamValueMessage reply;
  REQUIRE(reply.decode(frames[0].payload, frames[0].length));
  CHECK(reply.result == static_cast<uint8_t>(pb::ParamResult::BUSY));
  CHECK(static_cast<int32_t>(reply.value) == 150);  // a copy: the field is packed
  b.send(pb::StopMessage());
  b.advance(700);
  b.drain(frames, 4);
  CHECK(b.particle.state() == pb::State::IDLE);
  b.send(set);
  pb::GetParamMessage get;
  get.target = pb::kUnassignedId;
  get.param = set.param;
  b.send(get);
  get.param = 99;
  b.send(get);
  REQUIRE(b.drain(frames, 4) == 3);
  REQUIRE(reply.decode(frames[0].payload, frames[0].length));
  CHECK(reply.result == static_cast<uint8_t>(pb::ParamResult::OK));
  REQUIRE(reply.decode(frames[1].payload, frames[1].length));
  CHECK(static_cast<int32_t>(reply.value) == 75);
  REQUIRE(reply.decode(frames[2].payload, frames[2].length));
  CHECK(reply.result == static_cast<uint8_t>(pb::ParamResult::UNKNOWN_PARAM));
}

TEST_CASE("a full transmit queue drops whole frames, never parts of one") {
  Bench b;
  pb::Frame frames[8];
  b.drain(frames, 8);
  pb::PingMessage ping;
  ping.target = pb::kUnassignedId;
  for (int i = 0; i < 5; ++i) b.send(ping);
  // STATUS frames are 54 bytes: two fit in 128.
  const size_t status_frame = pb::StatusMessage::kPayloadSize + pb::kFrameOverhead;
  CHECK(b.particle.tx_pending() == 2 * status_frame);
  CHECK(b.particle.tx_dropped_frames() == 3);
  CHECK(b.drain(frames, 8) == 2);
  CHECK(static_cast<uint8_t>(frames[1].seq - frames[0].seq) == 1);
}

TEST_CASE("a frame cut short is dropped after 100 ms of silence and the next one is read") {
  Bench b;
  pb::Frame frames[4];
  b.drain(frames, 4);
  const uint8_t partial[] = {pb::kSync0, pb::kSync1, 1, 0x05, 0};
  for (size_t i = 0; i < sizeof partial; ++i) b.particle.on_rx_byte(partial[i], b.now);
  b.advance(150);
  pb::PingMessage ping;
  ping.target = pb::kUnassignedId;
  b.send(ping);
  REQUIRE(b.drain(frames, 4) >= 1);
  const pb::StatusMessage s = status_of(frames[0]);
  CHECK(s.rx_bad_length == 1);
  CHECK(s.rx_frames == 1);
}

TEST_CASE("STATUS goes out every period give or take a quarter") {
  Bench b;
  pb::Frame frames[16];
  b.drain(frames, 16);
  uint32_t last = b.now;
  int seen = 0;
  for (int i = 0; i < 20000; ++i) {
    b.advance(1);
    if (b.drain(frames, 16) > 0) {
      if (seen > 0) {
        CHECK(b.now - last >= 1500);
        CHECK(b.now - last <= 2500);
      }
      last = b.now;
      ++seen;
    }
  }
  CHECK(seen >= 8);
}

TEST_CASE("SET_ID renames only the addressed particle and persists") {
  Bench b;
  pb::Frame frames[4];
  b.drain(frames, 4);
  pb::SetIdMessage set;
  set.target = pb::kBroadcastId;
  set.new_id = 12;
  b.send(set);
  CHECK(b.particle.id() == pb::kUnassignedId);
  set.target = pb::kUnassignedId;
  b.send(set);
  CHECK(b.particle.id() == 12);
  REQUIRE(b.drain(frames, 4) == 1);
  CHECK(frames[0].sender == 12);
  pb::Particle again(b.storage, 1, 5);
  again.begin(0);
  CHECK(again.id() == 12);
}

TEST_CASE("SET_ID to an id no particle may take is refused and answered from the old id") {
  Bench b;
  pb::Frame frames[4];
  b.drain(frames, 4);
  pb::SetIdMessage set;
  set.target = pb::kUnassignedId;
  set.new_id = 7;
  b.send(set);
  REQUIRE(b.drain(frames, 4) == 1);
  const uint8_t refused[] = {pb::kBaseStationId, pb::kUnassignedId, pb::kBroadcastId};
  for (size_t i = 0; i < sizeof refused; ++i) {
    set.target = 7;
    set.new_id = refused[i];
    b.send(set);
    CHECK(b.particle.id() == 7);
    REQUIRE(b.drain(frames, 4) == 1);
    CHECK(frames[0].sender == 7);
    CHECK(frames[0].type == static_cast<uint8_t>(pb::MessageType::STATUS));
  }
}

namespace {

// Ticks the bench one millisecond at a time from its current time until the particle queues a
// frame; returns how long that took (0: queued by a tick at the current time), or -1 after limit.
int ms_until_tx(Bench &b, uint32_t limit) {
  b.particle.tick(b.now);
  for (uint32_t waited = 0; waited <= limit; ++waited) {
    if (b.particle.tx_pending() > 0) return static_cast<int>(waited);
    b.advance(1);
  }
  return -1;
}

// Periodic STATUS frames would be taken for answers: after the one due within the first
// period from boot, the next comes 45 s or more later.
void quieten(Bench &b) {
  pb::SetParamMessage set;
  set.target = pb::kUnassignedId;
  set.param = static_cast<uint8_t>(pb::Param::STATUS_PERIOD_MS);
  set.value = 60000;
  b.send(set);
  b.advance(2100);
  pb::Frame frames[4];
  b.drain(frames, 4);
}

pb::PingMessage ping_to(uint8_t target) {
  pb::PingMessage ping;
  ping.target = target;
  return ping;
}

// Bench b in round 0 of a method-D run whose readings come from `others` more particles, then
// past the round's end, so the particle knows its group.
void run_round_with(Bench &b, uint8_t others) {
  pb::StartMessage start;
  memset(&start, 0, sizeof start);
  start.run_id = 4;
  start.method = static_cast<uint8_t>(pb::Method::COUNTING);
  start.cycle_steps = 10;
  b.send(start);
  for (uint8_t i = 0; i < others; ++i) {
    pb::IntensityMessage m;
    m.run_id = 4;
    m.round = 0;
    m.repeat = 0;
    m.intensity = static_cast<uint16_t>(700 + i);
    b.send(m, static_cast<uint8_t>(10 + i));
  }
  b.advance(3100);  // ROUND_MS 3000
  REQUIRE(b.particle.coordinator().group_size() == others + 1);
}

}  // namespace

TEST_CASE(
    "a broadcast PING is answered in a random 60 ms slot, one of 10 while no group is known") {
  bool used[pb::Particle::kPingSlotsUnknown] = {};
  for (uint32_t seed = 1; seed <= 60; ++seed) {
    Bench b(seed * 7919u);
    quieten(b);
    pb::Frame frames[4];
    b.send(ping_to(pb::kBroadcastId));
    const int waited = ms_until_tx(b, 1000);
    REQUIRE(waited >= 0);
    CHECK(waited % 60 == 0);
    CHECK(waited < 60 * pb::Particle::kPingSlotsUnknown);
    used[waited / 60 % pb::Particle::kPingSlotsUnknown] = true;
    REQUIRE(b.drain(frames, 4) == 1);
    CHECK(frames[0].type == static_cast<uint8_t>(pb::MessageType::STATUS));
  }
  int slots = 0;
  for (bool u : used) slots += u ? 1 : 0;
  CHECK(slots >= 8);  // 60 draws spread over the ten slots
}

TEST_CASE("once a round has heard its group, a broadcast PING waits at most group - 1 slots") {
  for (uint32_t seed = 1; seed <= 20; ++seed) {
    Bench b(seed * 104729u);
    quieten(b);
    run_round_with(b, 2);  // a group of three
    pb::Frame frames[8];
    b.drain(frames, 8);
    b.send(ping_to(pb::kBroadcastId));
    const int waited = ms_until_tx(b, 1000);
    REQUIRE(waited >= 0);
    CHECK(waited % 60 == 0);
    CHECK(waited <= 120);
  }
  Bench big(5);
  quieten(big);
  run_round_with(big, 30);  // a group of 31 still answers within a second
  pb::Frame frames[8];
  big.drain(frames, 8);
  for (int i = 0; i < 20; ++i) {
    big.send(ping_to(pb::kBroadcastId));
    const int waited = ms_until_tx(big, 2000);
    CHECK(waited >= 0);
    CHECK(waited < 60 * pb::Particle::kPingSlotsMax);
    big.drain(frames, 8);
  }
}

TEST_CASE("broadcast SET_PARAM, GET_PARAM and IDENTIFY are answered in a reply slot") {
  bool waited_somewhere = false;
  for (uint32_t seed = 1; seed <= 20; ++seed) {
    Bench b(seed * 7919u);
    quieten(b);
    pb::Frame frames[4];
    pb::SetParamMessage set;
    set.target = pb::kBroadcastId;
    set.param = static_cast<uint8_t>(pb::Param::CYCLE_STEPS);
    set.value = 75;
    b.send(set);
    int waited = ms_until_tx(b, 1000);
    REQUIRE(waited >= 0);
    CHECK(waited % 60 == 0);
    CHECK(waited < 60 * pb::Particle::kPingSlotsUnknown);
    waited_somewhere = waited_somewhere || waited > 0;
    REQUIRE(b.drain(frames, 4) == 1);
    pb::ParamValueMessage reply;
    REQUIRE(reply.decode(frames[0].payload, frames[0].length));
    CHECK(reply.result == static_cast<uint8_t>(pb::ParamResult::OK));
    CHECK(static_cast<int32_t>(reply.value) == 75);

    pb::GetParamMessage get;
    get.target = pb::kBroadcastId;
    get.param = set.param;
    b.send(get);
    REQUIRE(ms_until_tx(b, 1000) >= 0);
    REQUIRE(b.drain(frames, 4) == 1);
    CHECK(frames[0].type == static_cast<uint8_t>(pb::MessageType::PARAM_VALUE));

    pb::IdentifyMessage identify;
    identify.target = pb::kBroadcastId;
    b.send(identify);
    CHECK(b.particle.state() == pb::State::IDENTIFYING);  // the wiggle itself starts at once
    REQUIRE(ms_until_tx(b, 1000) >= 0);
    REQUIRE(b.drain(frames, 4) == 1);
    CHECK(frames[0].type == static_cast<uint8_t>(pb::MessageType::STATUS));
  }
  CHECK(waited_somewhere);  // the replies really were spread out, not all sent at once
}

TEST_CASE("a second broadcast parameter request sends the reply still waiting at once") {
  Bench b(11);
  quieten(b);
  pb::Frame frames[4];
  pb::GetParamMessage get;
  get.target = pb::kBroadcastId;
  get.param = static_cast<uint8_t>(pb::Param::CYCLE_STEPS);
  int tries = 0;
  // Find a draw whose reply has to wait, then ask again before it is due.
  do {
    b.send(get);
    b.particle.tick(b.now);
    if (b.particle.tx_pending() == 0) break;
    b.drain(frames, 4);
  } while (++tries < 20);
  REQUIRE(b.particle.tx_pending() == 0);
  get.param = static_cast<uint8_t>(pb::Param::ROUND_MS);
  b.send(get);
  REQUIRE(b.drain(frames, 4) == 1);  // the first reply, not lost
  pb::ParamValueMessage reply;
  REQUIRE(reply.decode(frames[0].payload, frames[0].length));
  CHECK(reply.param == static_cast<uint8_t>(pb::Param::CYCLE_STEPS));
  REQUIRE(ms_until_tx(b, 1000) >= 0);
  REQUIRE(b.drain(frames, 4) == 1);
  REQUIRE(reply.decode(frames[0].payload, frames[0].length));
  CHECK(reply.param == static_cast<uint8_t>(pb::Param::ROUND_MS));
}

TEST_CASE("a PING to its id while a broadcast answer waits is answered once, at once") {
  Bench b(3);
  quieten(b);
  pb::Frame frames[4];
  int tries = 0;
  // A seed whose slot is not the first, so that the answer is still waiting.
  do {
    b.send(ping_to(pb::kBroadcastId));
    b.particle.tick(b.now);
    if (b.particle.tx_pending() == 0) break;
    b.drain(frames, 4);
  } while (++tries < 20);
  REQUIRE(b.particle.tx_pending() == 0);
  b.send(ping_to(pb::kBroadcastId));  // a repeat does not draw a second answer
  b.send(ping_to(pb::kUnassignedId));
  CHECK(b.drain(frames, 4) == 1);
  b.advance(1000);
  CHECK(b.drain(frames, 4) == 0);
}

TEST_CASE("take_tx hands out one frame at a time, however much room the caller has") {
  Bench b;
  pb::Frame frames[4];
  b.drain(frames, 4);
  b.send(ping_to(pb::kUnassignedId));
  b.send(ping_to(pb::kUnassignedId));
  pb::GetParamMessage get;
  get.target = pb::kUnassignedId;
  get.param = static_cast<uint8_t>(pb::Param::ROUND_MS);
  b.send(get);
  const size_t status_len = pb::StatusMessage::kPayloadSize + pb::kFrameOverhead;
  const size_t value_len = pb::ParamValueMessage::kPayloadSize + pb::kFrameOverhead;
  REQUIRE(b.particle.tx_pending() == 2 * status_len + value_len);
  uint8_t out[256];
  CHECK(!b.particle.tx_frame_open());
  CHECK(b.particle.take_tx(out, sizeof out) == status_len);
  CHECK(!b.particle.tx_frame_open());
  // A frame taken in pieces: the last piece ends with the frame.
  CHECK(b.particle.take_tx(out, 10) == 10);
  CHECK(b.particle.tx_frame_open());
  CHECK(out[0] == pb::kSync0);
  CHECK(b.particle.take_tx(out, sizeof out) == status_len - 10);
  CHECK(!b.particle.tx_frame_open());
  CHECK(b.particle.take_tx(out, sizeof out) == value_len);
  CHECK(out[3] == static_cast<uint8_t>(pb::MessageType::PARAM_VALUE));
  CHECK(b.particle.take_tx(out, sizeof out) == 0);
  CHECK(!b.particle.tx_frame_open());
}

TEST_CASE("ticked as main.cpp does, each 50 Hz frame carries the next step of the cycle") {
  // Frames begin every 20 ms. main.cpp ticks at uneven instants and passes the next frame's
  // start as servo_ms; a frame carries the pulse left by the last tick before it begins. START
  // lands at each millisecond of a frame in turn: no step may repeat or be skipped.
  const uint16_t steps = 10;
  const uint32_t round_ms = 3000;  // ROUND_MS default
  const int kFrames = 60;
  for (uint32_t phase = 0; phase < 20; ++phase) {
    RamStorage storage;
    pb::Particle p(storage, 1, 1000 + phase);
    p.begin(0);
    const uint32_t start_ms = 1000 + phase;
    const uint32_t cycle_ms = start_ms + round_ms;      // alone: S_n = 1, t_I = 0, t_p = 0
    const uint32_t first_frame = (cycle_ms + 19) / 20;  // the first to begin at or after it
    uint16_t latched[kFrames];
    int seen = 0;
    uint32_t rng = 12345 + phase;
    uint32_t now = 0;
    bool started = false;
    while (seen < kFrames) {
      rng = rng * 1103515245u + 12345u;
      const uint32_t next = now + 1 + (rng >> 16) % 3;  // a pass every 1-3 ms
      // Frames beginning before this pass carry what the previous pass left.
      for (uint32_t f = now / 20 + 1; f * 20 <= next; ++f) {
        if (f >= first_frame && seen < kFrames) latched[seen++] = p.servo_pulse_us();
      }
      now = next;
      for (int k = 0; k < 8; ++k) p.on_adc_sample(p.next_sensor(), 600);
      if (!started && now >= start_ms) {
        pb::StartMessage m;
        memset(&m, 0, sizeof m);
        m.run_id = 1;
        m.method = static_cast<uint8_t>(pb::Method::COUNTING);
        m.cycle_steps = steps;
        m.wave_size = 1;
        uint8_t payload[pb::kMaxPayload];
        uint8_t frame[pb::kMaxPayload + pb::kFrameOverhead];
        const size_t len = pb::encode_frame(static_cast<uint8_t>(pb::MessageType::START), 0, 0,
                                            payload, m.encode(payload), frame, sizeof frame);
        for (size_t i = 0; i < len; ++i) p.on_rx_byte(frame[i], start_ms);
        started = true;
      }
      p.tick(now, (now / 20 + 1) * 20);
    }
    uint16_t table[pb::kServoCalPoints];
    p.settings().servo_table(table);
    const pb::Geometry g = {static_cast<uint32_t>(p.settings().get(pb::Param::RADIUS_MIN_UM)),
                            static_cast<uint32_t>(p.settings().get(pb::Param::RADIUS_MAX_UM))};
    for (int f = 0; f < kFrames; ++f) {
      const uint16_t k = static_cast<uint16_t>(f % steps);
      CAPTURE(phase);
      CAPTURE(f);
      CHECK(latched[f] == pb::servo_pulse_us(pb::cycle_radius_um(k, steps, g), g, table));
    }
  }
}

namespace {

pb::ServoHoldMessage hold_message(uint8_t target, uint16_t pulse_us, uint8_t hold_s) {
  pb::ServoHoldMessage m;
  m.target = target;
  m.pulse_us = pulse_us;
  m.hold_s = hold_s;
  return m;
}

// The STATUS a command was answered with (the only frame queued).
pb::StatusMessage answer(Bench &b) {
  pb::Frame frames[4];
  REQUIRE(b.drain(frames, 4) == 1);
  return status_of(frames[0]);
}

}  // namespace

TEST_CASE("SERVO_HOLD holds the pulse, answers with STATUS HOLDING, and lets go in time") {
  Bench b;
  pb::Frame frames[4];
  b.drain(frames, 4);
  const uint16_t contracted = b.particle.servo_pulse_us();
  CHECK(contracted == 1000);
  b.send(hold_message(pb::kUnassignedId, 1777, 2));
  // const: doctest binds a reference to what it checks, which a packed field only allows const.
  const pb::StatusMessage s = answer(b);
  CHECK(s.state == static_cast<uint8_t>(pb::State::HOLDING));
  CHECK(s.servo_pulse_us == 1777);
  CHECK(s.radius_um == 77500);  // the motion's radius; the servo follows the held pulse
  CHECK(b.particle.servo_pulse_us() == 1777);
  CHECK(b.particle.state() == pb::State::HOLDING);
  // A new hold moves the pulse and restarts the time.
  b.advance(1500);
  b.drain(frames, 4);
  b.send(hold_message(pb::kUnassignedId, 1200, 2));
  CHECK(answer(b).servo_pulse_us == 1200);
  b.advance(1990);
  CHECK(b.particle.servo_pulse_us() == 1200);
  b.advance(20);
  CHECK(b.particle.servo_pulse_us() == contracted);
  CHECK(b.particle.state() == pb::State::IDLE);
}

TEST_CASE("STOP, START, IDENTIFY and hold_s 0 end a hold; it is refused while running") {
  Bench b;
  pb::Frame frames[4];
  b.drain(frames, 4);
  b.send(hold_message(pb::kUnassignedId, 2000, 30));
  CHECK(b.particle.servo_pulse_us() == 2000);
  b.send(pb::StopMessage());
  CHECK(b.particle.servo_pulse_us() == 1000);
  CHECK(b.particle.state() != pb::State::HOLDING);

  b.send(hold_message(pb::kUnassignedId, 2000, 30));
  b.send(hold_message(pb::kUnassignedId, 2000, 0));
  CHECK(b.particle.servo_pulse_us() == 1000);

  pb::IdentifyMessage identify;
  identify.target = pb::kUnassignedId;
  b.send(hold_message(pb::kUnassignedId, 2000, 30));
  b.send(identify);
  CHECK(b.particle.state() == pb::State::IDENTIFYING);
  b.advance(2000);

  pb::StartMessage start;
  memset(&start, 0, sizeof start);
  start.run_id = 4;
  start.method = static_cast<uint8_t>(pb::Method::DIRECT);
  b.send(hold_message(pb::kUnassignedId, 2000, 30));
  b.drain(frames, 4);
  b.send(start);
  CHECK(b.particle.state() == pb::State::ESTIMATING);
  CHECK(b.particle.servo_pulse_us() == 1000);
  // Running: refused, and the answer shows it.
  b.send(hold_message(pb::kUnassignedId, 2000, 30));
  const pb::StatusMessage s = answer(b);
  CHECK(s.state == static_cast<uint8_t>(pb::State::ESTIMATING));
  CHECK(s.servo_pulse_us == 1000);
}

TEST_CASE("a hold is refused out of 500..2500 us, capped at 60 s, and never by broadcast") {
  Bench b;
  pb::Frame frames[4];
  b.drain(frames, 4);
  b.send(hold_message(pb::kUnassignedId, 499, 10));
  CHECK(answer(b).state == static_cast<uint8_t>(pb::State::IDLE));
  b.send(hold_message(pb::kUnassignedId, 2501, 10));
  CHECK(answer(b).servo_pulse_us == 1000);
  b.send(hold_message(pb::kBroadcastId, 1500, 10));
  CHECK(b.drain(frames, 4) == 0);
  CHECK(b.particle.servo_pulse_us() == 1000);
  b.send(hold_message(pb::kUnassignedId, 2500, 255));
  CHECK(answer(b).servo_pulse_us == 2500);
  b.advance(59990);
  CHECK(b.particle.servo_pulse_us() == 2500);
  b.advance(20);
  CHECK(b.particle.servo_pulse_us() == 1000);
}

TEST_CASE("the photocell calibration parameters change the intensity, not the raw readings") {
  Bench b;
  pb::Frame frames[4];
  b.drain(frames, 4);
  pb::PingMessage ping;
  ping.target = pb::kUnassignedId;
  b.send(ping);
  CHECK(answer(b).intensity == 600);
  pb::SetParamMessage set;
  set.target = pb::kUnassignedId;
  for (uint8_t k = 0; k < 6; ++k) {
    set.param = static_cast<uint8_t>(static_cast<uint8_t>(pb::Param::SENSOR_GAMMA_0) + k);
    set.value = 800;
    b.send(set);
    set.param = static_cast<uint8_t>(static_cast<uint8_t>(pb::Param::SENSOR_GAIN_0) + k);
    set.value = 1500;
    b.send(set);
  }
  b.drain(frames, 4);
  b.advance(100);  // a whole new reading
  b.drain(frames, 4);
  b.send(ping);
  const pb::StatusMessage s = answer(b);
  const uint16_t expected = pb::calibrated_reading(600, pb::sensor_calibration(800, 1500));
  CHECK(expected != 600);
  CHECK(s.intensity == expected);
  CHECK(s.sensors[0] == 600);
  // The calibration is in EEPROM: a particle booted from it reads the same.
  pb::Particle again(b.storage, 1, 5);
  again.begin(0);
  for (int i = 0; i < 50 * 8; ++i) again.on_adc_sample(again.next_sensor(), 600);
  uint8_t payload[pb::StatusMessage::kPayloadSize];
  again.status_payload(payload);
  pb::StatusMessage rebooted;
  REQUIRE(rebooted.decode(payload, sizeof payload));
  const uint16_t intensity = rebooted.intensity;
  CHECK(intensity == expected);
}
