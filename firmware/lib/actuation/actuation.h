// Body motion over time (eq. 4 cycles, stop ramp, identify wiggle) and radius -> servo pulse.
#ifndef PARTICLEBOT_ACTUATION_H
#define PARTICLEBOT_ACTUATION_H

#include <stdint.h>

namespace pb {

// The servo is commanded once per step; every motion below is quantised to whole steps counted
// from its own start, so a cycle's phase does not depend on when the main loop happens to run.
const uint16_t kStepMs = 20;
// A full-stroke stop ramp lasts 30 steps (600 ms); shorter strokes take proportionally fewer.
const uint16_t kStopRampFullSteps = 30;
// IDENTIFY: three bumps of 25 steps (0.5 s) each to a quarter of the stroke.
const uint8_t kWiggleCount = 3;
const uint16_t kWiggleSteps = 25;
const uint8_t kServoCalPoints = 9;
const uint16_t kServoPulseMinUs = 500;
const uint16_t kServoPulseMaxUs = 2500;

struct Geometry {
  uint32_t r_min_um;  // contracted
  uint32_t r_max_um;  // fully expanded; callers keep r_max_um > r_min_um
};

// Eq. 4 at step k of an n-step cycle: R = R_min + dR/2 * (1 - cos(2 pi k / n)), which is the SI's
// dR/2 * (1 + sin(2 pi f t - pi/2)) + R_min with t = k * 20 ms and f = 1 / (n * 20 ms).
// k >= n (cycle over) and n == 0 give R_min. Rounded to the nearest micrometre.
uint32_t cycle_radius_um(uint16_t k, uint16_t n, const Geometry &g);

// Steps a stop ramp from from_um down to R_min takes: ceil(30 * stroke / full stroke), so the
// steepest step is never steeper than the full-stroke ramp's.
uint16_t stop_ramp_steps(uint32_t from_um, const Geometry &g);

// Half-cosine from from_um (step 0) to R_min (step `steps` and after).
uint32_t ramp_radius_um(uint32_t from_um, uint16_t j, uint16_t steps, const Geometry &g);

// IDENTIFY wiggle at step j (R_min from step kWiggleCount * kWiggleSteps on).
uint32_t wiggle_radius_um(uint16_t j, const Geometry &g);

// Servo pulse for a radius through the calibration table: cal[i] is the pulse at
// R_min + i/8 * (R_max - R_min); linear interpolation between points; radii outside the range
// use the end points. The result is clamped to 500..2500 us.
uint16_t servo_pulse_us(uint32_t radius_um, const Geometry &g, const uint16_t cal[kServoCalPoints]);

// What the body is doing; the radius at any instant follows from it and the time.
struct Motion {
  enum Kind { kHold = 0, kCycle = 1, kRamp = 2, kWiggle = 3 };
  uint8_t kind;
  uint16_t steps;  // kCycle: n; kRamp: ramp length; otherwise unused
  uint32_t start_ms;
  uint32_t from_um;  // kRamp only

  static Motion hold();
  static Motion cycle(uint32_t start_ms, uint16_t n);
  static Motion ramp(uint32_t start_ms, uint32_t from_um, const Geometry &g);
  static Motion wiggle(uint32_t start_ms);

  // Whole steps since start_ms (0 before it).
  uint16_t step_at(uint32_t now_ms) const;
  uint32_t radius_um(uint32_t now_ms, const Geometry &g) const;
  // True once the motion is back at R_min for good (always true for kHold).
  bool finished(uint32_t now_ms) const;
  // Length in ms (0 for kHold).
  uint32_t duration_ms() const;
};

// True when now_ms is at or after at_ms on the wrapping millisecond clock (valid within 24 days).
inline bool time_reached(uint32_t now_ms, uint32_t at_ms) {
  return static_cast<int32_t>(now_ms - at_ms) >= 0;
}

}  // namespace pb

#endif  // PARTICLEBOT_ACTUATION_H
