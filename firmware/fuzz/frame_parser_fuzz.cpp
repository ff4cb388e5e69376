// libFuzzer target of the firmware's radio receive path: the streaming frame parser, then the
// Particle that handles what it accepts (decoders, commands, EEPROM writes).
//
// `make fuzz` builds it with clang's -fsanitize=fuzzer,address,undefined and runs it for a few
// seconds from firmware/fuzz/corpus; a crash or a broken invariant stops it and leaves the input
// in build/fuzz/. Invariants checked on every input, beyond memory safety:
//   - every frame the parser accepts appears byte for byte in the input, with a valid CRC;
//   - once the stream has ended (timeout() until false), every input byte is counted exactly once:
//     in an accepted frame, as one of the two sync bytes of a dropped candidate, or as skipped.
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "frame.h"
#include "particle.h"
#include "settings.h"

namespace {

// Longer inputs could saturate the parser's 16-bit counters and void the byte count.
const size_t kMaxInput = 4096;

class RamStorage : public pb::Storage {
 public:
  RamStorage() { memset(bytes_, 0xFF, sizeof bytes_); }
  uint8_t read(uint16_t address) const {
    return address < pb::kEepromSize ? bytes_[address] : 0xFF;
  }
  void write(uint16_t address, uint8_t value) {
    if (address < pb::kEepromSize) bytes_[address] = value;
  }

 private:
  uint8_t bytes_[pb::kEepromSize];
};

void require(bool condition) {
  if (!condition) abort();  // libFuzzer reports it as a crash and saves the input
}

// The frame as it was on the air, re-encoded from what the parser returned.
size_t reencode(const pb::Frame &f, uint8_t *out, size_t capacity) {
  return pb::encode_frame(f.type, f.sender, f.seq, f.payload, f.length, out, capacity);
}

bool occurs_in(const uint8_t *data, size_t size, const uint8_t *needle, size_t length) {
  if (length > size) return false;
  for (size_t at = 0; at + length <= size; ++at) {
    if (memcmp(data + at, needle, length) == 0) return true;
  }
  return false;
}

void check_parser(const uint8_t *data, size_t size) {
  pb::FrameParser parser;
  size_t frame_bytes = 0;
  uint8_t encoded[pb::kMaxPayload + pb::kFrameOverhead];
  // Each byte, then the end of the stream: the particle's 100 ms silence.
  for (size_t i = 0; i <= size; ++i) {
    for (;;) {
      const bool found = i < size ? parser.push(data[i]) : parser.timeout();
      if (!found) break;
      const pb::Frame &f = parser.frame();
      require(f.length <= pb::kMaxPayload);
      const size_t n = reencode(f, encoded, sizeof encoded);
      require(n == f.length + pb::kFrameOverhead);
      require(occurs_in(data, size, encoded, n));
      frame_bytes += n;
      if (i < size) break;  // push() finds at most one frame per byte
    }
  }
  const pb::ParserCounters &c = parser.counters();
  require(frame_bytes + 2u * (c.bad_crc + c.bad_length) + c.skipped_bytes == size);
}

void drive_particle(const uint8_t *data, size_t size) {
  RamStorage storage;
  pb::Particle particle(storage, 1, 12345);
  particle.begin(0);
  uint8_t sink[64];
  uint32_t now = 0;
  for (size_t i = 0; i < size; ++i) {
    particle.on_rx_byte(data[i], now);
    // A byte time at 9600 baud, and now and then a long silence: commands, replies and the
    // parser's timeout all get their turn.
    now += (data[i] == 0x00) ? 150 : 1;
    particle.tick(now);
    while (particle.take_tx(sink, sizeof sink) > 0) {
    }
  }
  particle.tick(now + 10000);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  if (size > kMaxInput) return -1;  // not added to the corpus
  check_parser(data, size);
  drive_particle(data, size);
  return 0;
}
