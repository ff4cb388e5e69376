// Round-robin photocell sampling and the per-reading statistics the particle reports.
#include "light_sampler.h"

namespace pb {

namespace {

const uint16_t kSamplesPerCycle = static_cast<uint16_t>(kSensorCount) * kSamplesPerReading;

// Logarithms are kept in Q11 fixed point (the value times 2048, so that log2 of any 16-bit
// value fits an int16_t; a step of 3e-4 in rho is far below one count of a reading), the
// exponent 1000 / gamma in Q12, powers of two in Q16.
const uint8_t kLogBits = 11;
const uint8_t kExponentBits = 12;
const int32_t kOneQ16 = 1L << 16;
// Corrected resistance ratios beyond 2^10 either way are darker or brighter than any reading
// 1..1022 can show (rho runs from 1/1022 to 1022).
const int16_t kLog2RatioLimit = 10 << kLogBits;

// log2(x) in Q11 for x >= 1: the integer part is the highest set bit; each fraction bit comes
// from squaring the mantissa (in [1, 2), Q15) and seeing whether it reached 2.
int16_t log2_q11(uint16_t x) {
  int16_t result = 15 << kLogBits;
  while (!(x & 0x8000u)) {
    x = static_cast<uint16_t>(x << 1);
    result = static_cast<int16_t>(result - (1 << kLogBits));
  }
  uint32_t mantissa = x;  // x / 2^15, in [1, 2)
  for (uint16_t bit = 1u << (kLogBits - 1); bit != 0; bit >>= 1) {
    mantissa = (mantissa * mantissa) >> 15;  // < 2^32: mantissa < 2^16
    if (mantissa >= (2UL << 15)) {
      mantissa >>= 1;
      result = static_cast<int16_t>(result + bit);
    }
  }
  return result;
}

// 2^(l / 2048) in Q16 for |l| < kLog2RatioLimit (results below 2^26). The fraction's power
// comes from a cubic, 2^f - 1 = f (0.6951786 + f (0.2261497 + f 0.0786717)), within 2e-4
// relative on [0, 1).
uint32_t exp2_q16(int16_t l) {
  const int8_t whole = static_cast<int8_t>(l >> kLogBits);  // floor, also for negative l
  const uint32_t f = (static_cast<uint32_t>(l) & ((1u << kLogBits) - 1)) << (16 - kLogBits);
  uint32_t t = (5156u * f) >> 16;
  t = ((14821u + t) * f) >> 16;
  t = ((45559u + t) * f) >> 16;  // (45559 + t) <= 65536: the product stays below 2^32
  const uint32_t power = static_cast<uint32_t>(kOneQ16) + t;
  return whole >= 0 ? power << whole : power >> -whole;
}

}  // namespace

SensorCalibration sensor_calibration(uint16_t gamma_milli, uint16_t gain_milli) {
  SensorCalibration c;
  if (gamma_milli == 0) gamma_milli = kCalibrationUnit;
  if (gain_milli == 0) gain_milli = kCalibrationUnit;
  // <= 16384 for gamma >= 250
  c.exponent_q12 = static_cast<uint16_t>(
      (static_cast<uint32_t>(kCalibrationUnit) << kExponentBits) / gamma_milli);
  // The same function on both sides, so that a gain of 1000 gives exactly 0.
  c.log2_gain_q11 = static_cast<int16_t>(log2_q11(gain_milli) - log2_q11(kCalibrationUnit));
  return c;
}

uint16_t calibrated_reading(uint16_t raw, const SensorCalibration &c) {
  if (c.exponent_q12 == (1u << kExponentBits) && c.log2_gain_q11 == 0) return raw;
  if (raw == 0 || raw >= kAdcMax) return raw;
  // log2 rho' = log2(rho) * exponent + log2(gain), rho = (1023 - raw) / raw. |log2 rho| < 10,
  // so the product stays below 2^29.
  const int32_t log2_rho =
      log2_q11(static_cast<uint16_t>(kAdcMax - raw)) - static_cast<int32_t>(log2_q11(raw));
  const int32_t l = log2_rho * c.exponent_q12 / (1L << kExponentBits) + c.log2_gain_q11;
  if (l >= kLog2RatioLimit) return 1;
  if (l <= -kLog2RatioLimit) return kAdcMax - 1;
  // 1023 / (1 + rho'), with rho' in Q16, rounded.
  const uint32_t denominator = static_cast<uint32_t>(kOneQ16) + exp2_q16(static_cast<int16_t>(l));
  const uint32_t reading =
      (static_cast<uint32_t>(kAdcMax) * kOneQ16 + denominator / 2) / denominator;
  if (reading < 1) return 1;
  return reading >= kAdcMax ? kAdcMax - 1 : static_cast<uint16_t>(reading);
}

LightSampler::LightSampler() : intensity_(0), index_(0), faults_(0), has_reading_(false) {
  for (uint8_t k = 0; k < kSensorCount; ++k) {
    sums_[k] = 0;
    means_[k] = 0;
    calibration_[k] = sensor_calibration(kCalibrationUnit, kCalibrationUnit);
  }
}

void LightSampler::set_calibration(uint8_t sensor, uint16_t gamma_milli, uint16_t gain_milli) {
  if (sensor < kSensorCount) calibration_[sensor] = sensor_calibration(gamma_milli, gain_milli);
}

bool LightSampler::on_sample(uint8_t sensor, uint16_t raw) {
  if (sensor != next_sensor()) return false;
  sums_[sensor] = static_cast<uint16_t>(sums_[sensor] + (raw > kAdcMax ? kAdcMax : raw));
  ++index_;
  if (index_ < kSamplesPerCycle) return false;
  publish();
  index_ = 0;
  return true;
}

void LightSampler::publish() {
  uint16_t healthy_sum = 0;  // at most 6 * 1023
  uint8_t healthy = 0;
  uint8_t faults = 0;
  for (uint8_t k = 0; k < kSensorCount; ++k) {
    const uint16_t mean =
        static_cast<uint16_t>((sums_[k] + kSamplesPerReading / 2) / kSamplesPerReading);
    means_[k] = mean;
    sums_[k] = 0;
    if (mean == 0 || mean >= kAdcMax) {
      faults = static_cast<uint8_t>(faults | (1u << k));
    } else {
      healthy_sum = static_cast<uint16_t>(healthy_sum + calibrated_reading(mean, calibration_[k]));
      ++healthy;
    }
  }
  faults_ = faults;
  intensity_ = healthy == 0 ? 0 : static_cast<uint16_t>((healthy_sum + healthy / 2) / healthy);
  has_reading_ = true;
}

}  // namespace pb
