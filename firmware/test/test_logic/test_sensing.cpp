// Unit tests of the round-robin photocell sampler.
#include <doctest.h>

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
