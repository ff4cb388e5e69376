// Unit tests of the round-robin photocell sampler.
#include <doctest.h>
#include <math.h>

#include "light_sampler.h"

namespace {

// Feeds one complete reading in which sensor k reads values[k]; true if it completed a reading.
bool feed_reading(pb::LightSampler &s, const uint16_t values[6]) {
  bool done = false;
  for (int i = 0; i < 300; ++i) {
    const uint8_t k = s.next_sensor();
    done = s.on_sample(k, values[k]);
  }
  return done;
}

}  // namespace

TEST_CASE("the sampler asks for the sensors in turn, one sample at a time") {
  pb::LightSampler s;
  for (int i = 0; i < 20; ++i) {
    CHECK(s.next_sensor() == i % 6);
    s.on_sample(s.next_sensor(), 100);
  }
}

TEST_CASE("a reading is the rounded mean of 50 samples per sensor") {
  pb::LightSampler s;
  CHECK_FALSE(s.has_reading());
  int completed = 0;
  for (int i = 0; i < 300; ++i) {
    const uint8_t k = s.next_sensor();
    // Sensor 0 alternates 100 / 101: mean 100.5, rounded to 101.
    const uint16_t v =
        k == 0 ? static_cast<uint16_t>(100 + (i / 6) % 2) : static_cast<uint16_t>(200 + k);
    if (s.on_sample(k, v)) ++completed;
    CHECK(s.has_reading() == (i == 299));
  }
  CHECK(completed == 1);
  CHECK(s.mean(0) == 101);
  CHECK(s.mean(5) == 205);
  CHECK(s.faults() == 0);
  CHECK(s.intensity() == (101 + 201 + 202 + 203 + 204 + 205 + 3) / 6);
  CHECK(s.between_readings());
}

TEST_CASE("stuck sensors are flagged and left out of the intensity") {
  pb::LightSampler s;
  const uint16_t values[6] = {600, 0, 610, 1023, 620, 630};
  CHECK(feed_reading(s, values));
  CHECK(s.faults() == ((1 << 1) | (1 << 3)));
  CHECK(s.intensity() == 615);
  const uint16_t dead[6] = {0, 0, 1023, 1023, 0, 5000};  // 5000 is clamped to 1023
  CHECK(feed_reading(s, dead));
  CHECK(s.faults() == 0x3F);
  CHECK(s.intensity() == 0);
  CHECK(s.mean(5) == 1023);
}

TEST_CASE("a sample of the wrong sensor is ignored") {
  pb::LightSampler s;
  CHECK_FALSE(s.on_sample(3, 900));
  CHECK(s.next_sensor() == 0);
  const uint16_t values[6] = {10, 20, 30, 40, 50, 60};
  CHECK(feed_reading(s, values));
  CHECK(s.mean(3) == 40);
}

namespace {

// The correction as a formula in doubles: rho' = gain * rho^(1 / gamma), 1023 / (1 + rho').
double reference_reading(uint16_t raw, double gamma, double gain) {
  const double rho = (1023.0 - raw) / raw;
  const double corrected = gain * pow(rho, 1.0 / gamma);
  double v = 1023.0 / (1.0 + corrected);
  if (v < 1.0) v = 1.0;
  if (v > 1022.0) v = 1022.0;
  return v;
}

}  // namespace

TEST_CASE("the default calibration leaves every reading exactly as it is") {
  const pb::SensorCalibration unit = pb::sensor_calibration(1000, 1000);
  for (uint16_t raw = 0; raw <= 1023; ++raw) CHECK(pb::calibrated_reading(raw, unit) == raw);
}

TEST_CASE("a calibrated reading is within one count of the formula over the parameters' range") {
  const uint16_t gammas[] = {250, 400, 700, 900, 1000, 1100, 1350, 2000, 4000};
  const uint16_t gains[] = {100, 333, 800, 1000, 1250, 3000, 10000};
  int worst = 0;
  for (size_t g = 0; g < sizeof gammas / sizeof gammas[0]; ++g) {
    for (size_t k = 0; k < sizeof gains / sizeof gains[0]; ++k) {
      const pb::SensorCalibration c = pb::sensor_calibration(gammas[g], gains[k]);
      for (uint16_t raw = 1; raw <= 1022; ++raw) {
        const int ours = pb::calibrated_reading(raw, c);
        const double exact = reference_reading(raw, gammas[g] / 1000.0, gains[k] / 1000.0);
        CHECK(ours >= 1);
        CHECK(ours <= 1022);
        const int off = static_cast<int>(fabs(ours - exact) + 0.5);
        if (off > worst) worst = off;
        if (fabs(ours - exact) > 1.0) {
          FAIL_CHECK("raw " << raw << " gamma " << gammas[g] << " gain " << gains[k] << ": " << ours
                            << " vs " << exact);
        }
      }
    }
  }
  CHECK(worst <= 1);
  // Stuck sensors pass through untouched (they are left out of the intensity anyway).
  const pb::SensorCalibration c = pb::sensor_calibration(700, 3000);
  CHECK(pb::calibrated_reading(0, c) == 0);
  CHECK(pb::calibrated_reading(1023, c) == 1023);
}

TEST_CASE("the intensity averages the calibrated readings while mean() stays raw") {
  pb::LightSampler s;
  const uint16_t values[6] = {600, 0, 610, 500, 620, 630};  // sensor 1 is stuck
  s.set_calibration(0, 800, 1500);
  s.set_calibration(3, 1250, 700);
  CHECK(feed_reading(s, values));
  CHECK(s.mean(0) == 600);
  CHECK(s.mean(3) == 500);
  const int c0 = pb::calibrated_reading(600, pb::sensor_calibration(800, 1500));
  const int c3 = pb::calibrated_reading(500, pb::sensor_calibration(1250, 700));
  CHECK(c0 != 600);
  CHECK(c3 != 500);
  CHECK(s.intensity() == (c0 + 610 + c3 + 620 + 630 + 5 / 2) / 5);
  // Back to the defaults: the next reading is the plain mean again.
  s.set_calibration(0, 1000, 1000);
  s.set_calibration(3, 1000, 1000);
  CHECK(feed_reading(s, values));
  CHECK(s.intensity() == (600 + 610 + 500 + 620 + 630 + 5 / 2) / 5);
}
