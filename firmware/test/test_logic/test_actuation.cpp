// Unit tests of the radius profiles (eq. 4, stop ramp, wiggle) and the servo calibration.
#include <doctest.h>
#include <math.h>

#include "actuation.h"

namespace {

const pb::Geometry kPaper = {77500, 117500};  // R_min, R_max of the paper's particle
const double kPi = 3.14159265358979323846;

// Eq. 4 as the SI writes it: dR/2 (1 + sin(2 pi f t - pi/2)) + R_min.
double eq4(double t_s, double period_s, const pb::Geometry &g) {
  const double dr = static_cast<double>(g.r_max_um - g.r_min_um);
  return dr / 2.0 * (1.0 + sin(2.0 * kPi * t_s / period_s - kPi / 2.0)) + g.r_min_um;
}

}  // namespace

TEST_CASE("the raised cosine is within 2.4e-7 of the stroke, worst at a quarter turn") {
  // With a stroke of 2^30 um the radius is the Q30 fraction itself.
  const pb::Geometry unit = {0, 1ul << 30};
  double worst = 0;
  double worst_at = 0;
  for (uint16_t n = 10; n <= 3000; n = static_cast<uint16_t>(n + (n < 400 ? 1 : 13))) {
    for (uint16_t k = 0; k <= n; ++k) {
      const double s = sin(kPi * k / n);
      const double error = fabs(pb::cycle_radius_um(k, n, unit) / 1073741824.0 - s * s);
      if (error > worst) {
        worst = error;
        worst_at = static_cast<double>(k) / n;
      }
    }
  }
  CHECK(worst < 2.4e-7);
  CHECK(worst > 2.2e-7);  // the series' first omitted term, u^6 / 12! / 2 at psi = pi / 2
  CHECK((fabs(worst_at - 0.25) < 1e-3 || fabs(worst_at - 0.75) < 1e-3));
}

// Rounded to the micrometre from a fixed-point series within 2.4e-7 of the stroke.
TEST_CASE("a cycle follows eq. 4 step by step to the micrometre") {
  const uint16_t periods[] = {10, 75, 150, 300, 3000};
  const pb::Geometry wide = {50000, 150000};
  for (uint16_t n : periods) {
    for (uint16_t k = 0; k <= n; ++k) {
      const double t = k * 0.020;
      CHECK(fabs(pb::cycle_radius_um(k, n, kPaper) - eq4(t, n * 0.020, kPaper)) <= 0.55);
      CHECK(fabs(pb::cycle_radius_um(k, n, wide) - eq4(t, n * 0.020, wide)) <= 0.55);
    }
  }
}

TEST_CASE("a cycle starts and ends contracted and peaks fully expanded halfway") {
  CHECK(pb::cycle_radius_um(0, 150, kPaper) == kPaper.r_min_um);
  CHECK(pb::cycle_radius_um(75, 150, kPaper) == kPaper.r_max_um);
  CHECK(pb::cycle_radius_um(150, 150, kPaper) == kPaper.r_min_um);
  CHECK(pb::cycle_radius_um(5000, 150, kPaper) == kPaper.r_min_um);
  CHECK(pb::cycle_radius_um(3, 0, kPaper) == kPaper.r_min_um);
}

TEST_CASE("the stop ramp takes 30 steps for the full stroke and proportionally fewer") {
  CHECK(pb::stop_ramp_steps(kPaper.r_max_um, kPaper) == 30);
  CHECK(pb::stop_ramp_steps(kPaper.r_min_um + 20000, kPaper) == 15);
  CHECK(pb::stop_ramp_steps(kPaper.r_min_um + 1, kPaper) == 1);
  CHECK(pb::stop_ramp_steps(kPaper.r_min_um, kPaper) == 0);
  CHECK(pb::stop_ramp_steps(kPaper.r_max_um + 5000, kPaper) == 30);
}

TEST_CASE("the stop ramp falls monotonically along a half cosine, never steeper than full stroke") {
  const double full_step = kPi * (kPaper.r_max_um - kPaper.r_min_um) / 60.0;
  const uint32_t starts[] = {kPaper.r_max_um, 110000, 90000, 77600};
  for (uint32_t from : starts) {
    const uint16_t steps = pb::stop_ramp_steps(from, kPaper);
    CHECK(pb::ramp_radius_um(from, 0, steps, kPaper) == from);
    CHECK(pb::ramp_radius_um(from, steps, steps, kPaper) == kPaper.r_min_um);
    for (uint16_t j = 1; j <= steps; ++j) {
      const uint32_t before = pb::ramp_radius_um(from, j - 1, steps, kPaper);
      const uint32_t after = pb::ramp_radius_um(from, j, steps, kPaper);
      CHECK(after <= before);
      CHECK(before - after <= full_step + 1.0);
      const double ideal =
          kPaper.r_min_um + (from - kPaper.r_min_um) * (1.0 + cos(kPi * j / steps)) / 2.0;
      CHECK(fabs(after - ideal) <= 0.55);
    }
  }
}

TEST_CASE("the identify wiggle is three small bumps that end contracted") {
  const uint32_t quarter = (kPaper.r_max_um - kPaper.r_min_um) / 4;
  uint32_t peak = 0;
  for (uint16_t j = 0; j < 3 * pb::kWiggleSteps; ++j) {
    const uint32_t r = pb::wiggle_radius_um(j, kPaper);
    CHECK(r >= kPaper.r_min_um);
    CHECK(r <= kPaper.r_min_um + quarter);
    if (r > peak) peak = r;
    if (j % pb::kWiggleSteps == 0) CHECK(r == kPaper.r_min_um);
  }
  CHECK(peak > kPaper.r_min_um + quarter * 9 / 10);
  CHECK(pb::wiggle_radius_um(3 * pb::kWiggleSteps, kPaper) == kPaper.r_min_um);
}

TEST_CASE("the servo pulse interpolates the calibration table linearly") {
  const uint16_t cal[9] = {1000, 1100, 1195, 1285, 1370, 1455, 1545, 1640, 1750};
  const uint32_t eighth = (kPaper.r_max_um - kPaper.r_min_um) / 8;
  for (uint8_t i = 0; i < 9; ++i) {
    CHECK(pb::servo_pulse_us(kPaper.r_min_um + i * eighth, kPaper, cal) == cal[i]);
  }
  CHECK(pb::servo_pulse_us(kPaper.r_min_um + eighth / 2, kPaper, cal) == 1050);
  CHECK(pb::servo_pulse_us(kPaper.r_min_um + eighth / 4, kPaper, cal) == 1025);
  CHECK(pb::servo_pulse_us(10, kPaper, cal) == 1000);
  CHECK(pb::servo_pulse_us(900000, kPaper, cal) == 1750);
  uint16_t previous = 0;
  for (uint32_t r = kPaper.r_min_um; r <= kPaper.r_max_um; r += 37) {
    const uint16_t p = pb::servo_pulse_us(r, kPaper, cal);
    CHECK(p >= previous);
    previous = p;
  }
}

TEST_CASE("a falling calibration table and out-of-range entries still give sane pulses") {
  const uint16_t falling[9] = {2000, 1900, 1800, 1700, 1600, 1500, 1400, 1300, 1200};
  const uint32_t eighth = (kPaper.r_max_um - kPaper.r_min_um) / 8;
  CHECK(pb::servo_pulse_us(kPaper.r_min_um + eighth / 2, kPaper, falling) == 1950);
  const uint16_t wild[9] = {100, 100, 100, 100, 100, 3000, 3000, 3000, 3000};
  CHECK(pb::servo_pulse_us(kPaper.r_min_um, kPaper, wild) == 500);
  CHECK(pb::servo_pulse_us(kPaper.r_max_um, kPaper, wild) == 2500);
  const pb::Geometry flat = {80000, 80000};
  CHECK(pb::servo_pulse_us(90000, flat, falling) == 2000);
}

TEST_CASE("a motion gives its radius from the time alone, stepping every 20 ms") {
  const pb::Motion m = pb::Motion::cycle(1000, 150);
  CHECK(m.radius_um(999, kPaper) == kPaper.r_min_um);
  CHECK(m.radius_um(1000 + 75 * 20, kPaper) == kPaper.r_max_um);
  CHECK(m.radius_um(1000 + 75 * 20 + 19, kPaper) == kPaper.r_max_um);
  CHECK(m.radius_um(1000 + 76 * 20, kPaper) == pb::cycle_radius_um(76, 150, kPaper));
  CHECK_FALSE(m.finished(1000 + 150 * 20 - 1));
  CHECK(m.finished(1000 + 150 * 20));
  CHECK(m.duration_ms() == 3000);
  // Across the 32-bit wrap of the millisecond clock.
  const pb::Motion w = pb::Motion::cycle(0xFFFFFF00u, 150);
  CHECK(w.radius_um(0xFFFFFF00u + 75 * 20, kPaper) == kPaper.r_max_um);
  CHECK(pb::Motion::hold().finished(0));
  CHECK(pb::Motion::hold().radius_um(123, kPaper) == kPaper.r_min_um);
}
