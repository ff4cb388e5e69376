// Radius profiles and servo calibration, in integer arithmetic (no float library on the AVR).
#include "actuation.h"

namespace pb {

namespace {

// Fixed point with 30 fraction bits, so the AVR needs no float library. The raised cosine below
// is within 2.4e-7 of the stroke (0.024 um on the longest stroke the settings allow), so a radius
// rounded to the micrometre is within 0.53 um of eq. 4 (measured over every step of every cycle
// length, firmware/test: it rounds the other way from the floating-point formula in about 0.1 %
// of steps).
const uint32_t kOne = 1ul << 30;

uint32_t stroke_um(const Geometry &g) {
  return g.r_max_um > g.r_min_um ? g.r_max_um - g.r_min_um : 0;
}

// round(a * b / c) through a 64-bit product. Kept out of line: inlined 64-bit arithmetic costs
// the AVR ~100 bytes of flash per use.
__attribute__((noinline)) uint32_t mul_div_round(uint32_t a, uint32_t b, uint32_t c) {
  return static_cast<uint32_t>((static_cast<uint64_t>(a) * b + c / 2) / c);
}

uint32_t mul_q30(uint32_t a, uint32_t b) {
  return mul_div_round(a, b, kOne);
}

// (1 - cos(2 pi num / den)) / 2 = sin^2(pi num / den) in Q30, for 0 <= num <= den, den > 0.
uint32_t raised_cosine_q30(uint32_t num, uint32_t den) {
  if (2 * num > den) num = den - num;  // symmetric about half a turn
  // Angles past a quarter turn use 1 - cos(psi) = 2 - (1 - cos(pi - psi)), so the series below
  // only sees psi <= pi / 2. There five terms leave out u^6 / 12!, 4.7e-7 at psi = pi / 2, which
  // halved is the 2.4e-7 of the stroke measured at a quarter turn; the Q30 rounding adds ~1e-9.
  // A sixth term would reach 4e-9 for one more 64-bit division per step, which no servo can show.
  const bool flip = 4 * num > den;
  if (flip) {
    num = den - 2 * num;
    den *= 2;
  }
  const uint32_t pi_q30 = 3373259426ul;  // pi * 2^30
  const uint32_t psi = mul_div_round(2 * num, pi_q30, den);
  const uint32_t u = mul_q30(psi, psi);  // psi^2 <= 2.47: fits 32 bits in Q30
  // 1 - cos psi = u/2 (1 - u/12 (1 - u/30 (1 - u/56 (1 - u/90)))), divisors i (i + 1), i = 9..3;
  // w holds twice that.
  uint32_t f = kOne;
  for (uint8_t i = 9; i >= 3; i -= 2) f = kOne - mul_q30(u, f) / (i * (i + 1u));
  const uint32_t w = mul_q30(u, f);
  const uint32_t h = (w + 2) >> 2;
  return flip ? kOne - h : h;
}

// R_min + amplitude * sin^2(pi num / den), rounded to the micrometre.
uint32_t raised_radius(const Geometry &g, uint32_t amplitude_um, uint32_t num, uint32_t den) {
  return g.r_min_um + mul_q30(amplitude_um, raised_cosine_q30(num, den));
}

}  // namespace

uint32_t cycle_radius_um(uint16_t k, uint16_t n, const Geometry &g) {
  if (n == 0 || k >= n) return g.r_min_um;
  return raised_radius(g, stroke_um(g), k, n);
}

uint16_t stop_ramp_steps(uint32_t from_um, const Geometry &g) {
  const uint32_t full = stroke_um(g);
  if (from_um <= g.r_min_um || full == 0) return 0;
  const uint32_t stroke = from_um - g.r_min_um;
  if (stroke >= full) return kStopRampFullSteps;
  // stroke < full <= 100 mm, so the product stays far below 2^32.
  return static_cast<uint16_t>((stroke * kStopRampFullSteps + full - 1) / full);
}

uint32_t ramp_radius_um(uint32_t from_um, uint16_t j, uint16_t steps, const Geometry &g) {
  if (from_um <= g.r_min_um || j >= steps) return g.r_min_um;
  // (1 + cos(pi j / s)) / 2 = sin^2(pi (s - j) / 2s): the falling half of a raised cosine.
  return raised_radius(g, from_um - g.r_min_um, static_cast<uint32_t>(steps - j), 2u * steps);
}

uint32_t wiggle_radius_um(uint16_t j, const Geometry &g) {
  if (j >= static_cast<uint16_t>(kWiggleCount) * kWiggleSteps) return g.r_min_um;
  return raised_radius(g, stroke_um(g) / 4, j % kWiggleSteps, kWiggleSteps);
}

uint16_t servo_pulse_us(uint32_t radius_um, const Geometry &g,
                        const uint16_t cal[kServoCalPoints]) {
  const uint8_t last = kServoCalPoints - 1;
  const uint32_t full = stroke_um(g);
  uint32_t pulse;
  if (full == 0 || radius_um <= g.r_min_um) {
    pulse = cal[0];
  } else if (radius_um >= g.r_max_um) {
    pulse = cal[last];
  } else {
    // Position in eighths of the stroke; 8 * 100 mm in um and 2500 * 100 mm fit 32 bits.
    const uint32_t scaled = (radius_um - g.r_min_um) * last;
    const uint8_t i = static_cast<uint8_t>(scaled / full);
    const uint32_t frac = scaled % full;
    // Weighted mean of the two neighbours: no negative intermediate for a falling table.
    pulse = (cal[i] * (full - frac) + cal[i + 1] * frac + full / 2) / full;
  }
  if (pulse < kServoPulseMinUs) return kServoPulseMinUs;
  if (pulse > kServoPulseMaxUs) return kServoPulseMaxUs;
  return static_cast<uint16_t>(pulse);
}

Motion Motion::hold() {
  Motion m;
  m.kind = kHold;
  m.steps = 0;
  m.start_ms = 0;
  m.from_um = 0;
  return m;
}

Motion Motion::cycle(uint32_t start_ms, uint16_t n) {
  Motion m = hold();
  m.kind = kCycle;
  m.start_ms = start_ms;
  m.steps = n;
  return m;
}

Motion Motion::ramp(uint32_t start_ms, uint32_t from_um, const Geometry &g) {
  Motion m = hold();
  m.kind = kRamp;
  m.start_ms = start_ms;
  m.from_um = from_um;
  m.steps = stop_ramp_steps(from_um, g);
  return m;
}

Motion Motion::wiggle(uint32_t start_ms) {
  Motion m = hold();
  m.kind = kWiggle;
  m.start_ms = start_ms;
  m.steps = static_cast<uint16_t>(kWiggleCount) * kWiggleSteps;
  return m;
}

uint16_t Motion::step_at(uint32_t now_ms) const {
  if (!time_reached(now_ms, start_ms)) return 0;
  const uint32_t steps_since = (now_ms - start_ms) / kStepMs;
  return steps_since > 0xFFFFu ? 0xFFFFu : static_cast<uint16_t>(steps_since);
}

uint32_t Motion::radius_um(uint32_t now_ms, const Geometry &g) const {
  const uint16_t j = step_at(now_ms);
  switch (kind) {
    case kCycle:
      return cycle_radius_um(j, steps, g);
    case kRamp:
      return ramp_radius_um(from_um, j, steps, g);
    case kWiggle:
      return wiggle_radius_um(j, g);
    default:
      return g.r_min_um;
  }
}

bool Motion::finished(uint32_t now_ms) const {
  if (kind == kHold) return true;
  return time_reached(now_ms, start_ms + duration_ms());
}

uint32_t Motion::duration_ms() const {
  return kind == kHold ? 0 : static_cast<uint32_t>(steps) * kStepMs;
}

}  // namespace pb
