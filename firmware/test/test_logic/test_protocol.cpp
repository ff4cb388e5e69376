// Tests of the frame codec and the generated message structs against shared/vectors.toml.
//
// The golden file path comes from PARTICLEBOT_VECTORS (default "shared/vectors.toml", relative to
// the repository root, where `make cpp-test` runs). The parser is also compared, stream by stream,
// with a naive whole-buffer reference scan on pseudo-random mutated frames.
#include <doctest.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <map>
#include <string>
#include <vector>

#include "frame.h"
#include "protocol_gen.h"

namespace {

typedef std::vector<uint8_t> Bytes;

// ---- a reader for the small TOML subset vectors.toml keeps to ---------------------------------

struct Value {
  bool is_string;
  std::string text;
  std::vector<long long> numbers;  // one for a scalar, several for an array
  std::map<std::string, Value> table;
  bool is_table;
  bool is_array;
  Value() : is_string(false), is_table(false), is_array(false) {}
};

struct Entry {
  std::string kind;  // "vector", "bad" or "check"
  std::map<std::string, Value> values;

  const Value &at(const std::string &key) const {
    std::map<std::string, Value>::const_iterator it = values.find(key);
    if (it == values.end()) FAIL("missing key " << key << " in a [[" << kind << "]] entry");
    return it->second;
  }
  long long number(const std::string &key) const { return at(key).numbers.at(0); }
  const std::string &text(const std::string &key) const { return at(key).text; }
};

void skip_spaces(const std::string &s, size_t &i) {
  while (i < s.size() && (s[i] == ' ' || s[i] == '\t')) ++i;
}

std::string parse_key(const std::string &s, size_t &i) {
  skip_spaces(s, i);
  const size_t start = i;
  while (i < s.size() && (isalnum(static_cast<unsigned char>(s[i])) || s[i] == '_')) ++i;
  return s.substr(start, i - start);
}

long long parse_number(const std::string &s, size_t &i) {
  skip_spaces(s, i);
  char *end = 0;
  const long long value = strtoll(s.c_str() + i, &end, 0);
  REQUIRE(end != s.c_str() + i);
  i = static_cast<size_t>(end - s.c_str());
  return value;
}

void expect_char(const std::string &s, size_t &i, char c) {
  skip_spaces(s, i);
  REQUIRE_MESSAGE(i < s.size(), "line ended, expected '" << c << "': " << s);
  REQUIRE_MESSAGE(s[i] == c, "expected '" << c << "' at column " << i << ": " << s);
  ++i;
}

Value parse_value(const std::string &s, size_t &i) {
  Value value;
  skip_spaces(s, i);
  REQUIRE(i < s.size());
  if (s[i] == '"') {
    const size_t close = s.find('"', i + 1);
    REQUIRE(close != std::string::npos);
    value.is_string = true;
    value.text = s.substr(i + 1, close - i - 1);
    i = close + 1;
  } else if (s[i] == '[') {
    value.is_array = true;
    ++i;
    skip_spaces(s, i);
    while (i < s.size() && s[i] != ']') {
      value.numbers.push_back(parse_number(s, i));
      skip_spaces(s, i);
      if (i < s.size() && s[i] == ',') ++i;
      skip_spaces(s, i);
    }
    expect_char(s, i, ']');
  } else if (s[i] == '{') {
    value.is_table = true;
    ++i;
    skip_spaces(s, i);
    while (i < s.size() && s[i] != '}') {
      const std::string key = parse_key(s, i);
      REQUIRE(!key.empty());
      expect_char(s, i, '=');
      value.table[key] = parse_value(s, i);
      skip_spaces(s, i);
      if (i < s.size() && s[i] == ',') ++i;
      skip_spaces(s, i);
    }
    expect_char(s, i, '}');
  } else {
    value.numbers.push_back(parse_number(s, i));
  }
  return value;
}

std::vector<Entry> read_vectors() {
  const char *env = getenv("PARTICLEBOT_VECTORS");
  const std::string path = env != 0 && env[0] != '\0' ? env : "shared/vectors.toml";
  FILE *file = fopen(path.c_str(), "r");
  REQUIRE_MESSAGE(file != 0, "cannot open " << path << " (run from the repository root)");
  std::vector<Entry> entries;
  char buffer[4096];
  while (fgets(buffer, sizeof buffer, file) != 0) {
    std::string line(buffer);
    while (!line.empty() && (line[line.size() - 1] == '\n' || line[line.size() - 1] == '\r')) {
      line.erase(line.size() - 1);
    }
    size_t i = 0;
    skip_spaces(line, i);
    if (i >= line.size() || line[i] == '#') continue;
    if (line[i] == '[') {
      const bool array = line.compare(i, 2, "[[") == 0;
      const size_t start = i + (array ? 2 : 1);
      const size_t end = line.find(']', start);
      REQUIRE(end != std::string::npos);
      Entry entry;
      entry.kind = line.substr(start, end - start);
      entries.push_back(entry);
      continue;
    }
    REQUIRE_MESSAGE(!entries.empty(), "key before any table: " << line);
    const std::string key = parse_key(line, i);
    expect_char(line, i, '=');
    entries.back().values[key] = parse_value(line, i);
  }
  fclose(file);
  return entries;
}

const std::vector<Entry> &vectors() {
  static const std::vector<Entry> entries = read_vectors();
  return entries;
}

Bytes hex_bytes(const std::string &text) {
  Bytes out;
  int high = -1;
  for (size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (c == ' ') continue;
    int nibble;
    if (c >= '0' && c <= '9') {
      nibble = c - '0';
    } else if (c >= 'A' && c <= 'F') {
      nibble = c - 'A' + 10;
    } else if (c >= 'a' && c <= 'f') {
      nibble = c - 'a' + 10;
    } else {
      FAIL("not a hex digit in " << text);
      return out;
    }
    if (high < 0) {
      high = nibble;
    } else {
      out.push_back(static_cast<uint8_t>(high * 16 + nibble));
      high = -1;
    }
  }
  REQUIRE(high < 0);
  return out;
}

// ---- an independent reference: CRC bit by bit, and a whole-buffer scan -------------------------

uint16_t reference_crc(const uint8_t *data, size_t len) {
  uint16_t crc = 0xFFFF;
  for (size_t i = 0; i < len; ++i) {
    for (int bit = 7; bit >= 0; --bit) {
      const bool feedback = (((crc >> 15) & 1u) ^ ((data[i] >> bit) & 1u)) != 0;
      crc = static_cast<uint16_t>(crc << 1);
      if (feedback) crc = static_cast<uint16_t>(crc ^ 0x1021u);
    }
  }
  return crc;
}

struct Counts {
  long frames, bad_crc, bad_length, skipped;
  Counts() : frames(0), bad_crc(0), bad_length(0), skipped(0) {}
};

// What the parser must make of a stream the owner ends with timeout(): a failed candidate
// (LEN > max, CRC mismatch, truncated) resumes at the byte after its sync marker.
void reference_scan(const Bytes &s, std::vector<Bytes> *frames, Counts *counts) {
  size_t i = 0;
  const size_t n = s.size();
  while (i < n) {
    if (s[i] != pb::kSync0 || i + 1 >= n || s[i + 1] != pb::kSync1) {
      ++counts->skipped;
      ++i;
      continue;
    }
    if (i + 2 >= n || s[i + 2] > pb::kMaxPayload) {
      ++counts->bad_length;
      i += 2;
      continue;
    }
    const size_t end = i + 8 + s[i + 2];
    if (end > n) {
      ++counts->bad_length;
      i += 2;
      continue;
    }
    if (reference_crc(&s[i + 2], end - i - 4) != (s[end - 2] | (s[end - 1] << 8))) {
      ++counts->bad_crc;
      i += 2;
      continue;
    }
    frames->push_back(Bytes(s.begin() + static_cast<long>(i), s.begin() + static_cast<long>(end)));
    ++counts->frames;
    i = end;
  }
}

Bytes frame_bytes(const pb::Frame &frame) {
  uint8_t out[pb::kMaxPayload + pb::kFrameOverhead];
  const size_t size = pb::encode_frame(frame.type, frame.sender, frame.seq, frame.payload,
                                       frame.length, out, sizeof out);
  REQUIRE(size == frame.length + 8u);
  return Bytes(out, out + size);
}

// Feeds bytes one at a time and ends the stream with timeout(), collecting every frame.
std::vector<Bytes> parse_all(pb::FrameParser &parser, const Bytes &stream, bool end_stream) {
  std::vector<Bytes> frames;
  for (size_t i = 0; i < stream.size(); ++i) {
    if (parser.push(stream[i])) frames.push_back(frame_bytes(parser.frame()));
  }
  while (end_stream && parser.timeout()) frames.push_back(frame_bytes(parser.frame()));
  return frames;
}

// ---- field comparison of the generated structs
// ---------------------------------------------------

class FieldCheck {
 public:
  explicit FieldCheck(const Entry &vector) : fields_(vector.at("fields").table), checked_(0) {}

  void scalar(const char *name, long long actual) {
    std::map<std::string, Value>::const_iterator it = fields_.find(name);
    REQUIRE_MESSAGE(it != fields_.end(), "vector lacks field " << name);
    REQUIRE(!it->second.is_array);
    CHECK_MESSAGE(it->second.numbers.at(0) == actual, name);
    ++checked_;
  }
  template <typename T>
  void array(const char *name, const T *actual, size_t count) {
    std::map<std::string, Value>::const_iterator it = fields_.find(name);
    REQUIRE_MESSAGE(it != fields_.end(), "vector lacks field " << name);
    REQUIRE(it->second.numbers.size() == count);
    for (size_t i = 0; i < count; ++i) CHECK_MESSAGE(it->second.numbers[i] == actual[i], name);
    ++checked_;
  }
  // Every field the vector lists was compared.
  void done() const { CHECK(checked_ == fields_.size()); }

 private:
  const std::map<std::string, Value> &fields_;
  size_t checked_;
};

template <typename M>
void check_reencodes(const M &message, const Entry &vector, const Bytes &expected) {
  uint8_t payload[pb::kMaxPayload];
  REQUIRE(message.encode(payload) == M::kPayloadSize);
  uint8_t out[pb::kMaxPayload + pb::kFrameOverhead];
  const size_t size = pb::encode_frame(
      static_cast<uint8_t>(M::kType), static_cast<uint8_t>(vector.number("sender")),
      static_cast<uint8_t>(vector.number("seq")), payload, M::kPayloadSize, out, sizeof out);
  CHECK(Bytes(out, out + size) == expected);
}

template <typename M>
M decoded(const pb::Frame &frame) {
  M message;
  memset(&message, 0xCC, sizeof message);
  REQUIRE(message.decode(frame.payload, frame.length));
  return message;
}

void check_fields(const pb::Frame &frame, const Entry &vector, const Bytes &bytes) {
  FieldCheck c(vector);
  const std::string type = vector.text("type");
  if (type == "START") {
    REQUIRE(frame.type == static_cast<uint8_t>(pb::MessageType::START));
    const pb::StartMessage m = decoded<pb::StartMessage>(frame);
    c.scalar("run_id", m.run_id);
    c.scalar("method", m.method);
    c.scalar("cycle_steps", m.cycle_steps);
    c.scalar("wave_size", m.wave_size);
    c.scalar("update_interval_s", m.update_interval_s);
    c.scalar("phototaxis", m.phototaxis);
    check_reencodes(m, vector, bytes);
  } else if (type == "STOP") {
    REQUIRE(frame.type == static_cast<uint8_t>(pb::MessageType::STOP));
    check_reencodes(decoded<pb::StopMessage>(frame), vector, bytes);
  } else if (type == "SET_PARAM") {
    REQUIRE(frame.type == static_cast<uint8_t>(pb::MessageType::SET_PARAM));
    const pb::SetParamMessage m = decoded<pb::SetParamMessage>(frame);
    c.scalar("target", m.target);
    c.scalar("param", m.param);
    c.scalar("value", m.value);
    check_reencodes(m, vector, bytes);
  } else if (type == "GET_PARAM") {
    REQUIRE(frame.type == static_cast<uint8_t>(pb::MessageType::GET_PARAM));
    const pb::GetParamMessage m = decoded<pb::GetParamMessage>(frame);
    c.scalar("target", m.target);
    c.scalar("param", m.param);
    check_reencodes(m, vector, bytes);
  } else if (type == "PING") {
    REQUIRE(frame.type == static_cast<uint8_t>(pb::MessageType::PING));
    const pb::PingMessage m = decoded<pb::PingMessage>(frame);
    c.scalar("target", m.target);
    check_reencodes(m, vector, bytes);
  } else if (type == "IDENTIFY") {
    REQUIRE(frame.type == static_cast<uint8_t>(pb::MessageType::IDENTIFY));
    const pb::IdentifyMessage m = decoded<pb::IdentifyMessage>(frame);
    c.scalar("target", m.target);
    check_reencodes(m, vector, bytes);
  } else if (type == "SET_ID") {
    REQUIRE(frame.type == static_cast<uint8_t>(pb::MessageType::SET_ID));
    const pb::SetIdMessage m = decoded<pb::SetIdMessage>(frame);
    c.scalar("target", m.target);
    c.scalar("new_id", m.new_id);
    check_reencodes(m, vector, bytes);
  } else if (type == "SERVO_HOLD") {
    REQUIRE(frame.type == static_cast<uint8_t>(pb::MessageType::SERVO_HOLD));
    const pb::ServoHoldMessage m = decoded<pb::ServoHoldMessage>(frame);
    c.scalar("target", m.target);
    c.scalar("pulse_us", m.pulse_us);
    c.scalar("hold_s", m.hold_s);
    check_reencodes(m, vector, bytes);
  } else if (type == "STATUS") {
    REQUIRE(frame.type == static_cast<uint8_t>(pb::MessageType::STATUS));
    const pb::StatusMessage m = decoded<pb::StatusMessage>(frame);
    c.scalar("state", m.state);
    c.scalar("method", m.method);
    c.scalar("run_id", m.run_id);
    c.scalar("s_n", m.s_n);
    c.scalar("group_size", m.group_size);
    c.scalar("sensor_faults", m.sensor_faults);
    c.scalar("intensity", m.intensity);
    uint16_t sensors[6];  // an aligned copy: the struct is packed
    memcpy(sensors, m.sensors, sizeof sensors);
    c.array("sensors", sensors, 6);
    c.scalar("cycle_phase", m.cycle_phase);
    c.scalar("radius_um", m.radius_um);
    c.scalar("uptime_ms", m.uptime_ms);
    c.scalar("definition_hash", m.definition_hash);
    c.scalar("rx_frames", m.rx_frames);
    c.scalar("rx_bad_crc", m.rx_bad_crc);
    c.scalar("rx_bad_length", m.rx_bad_length);
    c.scalar("rx_skipped_bytes", m.rx_skipped_bytes);
    c.scalar("resets", m.resets);
    c.scalar("last_reset_cause", m.last_reset_cause);
    c.scalar("servo_pulse_us", m.servo_pulse_us);
    check_reencodes(m, vector, bytes);
  } else if (type == "INTENSITY") {
    REQUIRE(frame.type == static_cast<uint8_t>(pb::MessageType::INTENSITY));
    const pb::IntensityMessage m = decoded<pb::IntensityMessage>(frame);
    c.scalar("run_id", m.run_id);
    c.scalar("round", m.round);
    c.scalar("repeat", m.repeat);
    c.scalar("intensity", m.intensity);
    check_reencodes(m, vector, bytes);
  } else if (type == "PARAM_VALUE") {
    REQUIRE(frame.type == static_cast<uint8_t>(pb::MessageType::PARAM_VALUE));
    const pb::ParamValueMessage m = decoded<pb::ParamValueMessage>(frame);
    c.scalar("param", m.param);
    c.scalar("result", m.result);
    c.scalar("value", m.value);
    check_reencodes(m, vector, bytes);
  } else {
    FAIL("vector of unknown type " << type);
  }
  c.done();
}

// Deterministic pseudo-random numbers (Numerical Recipes' LCG), so every run fuzzes the same.
class Lcg {
 public:
  explicit Lcg(uint32_t seed) : state_(seed) {}
  uint32_t next() {
    state_ = state_ * 1664525u + 1013904223u;
    return state_ >> 8;
  }
  uint32_t below(uint32_t bound) { return next() % bound; }

 private:
  uint32_t state_;
};

}  // namespace

TEST_CASE("crc16 of \"123456789\" is the CCITT-FALSE check value 0x29B1") {
  const uint8_t check[] = {'1', '2', '3', '4', '5', '6', '7', '8', '9'};
  CHECK(pb::crc16(check, sizeof check) == 0x29B1);
  CHECK(reference_crc(check, sizeof check) == 0x29B1);
  for (size_t i = 0; i < vectors().size(); ++i) {
    const Entry &entry = vectors()[i];
    if (entry.kind != "check") continue;
    const std::string input = entry.text("crc16_input");
    CHECK(pb::crc16(reinterpret_cast<const uint8_t *>(input.data()), input.size()) ==
          entry.number("crc16"));
  }
}

TEST_CASE("crc16 agrees with a bitwise reference on pseudo-random data") {
  Lcg rng(7);
  uint8_t data[64];
  for (int round = 0; round < 200; ++round) {
    const size_t len = rng.below(sizeof data + 1);
    for (size_t i = 0; i < len; ++i) data[i] = static_cast<uint8_t>(rng.next());
    CHECK(pb::crc16(data, len) == reference_crc(data, len));
  }
}

TEST_CASE("every golden vector parses into its fields and re-encodes to the same bytes") {
  int seen = 0;
  for (size_t i = 0; i < vectors().size(); ++i) {
    const Entry &vector = vectors()[i];
    if (vector.kind != "vector") continue;
    ++seen;
    CAPTURE(vector.text("name"));
    const Bytes bytes = hex_bytes(vector.text("frame"));
    pb::FrameParser parser;
    for (size_t k = 0; k + 1 < bytes.size(); ++k) REQUIRE_FALSE(parser.push(bytes[k]));
    REQUIRE(parser.push(bytes[bytes.size() - 1]));
    const pb::Frame &frame = parser.frame();
    CHECK(parser.counters().frames == 1);
    CHECK(frame.sender == vector.number("sender"));
    CHECK(frame.seq == vector.number("seq"));
    CHECK(frame.length + 8u == bytes.size());
    uint8_t payload_size = 0;
    REQUIRE(pb::message_payload_size(frame.type, &payload_size));
    CHECK(payload_size == frame.length);
    check_fields(frame, vector, bytes);
  }
  CHECK(seen >= 10);
}

TEST_CASE("every bad vector produces its expected counters") {
  int seen = 0;
  for (size_t i = 0; i < vectors().size(); ++i) {
    const Entry &bad = vectors()[i];
    if (bad.kind != "bad") continue;
    ++seen;
    CAPTURE(bad.text("name"));
    pb::FrameParser parser;
    const std::vector<Bytes> frames = parse_all(parser, hex_bytes(bad.text("bytes")), true);
    const pb::ParserCounters &counters = parser.counters();
    CHECK(counters.frames == bad.number("frames"));
    CHECK(frames.size() == static_cast<size_t>(bad.number("frames")));
    CHECK(counters.bad_crc == bad.number("bad_crc"));
    // The firmware has no separate counter for truncation: it is a bad length too.
    CHECK(counters.bad_length == bad.number("bad_length") + bad.number("truncated"));
    CHECK(counters.skipped_bytes == bad.number("skipped_bytes"));
  }
  CHECK(seen >= 5);
}

TEST_CASE("encode_frame refuses an oversized payload or a short buffer without writing") {
  uint8_t payload[pb::kMaxPayload + 1] = {0};
  uint8_t out[pb::kMaxPayload + pb::kFrameOverhead + 4];
  memset(out, 0xEE, sizeof out);
  CHECK(pb::encode_frame(1, 2, 3, payload, pb::kMaxPayload + 1, out, sizeof out) == 0);
  CHECK(pb::encode_frame(1, 2, 3, payload, 10, out, 17) == 0);
  for (size_t i = 0; i < sizeof out; ++i) CHECK(out[i] == 0xEE);
  CHECK(pb::encode_frame(1, 2, 3, payload, 10, out, 18) == 18);
  CHECK(out[18] == 0xEE);
  CHECK(pb::encode_frame(9, 2, 3, 0, 0, out, 8) == 8);
}

TEST_CASE("a payload encoded in place behind the header frames correctly") {
  pb::PingMessage ping;
  ping.target = 42;
  uint8_t out[16];
  ping.encode(out + 6);
  REQUIRE(pb::encode_frame(static_cast<uint8_t>(pb::PingMessage::kType), 0, 5, out + 6,
                           pb::PingMessage::kPayloadSize, out, sizeof out) == 9);
  pb::FrameParser parser;
  bool got = false;
  for (size_t i = 0; i < 9; ++i) got = parser.push(out[i]);
  REQUIRE(got);
  CHECK(parser.frame().payload[0] == 42);
}

TEST_CASE("parser counters saturate at 65535") {
  pb::FrameParser parser;
  bool found = false;  // none of this is a frame
  for (long i = 0; i < 70000; ++i) found = parser.push(0x00) || found;
  CHECK(parser.counters().skipped_bytes == 65535);
  for (long i = 0; i < 70000; ++i) {
    found = parser.push(pb::kSync0) || found;
    found = parser.push(pb::kSync1) || found;
    found = parser.push(pb::kMaxPayload + 1) || found;
  }
  CHECK(parser.counters().bad_length == 65535);
  CHECK_FALSE(found);
}

TEST_CASE("the generated parameter table keeps every default inside its range") {
  int found = 0;
  for (int id = 0; id < 256; ++id) {
    pb::ParamSpec spec;
    if (!pb::param_spec(static_cast<uint8_t>(id), &spec)) continue;
    ++found;
    CHECK(spec.min <= spec.default_value);
    CHECK(spec.default_value <= spec.max);
  }
  CHECK(found == pb::kParamCount);
  CHECK_FALSE(pb::param_spec(0, 0));
  CHECK(pb::param_spec(static_cast<uint8_t>(pb::Param::CYCLE_STEPS), 0));
}

TEST_CASE("the parser matches a whole-buffer reference scan on mutated frame streams") {
  std::vector<Bytes> good;
  for (size_t i = 0; i < vectors().size(); ++i) {
    if (vectors()[i].kind == "vector") good.push_back(hex_bytes(vectors()[i].text("frame")));
  }
  REQUIRE(!good.empty());
  Lcg rng(20190320);
  long accepted = 0;
  for (int round = 0; round < 3000; ++round) {
    // A stream of segments, each ended by a timeout; a segment is a run of pieces: intact frames,
    // mutated frames, garbage rich in sync bytes.
    pb::FrameParser parser;
    std::vector<Bytes> expected;
    Counts counts;
    size_t total = 0;
    std::vector<Bytes> got;
    const uint32_t segments = 1 + rng.below(3);
    for (uint32_t seg = 0; seg < segments; ++seg) {
      Bytes stream;
      const uint32_t pieces = 1 + rng.below(6);
      for (uint32_t p = 0; p < pieces; ++p) {
        Bytes piece = good[rng.below(static_cast<uint32_t>(good.size()))];
        switch (rng.below(6)) {
          case 0:  // intact
            break;
          case 1:  // flip a byte
            piece[rng.below(static_cast<uint32_t>(piece.size()))] ^=
                static_cast<uint8_t>(1 + rng.below(255));
            break;
          case 2:  // cut short
            piece.resize(rng.below(static_cast<uint32_t>(piece.size())));
            break;
          case 3:  // insert a byte
            piece.insert(piece.begin() + rng.below(static_cast<uint32_t>(piece.size())),
                         static_cast<uint8_t>(rng.next()));
            break;
          case 4:  // overwrite LEN
            piece[2] = static_cast<uint8_t>(rng.next());
            break;
          default: {  // garbage
            piece.clear();
            const uint32_t len = rng.below(40);
            for (uint32_t k = 0; k < len; ++k) {
              const uint32_t r = rng.below(4);
              piece.push_back(r == 0   ? pb::kSync0
                              : r == 1 ? pb::kSync1
                                       : static_cast<uint8_t>(rng.next()));
            }
          }
        }
        stream.insert(stream.end(), piece.begin(), piece.end());
      }
      total += stream.size();
      reference_scan(stream, &expected, &counts);
      const std::vector<Bytes> frames = parse_all(parser, stream, true);
      got.insert(got.end(), frames.begin(), frames.end());
    }
    REQUIRE(got == expected);
    const pb::ParserCounters &c = parser.counters();
    REQUIRE(c.frames == counts.frames);
    REQUIRE(c.bad_crc == counts.bad_crc);
    REQUIRE(c.bad_length == counts.bad_length);
    REQUIRE(c.skipped_bytes == counts.skipped);
    // Every byte is accounted for exactly once.
    size_t in_frames = 0;
    for (size_t k = 0; k < got.size(); ++k) {
      in_frames += got[k].size();
      CHECK(reference_crc(&got[k][2], got[k].size() - 4) ==
            (got[k][got[k].size() - 2] | (got[k][got[k].size() - 1] << 8)));
    }
    CHECK(total == in_frames + 2u * (c.bad_crc + c.bad_length) + c.skipped_bytes);
    accepted += c.frames;
  }
  CHECK(accepted > 1000);
}

TEST_CASE("the parser survives arbitrary bytes with timeouts at random points") {
  Lcg rng(12345);
  pb::FrameParser parser;
  for (long i = 0; i < 200000; ++i) {
    const uint32_t r = rng.below(16);
    if (r == 0) {
      while (parser.timeout()) {
        const pb::Frame &frame = parser.frame();
        REQUIRE(frame.length <= pb::kMaxPayload);
      }
    } else {
      const uint8_t byte = r < 4 ? pb::kSync0 : r < 7 ? pb::kSync1 : r < 9 ? 0x03 : rng.next();
      if (parser.push(byte)) REQUIRE(parser.frame().length <= pb::kMaxPayload);
    }
  }
  CHECK(parser.counters().skipped_bytes > 0);
}
