// Persistent settings: the EEPROM layout, parameters with their ranges, id and reset bookkeeping.
#ifndef PARTICLEBOT_SETTINGS_H
#define PARTICLEBOT_SETTINGS_H

#include <stdint.h>

#include "actuation.h"
#include "protocol_gen.h"

namespace pb {

// The 1 KB EEPROM, reached through the owner: avr-libc's eeprom_* on the particle, a RAM array on
// the PC. Never deleted through this interface, hence no virtual destructor (which would drag
// operator delete into the AVR build).
class Storage {
 public:
  virtual uint8_t read(uint16_t address) const = 0;
  virtual void write(uint16_t address, uint8_t value) = 0;

 protected:
  ~Storage() {}
};

const uint16_t kEepromSize = 1024;

// EEPROM layout, all little-endian, one block from address 0:
//   0-1 magic 'P' 'B' | 2 layout version | 3 parameter count | 4 id | 5 resets | 6 last reset cause
//   7.. one int32 per parameter id 0..kParamSlots - 1 | CRC-16 of bytes 0 .. the last value
//   (CCITT-FALSE, as on the radio). Slots of ids the protocol lacks are never written: they keep
//   what the EEPROM held (erased 0xFF bytes on a new chip), and the CRC covers them as they are.
// Indexing by parameter id wastes a little EEPROM (of 1 KB) but no flash on lookups. The values
// are not mirrored in RAM: they are read from the EEPROM when used (a few microseconds each),
// which keeps about 90 bytes of the 2.5 KB SRAM free.
namespace eeprom_layout {
const uint8_t kMagic0 = 'P';
const uint8_t kMagic1 = 'B';
const uint8_t kVersion = 1;
const uint16_t kVersionAddress = 2;
const uint16_t kCountAddress = 3;
const uint16_t kIdAddress = 4;
const uint16_t kResetsAddress = 5;
const uint16_t kResetCauseAddress = 6;
const uint16_t kParamsAddress = 7;
// Parameter ids must stay below this (a unit test checks the generated table).
const uint8_t kParamSlots = 64;
const uint16_t kCrcAddress = kParamsAddress + 4u * kParamSlots;
const uint16_t kBlockSize = kCrcAddress + 2;
}  // namespace eeprom_layout

// True when the nine pulses never decrease or never increase (a servo mounted either way round).
bool servo_table_monotonic(const uint16_t table[kServoCalPoints]);

// value moved into param's protocol range (unchanged for an unknown id), for values that never
// passed Settings::set(): those in a START, and the estimators' inputs from any caller.
int32_t clamp_to_spec(Param param, int32_t value);

class Settings {
 public:
  explicit Settings(Storage &storage);

  // Checks the stored block. A blank or corrupt one (bad magic, version or CRC) is replaced by
  // the defaults with the unassigned id and no resets. A sound block from a firmware with other
  // parameters (a firmware update that added some) keeps the id, the reset count and every value
  // inside its parameter's range; the others, among them the new parameters' slots, which an
  // erased or never-written EEPROM leaves at -1, get their defaults. (So a parameter's range
  // must not contain -1, and an id that once meant another parameter must not be reused.)
  // Returns true when the block was valid as it was.
  bool load();
  // Counts a reset (saturating at 255) and stores its cause (MCUSR).
  void record_reset(uint8_t cause);

  uint8_t id() const { return id_; }
  // Any id but the base station's, broadcast and unassigned (1..253); false otherwise.
  PB_MUST_USE bool set_id(uint8_t id);
  uint8_t resets() const { return resets_; }
  uint8_t last_reset_cause() const { return reset_cause_; }

  // False for an unknown parameter id.
  PB_MUST_USE bool get(uint8_t param, int32_t *value) const;
  // The value of a known parameter.
  int32_t get(Param param) const;
  // Range checks, then stores the value, writing only the bytes that change: OUT_OF_RANGE outside
  // min..max, RADIUS_MIN_NOT_BELOW_MAX unless RADIUS_MIN_UM stays below RADIUS_MAX_UM,
  // SERVO_TABLE_NOT_MONOTONIC unless the servo table stays monotonic. (BUSY is the caller's.)
  ParamResult set(uint8_t param, int32_t value);
  void servo_table(uint16_t table[kServoCalPoints]) const;

 private:
  // A block in this layout but written by a firmware with other parameters (another count) is
  // carried over rather than reset: see load().
  enum Block : uint8_t { kBlockValid, kBlockOtherParams, kBlockInvalid };
  Block check_block() const;
  // Every parameter to its default (keep_valid_values: only those whose stored value is outside
  // its range), the count to this firmware's; without keep_valid_values also the header, the
  // unassigned id and no resets.
  void write_defaults(bool keep_valid_values);
  uint16_t compute_crc() const;
  void update_crc();
  int32_t read_value(uint8_t param) const;
  void write_value(uint8_t param, int32_t value);
  void write_byte(uint16_t address, uint8_t value);
  ParamResult check(uint8_t param, int32_t value) const;

  Storage &storage_;
  uint8_t id_;
  uint8_t resets_;
  uint8_t reset_cause_;
};

}  // namespace pb

#endif  // PARTICLEBOT_SETTINGS_H
