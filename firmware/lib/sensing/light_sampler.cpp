// Round-robin photocell sampling and the per-reading statistics the particle reports.
#include "light_sampler.h"

namespace pb {

namespace {
const uint16_t kSamplesPerCycle = static_cast<uint16_t>(kSensorCount) * kSamplesPerReading;
}  // namespace

LightSampler::LightSampler() : intensity_(0), index_(0), faults_(0), has_reading_(false) {
  for (uint8_t k = 0; k < kSensorCount; ++k) {
    sums_[k] = 0;
    means_[k] = 0;
  }
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
      healthy_sum = static_cast<uint16_t>(healthy_sum + mean);
      ++healthy;
    }
  }
  faults_ = faults;
  intensity_ = healthy == 0 ? 0 : static_cast<uint16_t>((healthy_sum + healthy / 2) / healthy);
  has_reading_ = true;
}

}  // namespace pb
