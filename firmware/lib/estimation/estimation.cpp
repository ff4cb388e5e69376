// The four S_n estimators and the per-round record of readings heard.
#include "estimation.h"

#include "protocol_gen.h"
#include "settings.h"

namespace pb {

namespace {

const uint16_t kFullScale = 1023;
const uint8_t kMaxIndex = kMaxSn;

uint8_t saturate_index(uint32_t zero_based) {
  return zero_based >= kMaxIndex ? kMaxIndex : static_cast<uint8_t>(zero_based + 1);
}

// S_n of the group index eq. 18 or eq. 30 gives: 1 + min(index, N_w - 1).
__attribute__((noinline)) uint8_t band(uint32_t index, uint32_t n_w) {
  return saturate_index(index > n_w - 1 ? n_w - 1 : index);
}

// floor(sqrt(m) * 2^13) for m < 2^18, two bits of the radicand (m followed by 26 zero bits) per
// iteration: no float library on the AVR. The remainder stays below twice the root (< 2^23), so
// everything fits 32 bits. One routine for both uses keeps the flash cost down.
__attribute__((noinline)) uint32_t sqrt_q13(uint32_t m) {
  uint32_t x = m << 14;  // the radicand's first bit pair at the top
  uint32_t root = 0;
  uint32_t rem = 0;
  for (uint8_t i = 2 * 22; i != 0; --i) {  // 9 pairs from m, 13 zero pairs
    rem = (rem << 1) | (x >> 31);
    x <<= 1;
    if (i & 1) {
      root <<= 1;
      const uint32_t trial = (root << 1) | 1;
      if (rem >= trial) {
        rem -= trial;
        root |= 1;
      }
    }
  }
  return root;
}

// floor((a * b) / (c * d)) saturated to 32 bits, in one place because 64-bit arithmetic is
// bulky on the AVR.
__attribute__((noinline)) uint32_t wide_quotient(uint32_t a, uint32_t b, uint32_t c, uint32_t d) {
  const uint64_t q = static_cast<uint64_t>(a) * b / (static_cast<uint64_t>(c) * d);
  return q > 0xFFFFFFFFull ? 0xFFFFFFFFul : static_cast<uint32_t>(q);
}

// N_w: the GROUPS parameter, or (GROUPS 0) the rows of particles the group spans toward the
// lamp: its farthest and nearest members' S_n by method A, eqs. 14-16, apart, plus one. The SI
// divides the group into groups of one particle along the radial direction (eqs. 19-22: a body
// N D long); in a line that is one group per particle, in a blob one per row. N_w <= 255.
uint8_t group_count(uint16_t v_max, uint16_t v_min, const EstimationParams &p) {
  if (p.groups > 0) return static_cast<uint8_t>(clamp_to_spec(Param::GROUPS, p.groups));
  return static_cast<uint8_t>(estimate_direct(v_min, p) - estimate_direct(v_max, p) + 1);
}

void extremes(uint16_t own, const uint16_t *others, size_t count, uint16_t *v_max,
              uint16_t *v_min) {
  uint16_t hi = own;
  uint16_t lo = own;
  for (size_t i = 0; i < count; ++i) {
    if (others[i] > hi) hi = others[i];
    if (others[i] < lo) lo = others[i];
  }
  *v_max = hi;
  *v_min = lo;
}

// Readings as eqs. 29-30 may use them: 0 (no light: an infinite distance) is taken as 1, and
// anything above full scale as 1023 (a distance of 0).
__attribute__((noinline)) uint16_t usable_reading(uint16_t v) {
  if (v < 1) return 1;
  return v > kFullScale ? kFullScale : v;
}

// g(V) = sqrt((1023 - V) V) rounded to 12 fraction bits (the floor with 13, halved), at most
// 2.1e-6 of itself off for V in 1..1022 and exact for 1023. Since sqrt((1023 - V) / V) is g / V,
// these give eqs. 26-28's roots.
uint32_t root_term(uint16_t v) {
  return (sqrt_q13(static_cast<uint32_t>(kFullScale - v) * v) + 1) >> 1;
}

// g(V_a) V_b + g(V_b) V_a: the sums of eq. 29 rewritten below.
__attribute__((noinline)) uint32_t cross_sum(uint16_t v_a, uint16_t v_b) {
  return root_term(v_a) * v_b + root_term(v_b) * v_a;
}

}  // namespace

uint8_t estimate_direct(uint16_t own, const EstimationParams &p) {
  if (own == 0) return kMaxIndex;
  // V_x is below full scale (REF_VALUE's range), so this also takes readings of 1023 and above.
  const uint32_t v_x = static_cast<uint32_t>(clamp_to_spec(Param::REF_VALUE, p.ref_value));
  if (own >= v_x) return 1;
  const uint32_t r_x =
      static_cast<uint32_t>(clamp_to_spec(Param::REF_DISTANCE_MM, p.ref_distance_mm));
  const uint32_t d = static_cast<uint32_t>(clamp_to_spec(Param::DIAMETER_MM, p.diameter_mm));
  // Eqs. 14-15: D_n^2 = r_n^2 - r_x^2 = r_x^2 * 1023 (V_x - V_n) / (V_n (1023 - V_x)). With
  // q = floor(4 D_n^2 / D^2) and z = floor(sqrt(q)) = floor(2 D_n / D), eq. 16 rounded half up is
  // round(D_n / D) = (z + 1) / 2 exactly, in integers (both sides fit 64 bits).
  // Factors: 4 r_x^2 < 2^29, 1023 (V_x - V_n) < 2^20, D^2 < 2^20, V_n (1023 - V_x) < 2^20.
  const uint32_t q = wide_quotient(4 * r_x * r_x, kFullScale * (v_x - own), d * d,
                                   static_cast<uint32_t>(own) * (kFullScale - v_x));
  const uint32_t saturated = 509ul * 509ul;  // z >= 509 gives S_n >= 256
  if (q >= saturated) return kMaxIndex;
  return saturate_index(((sqrt_q13(q) >> 13) + 1) / 2);
}

uint8_t estimate_linear(uint16_t own, const uint16_t *others, size_t count,
                        const EstimationParams &p) {
  uint16_t v_max, v_min;  // a group of one gives v_max == v_min below
  extremes(own, others, count, &v_max, &v_min);
  if (v_max == v_min) return 1;
  const uint32_t n_w = group_count(v_max, v_min, p);
  // floor((V_max - V_n) / ((V_max - V_min) / N_w)) in integers: (V_max - V_n) * N_w < 2^32.
  return band(static_cast<uint32_t>(v_max - own) * n_w / static_cast<uint32_t>(v_max - v_min), n_w);
}

uint8_t estimate_nonlinear(uint16_t own, const uint16_t *others, size_t count,
                           const EstimationParams &p) {
  uint16_t v_max, v_min;  // a group of one gives v_max == v_min below
  extremes(own, others, count, &v_max, &v_min);
  v_max = usable_reading(v_max);
  v_min = usable_reading(v_min);
  own = usable_reading(own);
  if (own >= v_max || v_max == v_min) return 1;  // the brightest, or a uniform group
  // Eq. 29's rho = (c - a) / (b - a) with a, b, c = g / V of V_max, V_min, V_n. Written as
  // c - a = 1023 (V_max - V_n) / (V_n V_max (c + a)) and likewise b - a, it becomes
  //   rho = (V_max - V_n) (g_max V_min + g_min V_max) / ((V_max - V_min) (g_max V_n + g_n V_max)),
  // which subtracts only exact integers. The roots' rounding moves rho by at most 4.2e-6 of
  // itself, so N_w rho is exact to 2.7e-4 for every group the firmware can form (N_w <= 64) and to
  // 1.1e-3 wherever S_n is below its ceiling of 255 (the 11-bit roots of eq. 29 as written were
  // off by whole groups for close readings). Factors: N_w (V_max - V_n) < 2^26; each sum of two
  // products stays below 2.8e9 (checked for every pair of readings).
  const uint32_t n_w = group_count(v_max, v_min, p);
  return band(wide_quotient(n_w * (v_max - own), cross_sum(v_max, v_min), v_max - v_min,
                            cross_sum(v_max, own)),  // eq. 30
              n_w);
}

uint8_t estimate_counting(uint16_t own, const uint16_t *others, size_t count, int32_t tolerance) {
  if (others == NULL) return 1;
  const uint32_t tol = static_cast<uint32_t>(clamp_to_spec(Param::COUNT_TOLERANCE, tolerance));
  uint32_t levels = 0;
  uint16_t last = 0;
  bool have_last = false;
  // Repeatedly take the strongest reading still more than tol below the last counted level: the
  // same walk as sorting descending, without a scratch copy of the readings.
  for (;;) {
    bool found = false;
    uint16_t best = 0;
    for (size_t i = 0; i < count; ++i) {
      const uint16_t v = others[i];
      if (v <= own) continue;
      if (have_last && static_cast<uint32_t>(last) <= v + tol) continue;  // last - v <= tol
      if (!found || v > best) {
        best = v;
        found = true;
      }
    }
    if (!found) break;
    ++levels;
    if (levels >= kMaxIndex) break;
    last = best;
    have_last = true;
  }
  return saturate_index(levels);
}

uint8_t estimate(uint8_t method, uint16_t own, const uint16_t *others, size_t count,
                 const EstimationParams &p) {
  switch (method) {
    case static_cast<uint8_t>(Method::DIRECT):
      return estimate_direct(own, p);
    case static_cast<uint8_t>(Method::LINEAR):
      return estimate_linear(own, others, count, p);
    case static_cast<uint8_t>(Method::NONLINEAR):
      return estimate_nonlinear(own, others, count, p);
    case static_cast<uint8_t>(Method::COUNTING):
      return estimate_counting(own, others, count, p.count_tolerance);
    default:
      return 0;
  }
}

bool IntensityRecord::add(uint8_t sender, uint16_t reading) {
  for (uint8_t i = 0; i < count_; ++i) {
    if (senders_[i] == sender) {
      readings_[i] = reading;
      return true;
    }
  }
  if (count_ >= kCapacity) return false;
  senders_[count_] = sender;
  readings_[count_] = reading;
  ++count_;
  return true;
}

}  // namespace pb
