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
  Bench() : particle(storage, 1, 99), now(0), seq(0) {
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

TEST_CASE("PING is answered at once with a STATUS carrying the definition hash") {
  Bench b;
  pb::Frame frames[4];
  b.drain(frames, 4);  // whatever STATUS went out at boot
  pb::PingMessage ping;
  ping.target = pb::kBroadcastId;
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
  pb::PingMessage ping;
  ping.target = pb::kBroadcastId;
  b.send(ping, 17);  // another particle
  ping.target = 9;   // another id
  b.send(ping);
  ping.target = pb::kBroadcastId;
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
  set.target = pb::kBroadcastId;
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
  CHECK(reply.value == 150);
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
  CHECK(reply.value == 75);
  REQUIRE(reply.decode(frames[2].payload, frames[2].length));
  CHECK(reply.result == static_cast<uint8_t>(pb::ParamResult::UNKNOWN_PARAM));
}

TEST_CASE("a full transmit queue drops whole frames, never parts of one") {
  Bench b;
  pb::Frame frames[8];
  b.drain(frames, 8);
  pb::PingMessage ping;
  ping.target = pb::kBroadcastId;
  for (int i = 0; i < 5; ++i) b.send(ping);
  // STATUS frames are 52 bytes: two fit in 128.
  CHECK(b.particle.tx_pending() == 104);
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
  ping.target = pb::kBroadcastId;
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
