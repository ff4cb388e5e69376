// Light readings from the six photocells: 50-sample means gathered one ADC conversion at a time.
#ifndef PARTICLEBOT_LIGHT_SAMPLER_H
#define PARTICLEBOT_LIGHT_SAMPLER_H

#include <stdint.h>

namespace pb {

const uint8_t kSensorCount = 6;
const uint8_t kSamplesPerReading = 50;
const uint16_t kAdcMax = 1023;
// Calibration factors are in thousandths; this is 1.
const uint16_t kCalibrationUnit = 1000;

// One photocell's calibration (SENSOR_GAMMA_k and SENSOR_GAIN_k in shared/protocol.toml) in the
// form the correction uses: 1000 / gamma in 1/4096 and log2(gain / 1000) in 1/2048.
struct SensorCalibration {
  uint16_t exponent_q12;
  int16_t log2_gain_q11;
};
// gamma_milli and gain_milli in thousandths, as the parameters hold them (0 counts as 1000; the
// parameters' ranges, 250..4000 and 100..10000, keep the arithmetic in bounds).
SensorCalibration sensor_calibration(uint16_t gamma_milli, uint16_t gain_milli);

// A photocell's reading corrected to the law eq. 14 assumes: with rho = (1023 - raw) / raw, the
// photocell's resistance over the load's, rho' = gain / 1000 * rho^(1000 / gamma) and the result
// is 1023 / (1 + rho'), rounded and kept within 1..1022 (a corrected reading never looks like a
// stuck sensor). Integer arithmetic within one count of that formula; gamma = gain = 1000 returns
// raw exactly, and so does a raw 0 or 1023 (a fault, which callers leave out).
uint16_t calibrated_reading(uint16_t raw, const SensorCalibration &calibration);

// Samples sensor by sensor (0, 1, ..., 5, 0, 1, ...) so a reading never stalls the main loop and
// all six sensors see the same stretch of time. While one reading is being gathered the previous
// one stays published.
class LightSampler {
 public:
  LightSampler();

  // Sensor whose conversion is wanted next.
  uint8_t next_sensor() const { return static_cast<uint8_t>(index_ % kSensorCount); }

  // One 10-bit conversion (values above 1023 are clamped). A sample of any sensor other than
  // next_sensor() is ignored, so a confused caller cannot skew one sensor's mean. Returns true
  // when this sample completed a reading.
  bool on_sample(uint8_t sensor, uint16_t raw);

  // True when the next sample starts a new reading.
  bool between_readings() const { return index_ == 0; }
  // True once at least one reading has completed since construction.
  bool has_reading() const { return has_reading_; }
  // Sensor k's mean of its last 50 samples, rounded to nearest (0 before the first reading).
  uint16_t mean(uint8_t sensor) const { return sensor < kSensorCount ? means_[sensor] : 0; }
  // Bit k set: sensor k's mean is 0 or 1023, i.e. it is shorted or open and is left out.
  uint8_t faults() const { return faults_; }
  // Mean of the healthy sensors' calibrated means (0 when every sensor is faulty or before any
  // reading).
  uint16_t intensity() const { return intensity_; }

  // Sensor k's calibration from the next reading on (see calibrated_reading()); 1000, 1000 (the
  // default) leaves its readings as they are.
  void set_calibration(uint8_t sensor, uint16_t gamma_milli, uint16_t gain_milli);

 private:
  void publish();

  uint16_t sums_[kSensorCount];  // 50 * 1023 fits 16 bits
  uint16_t means_[kSensorCount];
  SensorCalibration calibration_[kSensorCount];
  uint16_t intensity_;
  uint16_t index_;  // 0 .. 6 * 50 - 1: sample number within the reading being gathered
  uint8_t faults_;
  bool has_reading_;
};

}  // namespace pb

#endif  // PARTICLEBOT_LIGHT_SAMPLER_H
