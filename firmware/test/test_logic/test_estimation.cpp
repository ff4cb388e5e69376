// Unit tests of the S_n estimators (SI section S4) and the per-round record of readings.
#include <doctest.h>
#include <math.h>

#include "estimation.h"
#include "protocol_gen.h"

namespace {

const uint8_t kDirect = static_cast<uint8_t>(pb::Method::DIRECT);
const uint8_t kLinear = static_cast<uint8_t>(pb::Method::LINEAR);
const uint8_t kNonlinear = static_cast<uint8_t>(pb::Method::NONLINEAR);
const uint8_t kCounting = static_cast<uint8_t>(pb::Method::COUNTING);

pb::EstimationParams paper_params() {
  pb::EstimationParams p;
  p.ref_distance_mm = 280;
  p.ref_value = 980;
  p.diameter_mm = 155;
  p.count_tolerance = 10;
  p.groups = 0;
  return p;
}

// The paper's parameters with GROUPS = groups (N_w of methods B and C; 0: one per row).
pb::EstimationParams with_groups(int groups) {
  pb::EstimationParams p = paper_params();
  p.groups = groups;
  return p;
}

// Eq. 11 with the SI's calibration (V_x = 980 at r_x = 280 mm, R_R = 1.5 MOhm): the reading of a
// photocell at distance r_mm from the lamp, unrounded.
double reading_at(double r_mm) {
  const double r_r = 1.5e6;
  const double r_x = (1023.0 - 980.0) * r_r / 980.0;  // eq. 13
  const double r_n = (r_mm / 280.0) * (r_mm / 280.0) * r_x;
  return 1023.0 * r_r / (r_n + r_r);
}

}  // namespace

TEST_CASE("direct estimation ranks a particle by diameters from the point under the lamp") {
  const pb::EstimationParams p = paper_params();
  for (int k = 0; k < 6; ++k) {
    // k diameters along the floor from the reference point, 280 mm under the lamp.
    const double planar = 155.0 * k;
    const uint16_t v =
        static_cast<uint16_t>(lround(reading_at(sqrt(280.0 * 280.0 + planar * planar))));
    CHECK(pb::estimate(kDirect, v, NULL, 0, p) == k + 1);
  }
}

TEST_CASE("direct estimation handles the ends of the ADC range and odd parameters") {
  pb::EstimationParams p = paper_params();
  CHECK(pb::estimate_direct(0, p) == 255);
  CHECK(pb::estimate_direct(1023, p) == 1);
  CHECK(pb::estimate_direct(2000, p) == 1);
  CHECK(pb::estimate_direct(980, p) == 1);
  CHECK(pb::estimate_direct(1, p) == 255);
  p.ref_value = 5000;  // clamped to 1022
  p.diameter_mm = 0;   // clamped to 10
  p.ref_distance_mm = -3;
  const uint8_t s = pb::estimate_direct(500, p);
  CHECK(s >= 1);
  // The same as with the nearest in-range values given outright.
  pb::EstimationParams in_range = p;
  in_range.ref_value = 1022;
  in_range.diameter_mm = 10;
  in_range.ref_distance_mm = 10;
  CHECK(s == pb::estimate_direct(500, in_range));
  CHECK(s != pb::estimate_direct(500, paper_params()));
}

TEST_CASE("linear estimation splits the group's intensity range into equal bands") {
  const uint16_t group[] = {1000, 800, 600, 400, 200};
  const uint8_t expected[] = {1, 2, 3, 4, 5};
  for (int i = 0; i < 5; ++i) {
    uint16_t others[4];
    int n = 0;
    for (int j = 0; j < 5; ++j) {
      if (j != i) others[n++] = group[j];
    }
    // N_w = 5, dV = 160: (1000 - V) / 160 floored, the weakest clamped into the last band.
    CHECK(pb::estimate(kLinear, group[i], others, 4, with_groups(5)) == expected[i]);
  }
  const uint16_t two_groups[] = {1000, 200};
  CHECK(pb::estimate_linear(599, two_groups, 2, with_groups(2)) == 2);
  CHECK(pb::estimate_linear(601, two_groups, 2, with_groups(2)) == 1);
}

TEST_CASE("linear and nonlinear estimation give 1 to a lone particle or a uniform group") {
  const uint16_t same[] = {500, 500, 500};
  const pb::EstimationParams p = paper_params();
  CHECK(pb::estimate_linear(500, same, 3, p) == 1);
  CHECK(pb::estimate_nonlinear(500, same, 3, p) == 1);
  CHECK(pb::estimate_linear(500, NULL, 0, p) == 1);
  CHECK(pb::estimate_nonlinear(500, NULL, 0, p) == 1);
  const uint16_t clamped_alike[] = {0, 1};  // both read as 1 once clamped
  CHECK(pb::estimate_nonlinear(0, clamped_alike, 2, p) == 1);
}

TEST_CASE("nonlinear estimation recovers positions from an inverse-square field") {
  // Particles at (K + n) D from the lamp in a plane, n = 0..4, as in Fig. S7; rho = n / 4.
  const double d = 155.0;
  const double k = 2.0;
  uint16_t v[5];
  for (int n = 0; n < 5; ++n) v[n] = static_cast<uint16_t>(lround(reading_at((k + n) * d)));
  for (int i = 0; i < 5; ++i) {
    uint16_t others[4];
    int m = 0;
    for (int j = 0; j < 5; ++j) {
      if (j != i) others[m++] = v[j];
    }
    // N_w = 5: floor(5 * i / 4) = 0, 1, 2, 3, 5 -> clamped 4.
    CHECK(pb::estimate(kNonlinear, v[i], others, 4, with_groups(5)) == i + 1);
  }
}

// The reading of a photocell whose particle stands ground_mm along the floor from the point
// under the lamp, 280 mm below it (the reference height of method A).
uint16_t reading_on_floor(double ground_mm) {
  return static_cast<uint16_t>(lround(reading_at(sqrt(ground_mm * ground_mm + 280.0 * 280.0))));
}

TEST_CASE("with GROUPS 0 methods B and C give one group per row of the group toward the lamp") {
  // A blob's rows: two particles a few centimetres apart 0.5 m out, two one diameter further,
  // one two diameters further. Each row expands together: S_n is the row, as method A gives it.
  const double ground[] = {500, 530, 655, 680, 810};
  const uint8_t row[] = {1, 1, 2, 2, 3};
  uint16_t v[5];
  for (int i = 0; i < 5; ++i) v[i] = reading_on_floor(ground[i]);
  for (int i = 0; i < 5; ++i) {
    uint16_t others[4];
    int m = 0;
    for (int j = 0; j < 5; ++j) {
      if (j != i) others[m++] = v[j];
    }
    CAPTURE(i);
    CHECK(pb::estimate(kLinear, v[i], others, 4, paper_params()) == row[i]);
    CHECK(pb::estimate(kNonlinear, v[i], others, 4, paper_params()) == row[i]);
  }
  // In a line, one diameter apart, that is one group per particle: its rank.
  uint16_t line[6];
  for (int n = 0; n < 6; ++n) line[n] = reading_on_floor(400 + 155.0 * n);
  for (int i = 0; i < 6; ++i) {
    uint16_t others[5];
    int m = 0;
    for (int j = 0; j < 6; ++j) {
      if (j != i) others[m++] = line[j];
    }
    CHECK(pb::estimate(kNonlinear, line[i], others, 5, paper_params()) == i + 1);
  }
}

// N_w: GROUPS, or the rows between the group's strongest and weakest readings by method A.
int group_count(uint16_t hi, uint16_t lo, int groups) {
  if (groups > 0) return groups;
  const pb::EstimationParams p = paper_params();
  return pb::estimate_direct(lo, p) - pb::estimate_direct(hi, p) + 1;
}

// Eqs. 29-30 in double precision: N_w rho, or -1 for a degenerate group.
double nonlinear_groups(uint16_t own, const uint16_t *others, int count, int groups) {
  uint16_t hi = own, lo = own;
  for (int i = 0; i < count; ++i) {
    hi = others[i] > hi ? others[i] : hi;
    lo = others[i] < lo ? others[i] : lo;
  }
  const double a = sqrt((1023.0 - hi) / hi);
  const double b = sqrt((1023.0 - lo) / lo);
  if (b <= a) return -1;
  return group_count(hi > 1023 ? 1023 : hi, lo < 1 ? 1 : lo, groups) *
         (sqrt((1023.0 - own) / own) - a) / (b - a);
}

TEST_CASE("nonlinear estimation matches eqs. 29-30 for close readings and 64 groups") {
  // The 11-bit roots put a particle whole groups off here: 31 readings 822..850 (the one at 843
  // got 9 for the exact 8) and 64 groups over readings 2 counts apart (7 off).
  for (int spacing = 1; spacing <= 3; ++spacing) {
    for (int base = 1; base + 40 * spacing <= 1023; base += 7) {
      uint16_t group[41];
      for (int i = 0; i < 41; ++i) group[i] = static_cast<uint16_t>(base + spacing * i);
      const int sizes[] = {31, 41};
      for (int size : sizes) {
        for (int i = 0; i < size; ++i) {
          uint16_t others[40];
          int n = 0;
          for (int j = 0; j < size; ++j) {
            if (j != i) others[n++] = group[j];
          }
          const int groups_choices[] = {0, size, 64};
          for (int groups : groups_choices) {
            const double x = nonlinear_groups(group[i], others, n, groups);
            const int n_w = group_count(group[size - 1], group[0], groups);
            if (fabs(x - floor(x + 0.5)) < 1e-3) continue;  // on a group boundary
            const int expected = 1 + (x >= n_w - 1 ? n_w - 1 : static_cast<int>(floor(x)));
            CAPTURE(base);
            CAPTURE(spacing);
            CAPTURE(group[i]);
            CHECK(pb::estimate_nonlinear(group[i], others, n, with_groups(groups)) == expected);
          }
        }
      }
    }
  }
}

TEST_CASE("nonlinear estimation takes 1023 as at the lamp and 0 as 1") {
  const uint16_t others[] = {1022, 900};
  // 1023 is the brightest possible reading (root 0), no longer the same as 1022.
  const pb::EstimationParams p = paper_params();
  CHECK(pb::estimate_nonlinear(1023, others, 2, p) == 1);
  const uint16_t with_full[] = {1023, 900};
  const double x = nonlinear_groups(1022, with_full, 2, 0);
  CHECK(x > 0.1);
  CHECK(pb::estimate_nonlinear(1022, with_full, 2, p) == 1 + static_cast<int>(floor(x)));
  const uint16_t over[] = {4000, 900};  // above full scale reads as 1023
  CHECK(pb::estimate_nonlinear(1022, over, 2, p) == pb::estimate_nonlinear(1022, with_full, 2, p));
  const uint16_t dark[] = {0, 1};  // no light counts as 1: the farthest
  CHECK(pb::estimate_nonlinear(500, dark, 2, with_groups(3)) == 1);
  CHECK(pb::estimate_nonlinear(0, dark + 1, 1, with_groups(3)) == 1);
}

TEST_CASE("counting estimation counts distinct stronger levels whatever the arrival order") {
  const uint16_t heard[] = {800, 805, 700, 600, 400};
  CHECK(pb::estimate_counting(500, heard, 5, 10) == 4);  // 805, 700, 600 (800 joins 805)
  const uint16_t reversed[] = {400, 600, 700, 805, 800};
  CHECK(pb::estimate_counting(500, reversed, 5, 10) == 4);
  CHECK(pb::estimate_counting(500, heard, 5, 0) == 5);
  CHECK(pb::estimate_counting(900, heard, 5, 10) == 1);
  // A chain of readings 8 apart: distance is measured from the last counted level, so 532 and
  // 516 count while 524 and 508 join them.
  const uint16_t chain[] = {508, 516, 524, 532};
  CHECK(pb::estimate_counting(500, chain, 4, 10) == 3);
  CHECK(pb::estimate_counting(500, heard, 0, 10) == 1);
}

TEST_CASE("an unknown method gives 0") {
  CHECK(pb::estimate(4, 500, NULL, 0, paper_params()) == 0);
}

TEST_CASE("the record keeps one reading per sender and at most 32 senders") {
  pb::IntensityRecord r;
  CHECK(r.add(7, 100));
  CHECK(r.add(7, 120));
  CHECK(r.count() == 1);
  CHECK(r.readings()[0] == 120);
  for (uint8_t s = 0; s < 31; ++s) CHECK(r.add(static_cast<uint8_t>(100 + s), s));
  CHECK(r.count() == 32);
  CHECK_FALSE(r.add(1, 5));
  CHECK(r.add(7, 130));  // a known sender still updates when full
  CHECK(r.readings()[0] == 130);
  r.clear();
  CHECK(r.count() == 0);
}
