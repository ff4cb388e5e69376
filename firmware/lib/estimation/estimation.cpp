// The four S_n estimators and the per-round record of readings heard.
#include "estimation.h"

#include "protocol_gen.h"
#include "settings.h"

namespace pb {

namespace {

const uint16_t kFullScale = 1023;
const uint8_t kMaxIndex = 255;

uint8_t saturate_index(uint32_t zero_based) {
  return zero_based >= kMaxIndex ? kMaxIndex : static_cast<uint8_t>(zero_based + 1);
}

// floor(sqrt(x)), bit by bit: no float library on the AVR.
uint32_t isqrt(uint32_t x) {
  uint32_t root = 0;
  for (uint32_t bit = 1ul << 30; bit != 0; bit >>= 2) {
    if (x >= root + bit) {
      x -= root + bit;
      root = (root >> 1) + bit;
    } else {
      root >>= 1;
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

// N_w: the GROUPS parameter, or one group per particle in {own} + others. Capped so every
// product below fits 32 bits; a group that large saturates S_n anyway.
uint32_t group_count(size_t count, int32_t groups) {
  if (groups > 0) return static_cast<uint32_t>(clamp_to_spec(Param::GROUPS, groups));
  const uint32_t cap = 0xFFFFu;
  return count >= cap ? cap : static_cast<uint32_t>(count) + 1;
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

// sqrt((1023 - V) / V) = sqrt(R_n / R_R) in fixed point with 11 fraction bits (eqs. 26-28), V
// clamped to 1..1022: (1023 - V) * 2^22 just fits 32 bits, and the root is proportional to the
// distance to the lamp.
uint32_t root_resistance(uint16_t v) {
  if (v < 1) v = 1;
  if (v > kFullScale - 1) v = kFullScale - 1;
  return isqrt((static_cast<uint32_t>(kFullScale - v) << 22) / v);
}

}  // namespace

uint8_t estimate_direct(uint16_t own, const EstimationParams &p) {
  if (own == 0) return kMaxIndex;
  if (own >= kFullScale) return 1;
  const uint32_t v_x = static_cast<uint32_t>(clamp_to_spec(Param::REF_VALUE, p.ref_value));
  if (own >= v_x) return 1;
  const uint32_t r_x =
      static_cast<uint32_t>(clamp_to_spec(Param::REF_DISTANCE_MM, p.ref_distance_mm));
  const uint32_t d = static_cast<uint32_t>(clamp_to_spec(Param::DIAMETER_MM, p.diameter_mm));
  // Eqs. 14-15: D_n^2 = r_n^2 - r_x^2 = r_x^2 * 1023 (V_x - V_n) / (V_n (1023 - V_x)). With
  // q = floor(4 D_n^2 / D^2) and z = floor(sqrt(q)) = floor(2 D_n / D), eq. 16 rounded half up is
  // round(D_n / D) = (z + 1) / 2 exactly, in integers (both sides fit 64 bits).
  // Factors: 4 r_x^2 < 2^29, 1023 (V_x - V_n) < 2^20, D^2 < 2^20, V_n (1023 - V_x) < 2^20.
  const uint32_t q =
      wide_quotient(4 * r_x * r_x, kFullScale * (v_x - own), d * d, own * (kFullScale - v_x));
  const uint32_t saturated = 509ul * 509ul;  // z >= 509 gives S_n >= 256
  if (q >= saturated) return kMaxIndex;
  return saturate_index((isqrt(q) + 1) / 2);
}

uint8_t estimate_linear(uint16_t own, const uint16_t *others, size_t count, int32_t groups) {
  if (count == 0 || others == NULL) return 1;
  uint16_t v_max, v_min;
  extremes(own, others, count, &v_max, &v_min);
  if (v_max == v_min) return 1;
  const uint32_t n_w = group_count(count, groups);
  // floor((V_max - V_n) / ((V_max - V_min) / N_w)) in integers: (V_max - V_n) * N_w < 2^32.
  uint32_t index = static_cast<uint32_t>(v_max - own) * n_w / static_cast<uint32_t>(v_max - v_min);
  if (index > n_w - 1) index = n_w - 1;
  return saturate_index(index);
}

uint8_t estimate_nonlinear(uint16_t own, const uint16_t *others, size_t count, int32_t groups) {
  if (count == 0 || others == NULL) return 1;
  uint16_t v_max, v_min;
  extremes(own, others, count, &v_max, &v_min);
  const uint32_t a = root_resistance(v_max);
  const uint32_t b = root_resistance(v_min);
  if (b <= a) return 1;  // V_max == V_min once clamped
  const uint32_t c = root_resistance(own);
  const uint32_t n_w = group_count(count, groups);
  // Eq. 30 with eq. 29's rho = (c - a) / (b - a): n_w and c - a are both below 2^16.
  uint32_t index = n_w * (c - a) / (b - a);
  if (index > n_w - 1) index = n_w - 1;
  return saturate_index(index);
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
      return estimate_linear(own, others, count, p.groups);
    case static_cast<uint8_t>(Method::NONLINEAR):
      return estimate_nonlinear(own, others, count, p.groups);
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
