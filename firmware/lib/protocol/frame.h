// Frame codec of the radio link: CRC-16, frame encoder and a streaming parser that resynchronises.
//
// Frame: SYNC0 SYNC1 LEN TYPE SENDER SEQ PAYLOAD[LEN] CRC_LO CRC_HI, CRC-16/CCITT-FALSE over LEN
// through the last payload byte. The parser is written for the ATmega32U4 (about 66 bytes of
// state, no heap) and is the same code the host tests and virtual particles run.
#ifndef PARTICLEBOT_FRAME_H
#define PARTICLEBOT_FRAME_H

#include <stddef.h>
#include <stdint.h>

// The generated header must come from the generator version this codec was written against.
#define PB_PROTOCOL_EXPECTED_GENERATOR_VERSION 2
#include "protocol_gen.h"
#if PB_PROTOCOL_GENERATOR_VERSION != PB_PROTOCOL_EXPECTED_GENERATOR_VERSION
#error "Regenerate protocol_gen.h with tools/gen_protocol.py (make generate)"
#endif

namespace pb {

// A partial frame older than this is truncated: the owner then calls FrameParser::timeout().
// At 9600 baud a byte takes ~1 ms and the XBee forwards a packet in one burst.
const uint16_t kFrameTimeoutMs = 100;

// CRC-16/CCITT-FALSE: polynomial 0x1021, initial value 0xFFFF, no reflection, no final xor.
uint16_t crc16_update(uint16_t crc, uint8_t byte);
uint16_t crc16(const uint8_t *data, size_t len);

// Writes one frame into out. Returns its length (len + kFrameOverhead), or 0 without writing
// anything when len > kMaxPayload or capacity is too small. payload may be null when len is 0.
size_t encode_frame(uint8_t type, uint8_t sender, uint8_t seq, const uint8_t *payload, uint8_t len,
                    uint8_t *out, size_t capacity);

// One frame that passed the CRC check. Unknown types are frames too: the consumer ignores them.
// The fields are in the order the bytes after the sync marker arrive (LEN TYPE SENDER SEQ
// PAYLOAD CRC), so that the parser collects a frame in place; the two bytes after the longest
// payload hold that frame's CRC while it is checked.
struct Frame {
  uint8_t length;  // payload bytes, <= kMaxPayload
  uint8_t type;
  uint8_t sender;
  uint8_t seq;
  uint8_t payload[kMaxPayload + 2];
};

// Every counter saturates at 65535. Each received byte ends up in exactly one place: in an
// accepted frame, in the two sync bytes of a dropped candidate (bad_crc or bad_length), or in
// skipped_bytes.
struct ParserCounters {
  uint16_t frames;         // frames accepted
  uint16_t bad_crc;        // candidates whose CRC did not match
  uint16_t bad_length;     // candidates with LEN > kMaxPayload, or truncated (timeout())
  uint16_t skipped_bytes;  // bytes outside any candidate while hunting for the sync marker
};

// Streaming frame parser. A dropped candidate (bad length, bad CRC, truncation) is not thrown
// away: the bytes after its sync marker are scanned again, so a real frame hidden inside a
// corrupted one is still found. Every index is bounded by the fixed buffer; any byte sequence is
// safe to feed.
class FrameParser {
 public:
  FrameParser();

  // Feeds one received byte. Returns true when a valid frame is complete: read it with frame()
  // before the next push() or timeout(), which reuse its storage.
  PB_MUST_USE bool push(uint8_t byte);

  // The owner calls this after >= kFrameTimeoutMs without a byte: a partial frame is dropped as
  // truncated (bad_length) and its bytes are rescanned. Returns true when that rescan completes a
  // frame hidden in them (read it with frame()); call timeout() again until it returns false to
  // finish the rescan. Harmless when nothing is pending.
  PB_MUST_USE bool timeout();

  const Frame &frame() const { return frame_; }
  const ParserCounters &counters() const { return counters_; }

 private:
  // Bytes after the sync marker (LEN TYPE SENDER SEQ PAYLOAD CRC) live in frame_, whose fields
  // are laid out in that order, so that a valid frame needs no copy.
  static const uint8_t kBodyCapacity = kMaxPayload + 6;

  uint8_t *body() { return reinterpret_cast<uint8_t *>(&frame_); }
  bool step(uint8_t byte);
  bool drain();
  uint8_t pack_queue();
  void requeue();

  Frame frame_;
  ParserCounters counters_;
  uint8_t state_;       // hunting, saw SYNC0, or collecting the body
  uint8_t fill_;        // body bytes collected
  uint8_t queue_read_;  // body[queue_read_, queue_end_) still has to be (re)scanned
  uint8_t queue_end_;
};

}  // namespace pb

#endif  // PARTICLEBOT_FRAME_H
