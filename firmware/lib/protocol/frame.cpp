// Frame codec of the radio link: CRC-16, encoder and the resynchronising streaming parser.
//
// How the parser rescans without a second buffer: the body bytes of a candidate are stored from
// index 0 while the bytes still waiting to be (re)scanned sit behind them in the same storage. A
// candidate only stores bytes that follow its own sync marker, so its write index always stays at
// least two below the read index of the queue and never overwrites a byte not yet scanned.

// This translation unit emits the out-of-class definitions of the message structs' constants.
#define PB_PROTOCOL_DEFINE_STATICS
#include "frame.h"

namespace pb {

namespace {

enum ParserState : uint8_t { kHunting = 0, kSawSync0 = 1, kCollecting = 2 };

// LEN TYPE SENDER SEQ precede the payload; the CRC follows it.
const uint8_t kHeaderBytes = 4;
const uint8_t kCrcBytes = 2;

void bump(uint16_t &counter) {
  if (counter != 0xFFFF) ++counter;
}

}  // namespace

uint16_t crc16_update(uint16_t crc, uint8_t byte) {
  crc = static_cast<uint16_t>(crc ^ static_cast<uint16_t>(static_cast<uint16_t>(byte) << 8));
  for (uint8_t bit = 0; bit < 8; ++bit) {
    if (crc & 0x8000u) {
      crc = static_cast<uint16_t>(static_cast<uint16_t>(crc << 1) ^ 0x1021u);
    } else {
      crc = static_cast<uint16_t>(crc << 1);
    }
  }
  return crc;
}

uint16_t crc16(const uint8_t *data, size_t len) {
  uint16_t crc = 0xFFFF;
  for (size_t i = 0; i < len; ++i) crc = crc16_update(crc, data[i]);
  return crc;
}

size_t encode_frame(uint8_t type, uint8_t sender, uint8_t seq, const uint8_t *payload, uint8_t len,
                    uint8_t *out, size_t capacity) {
  if (len > kMaxPayload || out == 0) return 0;
  if (payload == 0 && len != 0) return 0;
  const size_t total = static_cast<size_t>(len) + kFrameOverhead;
  if (capacity < total) return 0;
  // Payload first, so a payload already encoded in place at out + 6 stays valid.
  for (uint8_t i = 0; i < len; ++i) out[6 + i] = payload[i];
  out[0] = kSync0;
  out[1] = kSync1;
  out[2] = len;
  out[3] = type;
  out[4] = sender;
  out[5] = seq;
  const uint16_t crc = crc16(out + 2, static_cast<size_t>(len) + kHeaderBytes);
  out[6 + len] = static_cast<uint8_t>(crc);
  out[7 + len] = static_cast<uint8_t>(crc >> 8);
  return total;
}

FrameParser::FrameParser()
    : frame_(), counters_(), state_(kHunting), fill_(0), queue_read_(0), queue_end_(0) {}

// The parser stores a frame's body (LEN .. CRC) in a Frame, byte after byte.
static_assert(sizeof(Frame) == kMaxPayload + 6, "Frame holds a whole frame body");
static_assert(offsetof(Frame, payload) == 4, "LEN TYPE SENDER SEQ, then the payload");

// Moves the bytes still queued down to just behind the candidate's fill_ bytes; returns the
// index past the last one.
uint8_t FrameParser::pack_queue() {
  uint8_t end = fill_;
  uint8_t *bytes = body();
  for (uint8_t i = queue_read_; i < queue_end_; ++i) bytes[end++] = bytes[i];
  return end;
}

// Drops the candidate: its body bytes go back to the front of the scan queue, ahead of whatever
// was still queued. The candidate's two sync bytes are not rescanned (they were the failed marker).
void FrameParser::requeue() {
  queue_end_ = pack_queue();
  queue_read_ = 0;
  fill_ = 0;
  state_ = kHunting;
}

bool FrameParser::step(uint8_t byte) {
  if (state_ == kHunting) {
    if (byte == kSync0) {
      state_ = kSawSync0;
    } else {
      bump(counters_.skipped_bytes);
    }
    return false;
  }
  if (state_ == kSawSync0) {
    if (byte == kSync1) {
      state_ = kCollecting;
      fill_ = 0;
    } else if (byte == kSync0) {
      bump(counters_.skipped_bytes);  // the earlier SYNC0; this one may still start a marker
    } else {
      bump(counters_.skipped_bytes);
      bump(counters_.skipped_bytes);
      state_ = kHunting;
    }
    return false;
  }
  if (fill_ >= kBodyCapacity) {  // unreachable: LEN is checked below before the body grows
    bump(counters_.bad_length);
    requeue();
    return false;
  }
  body()[fill_++] = byte;
  if (fill_ == 1) {
    if (byte > kMaxPayload) {
      bump(counters_.bad_length);
      requeue();
    }
    return false;
  }
  const uint8_t length = frame_.length;
  if (fill_ < length + kHeaderBytes + kCrcBytes) return false;
  const uint8_t *bytes = body();
  const uint16_t crc = crc16(bytes, length + kHeaderBytes);
  const uint16_t received = static_cast<uint16_t>(
      bytes[length + kHeaderBytes] |
      static_cast<uint16_t>(static_cast<uint16_t>(bytes[length + kHeaderBytes + 1]) << 8));
  if (crc != received) {
    bump(counters_.bad_crc);
    requeue();
    return false;
  }
  bump(counters_.frames);
  state_ = kHunting;
  fill_ = 0;
  return true;
}

bool FrameParser::drain() {
  while (queue_read_ < queue_end_) {
    const uint8_t byte = body()[queue_read_++];
    if (step(byte)) return true;
  }
  queue_read_ = 0;
  queue_end_ = 0;
  return false;
}

bool FrameParser::push(uint8_t byte) {
  if (queue_read_ >= queue_end_) {
    if (step(byte)) return true;
    return drain();
  }
  // Bytes left over after a frame found by a rescan come first. The returned frame may now be
  // overwritten, so they move to the front, behind any candidate, and the new byte joins them.
  uint8_t end = pack_queue();
  queue_read_ = fill_;
  if (end < kBodyCapacity) {
    body()[end++] = byte;
  } else {
    bump(counters_.skipped_bytes);  // unreachable: a found frame freed at least 8 bytes
  }
  queue_end_ = end;
  return drain();
}

bool FrameParser::timeout() {
  for (;;) {
    if (drain()) return true;
    if (state_ == kSawSync0) {
      bump(counters_.skipped_bytes);
      state_ = kHunting;
      return false;
    }
    if (state_ != kCollecting) return false;
    bump(counters_.bad_length);
    requeue();
  }
}

}  // namespace pb
