// EEPROM-backed settings with defaults, range checks and wear-sparing writes.
#include "settings.h"

#include <string.h>

#include "frame.h"

namespace pb {

namespace {

const uint8_t kServoCal0 = static_cast<uint8_t>(Param::SERVO_CAL_0);
const uint8_t kRadiusMin = static_cast<uint8_t>(Param::RADIUS_MIN_UM);
const uint8_t kRadiusMax = static_cast<uint8_t>(Param::RADIUS_MAX_UM);

// Known to the protocol and inside the EEPROM block.
bool known(uint8_t param) {
  return param < eeprom_layout::kParamSlots && param_spec(param, 0);
}

bool is_servo_cal(uint8_t param) {
  return param >= kServoCal0 && param < kServoCal0 + kServoCalPoints;
}

}  // namespace

bool servo_table_monotonic(const uint16_t table[kServoCalPoints]) {
  bool rising = true;
  bool falling = true;
  for (uint8_t i = 1; i < kServoCalPoints; ++i) {
    if (table[i] < table[i - 1]) rising = false;
    if (table[i] > table[i - 1]) falling = false;
  }
  return rising || falling;
}

int32_t clamp_to_spec(Param param, int32_t value) {
  ParamSpec spec;
  if (!param_spec(static_cast<uint8_t>(param), &spec)) return value;
  if (value < spec.min) return spec.min;
  return value > spec.max ? spec.max : value;
}

Settings::Settings(Storage &storage)
    : storage_(storage), id_(kUnassignedId), resets_(0), reset_cause_(0) {}

bool Settings::load() {
  const Block block = check_block();
  if (block != kBlockValid) write_defaults(block == kBlockOtherParams);
  const bool valid = block == kBlockValid;
  id_ = storage_.read(eeprom_layout::kIdAddress);
  resets_ = storage_.read(eeprom_layout::kResetsAddress);
  reset_cause_ = storage_.read(eeprom_layout::kResetCauseAddress);
  return valid;
}

void Settings::record_reset(uint8_t cause) {
  if (resets_ < 0xFF) ++resets_;
  reset_cause_ = cause;
  write_byte(eeprom_layout::kResetsAddress, resets_);
  write_byte(eeprom_layout::kResetCauseAddress, reset_cause_);
  update_crc();
}

bool Settings::set_id(uint8_t id) {
  if (id == kBaseStationId || id == kBroadcastId || id == kUnassignedId) return false;
  id_ = id;
  write_byte(eeprom_layout::kIdAddress, id);
  update_crc();
  return true;
}

bool Settings::get(uint8_t param, int32_t *value) const {
  if (!known(param)) return false;
  *value = read_value(param);
  return true;
}

int32_t Settings::get(Param param) const {
  return read_value(static_cast<uint8_t>(param));
}

ParamResult Settings::set(uint8_t param, int32_t value) {
  if (!known(param)) return ParamResult::UNKNOWN_PARAM;
  const ParamResult result = check(param, value);
  if (result != ParamResult::OK) return result;
  write_value(param, value);
  update_crc();
  return ParamResult::OK;
}

void Settings::servo_table(uint16_t table[kServoCalPoints]) const {
  for (uint8_t i = 0; i < kServoCalPoints; ++i) {
    table[i] = static_cast<uint16_t>(read_value(static_cast<uint8_t>(kServoCal0 + i)));
  }
}

ParamResult Settings::check(uint8_t param, int32_t value) const {
  ParamSpec spec;
  if (!param_spec(param, &spec)) return ParamResult::UNKNOWN_PARAM;
  if (value < spec.min || value > spec.max) return ParamResult::OUT_OF_RANGE;
  // Values inside the range that contradict another parameter get a result of their own, so a
  // person sees why a value the range allows was refused.
  if ((param == kRadiusMin && value >= get(Param::RADIUS_MAX_UM)) ||
      (param == kRadiusMax && value <= get(Param::RADIUS_MIN_UM))) {
    return ParamResult::RADIUS_MIN_NOT_BELOW_MAX;
  }
  if (is_servo_cal(param)) {
    uint16_t table[kServoCalPoints];
    servo_table(table);
    table[param - kServoCal0] = static_cast<uint16_t>(value);
    if (!servo_table_monotonic(table)) return ParamResult::SERVO_TABLE_NOT_MONOTONIC;
  }
  return ParamResult::OK;
}

Settings::Block Settings::check_block() const {
  using namespace eeprom_layout;
  if (storage_.read(0) != kMagic0 || storage_.read(1) != kMagic1) return kBlockInvalid;
  if (storage_.read(kVersionAddress) != kVersion) return kBlockInvalid;
  const uint16_t stored = static_cast<uint16_t>(
      storage_.read(kCrcAddress) | static_cast<uint16_t>(storage_.read(kCrcAddress + 1) << 8));
  if (stored != compute_crc()) return kBlockInvalid;
  // Values are not range-checked again: set() admitted them, a firmware with other ranges must
  // bump kVersion, and every consumer copes with odd values anyway (no division by zero).
  return storage_.read(kCountAddress) == kParamCount ? kBlockValid : kBlockOtherParams;
}

void Settings::write_defaults(bool keep_valid_values) {
  using namespace eeprom_layout;
  if (!keep_valid_values) {
    write_byte(0, kMagic0);
    write_byte(1, kMagic1);
    write_byte(kVersionAddress, kVersion);
    write_byte(kIdAddress, kUnassignedId);
    write_byte(kResetsAddress, 0);
    write_byte(kResetCauseAddress, 0);
  }
  write_byte(kCountAddress, kParamCount);
  // Slots of ids the protocol lacks keep whatever they hold (the CRC covers them): on a new chip
  // that spares ~220 writes of 3.4 ms each.
  ParamSpec spec;
  for (uint8_t param = 0; param < kParamSlots; ++param) {
    if (!param_spec(param, &spec)) continue;
    const int32_t value = read_value(param);
    if (keep_valid_values && value >= spec.min && value <= spec.max) continue;
    write_value(param, spec.default_value);
  }
  update_crc();
}

uint16_t Settings::compute_crc() const {
  uint16_t crc = 0xFFFF;
  for (uint16_t a = 0; a < eeprom_layout::kCrcAddress; ++a)
    crc = crc16_update(crc, storage_.read(a));
  return crc;
}

void Settings::update_crc() {
  const uint16_t crc = compute_crc();
  write_byte(eeprom_layout::kCrcAddress, static_cast<uint8_t>(crc));
  write_byte(eeprom_layout::kCrcAddress + 1, static_cast<uint8_t>(crc >> 8));
}

// The values are stored little-endian, the byte order of every machine this code runs on (the
// message structs rely on it too, see protocol_gen.h), so a value is its four bytes as stored:
// copying them costs the AVR far less flash than shifting each into place.
int32_t Settings::read_value(uint8_t param) const {
  const uint16_t a = static_cast<uint16_t>(eeprom_layout::kParamsAddress + 4u * param);
  uint8_t bytes[4];
  for (uint8_t i = 0; i < 4; ++i) bytes[i] = storage_.read(a + i);
  int32_t value;
  memcpy(&value, bytes, sizeof value);
  return value;
}

void Settings::write_value(uint8_t param, int32_t value) {
  const uint16_t a = static_cast<uint16_t>(eeprom_layout::kParamsAddress + 4u * param);
  uint8_t bytes[4];
  memcpy(bytes, &value, sizeof bytes);
  for (uint8_t i = 0; i < 4; ++i) write_byte(a + i, bytes[i]);
}

void Settings::write_byte(uint16_t address, uint8_t value) {
  // EEPROM cells wear out after ~100k writes: skip the ones that already hold the value.
  if (storage_.read(address) != value) storage_.write(address, value);
}

}  // namespace pb
