// Position estimation of SI section S4: each method turns light readings into S_n (1 = nearest).
#ifndef PARTICLEBOT_ESTIMATION_H
#define PARTICLEBOT_ESTIMATION_H

#include <stddef.h>
#include <stdint.h>

#include "protocol_gen.h"

namespace pb {

// S_n saturates here: STATUS and the schedule carry it in one byte.
const uint8_t kMaxSn = 255;

// Every method returns S_n in 1..255 (saturating), never divides by zero and accepts any input:
// readings above 1023, empty groups (others may be NULL when count is 0), parameters outside
// their protocol ranges (clamped to them).
// An unknown method gives 0. Integer arithmetic only: the AVR build carries no float library.
struct EstimationParams {
  int32_t ref_distance_mm;  // method A: r_x (REF_DISTANCE_MM)
  int32_t ref_value;        // method A: V_x (REF_VALUE)
  int32_t diameter_mm;      // method A: D (DIAMETER_MM)
  int32_t count_tolerance;  // method D: readings this close are one level (COUNT_TOLERANCE)
  int32_t groups;           // methods B and C: N_w (GROUPS); 0 or less: one per row (below)
};

// (A) eqs. 14-16: D_n = sqrt(r_n^2 - r_x^2) with r_n^2 from eq. 14, S_n = 1 + round(D_n / D),
// rounding halves up, computed exactly. V_n == 0 (no light at all) gives 255, V_n >= 1023 gives
// 1; a reading at least as bright as V_x gives 1.
uint8_t estimate_direct(uint16_t own, const EstimationParams &p);

// N_w of methods B and C: GROUPS, or with GROUPS 0 the rows the group spans toward the lamp,
// one contracted diameter each: S_n of its weakest reading by method A less that of its
// strongest, plus one (eqs. 14-16 with the reference point's parameters). The SI derives eq. 30
// for a body N particles long in the radial direction (eqs. 19-22), where rho N is the particle's
// place n in diameters: in a line that is one group per particle, in a blob one per row, so that
// a row expands together. (One group per particle heard split a 10-particle blob's four rows into
// ten steps of the wave, and the blob hardly moved: README, closed-loop phototaxis.)

// (B) eqs. 17-18 over the group {own} + others: S_n = 1 + min(floor((V_max - V_n) / dV), N_w - 1)
// with dV = (V_max - V_min) / N_w. A group of one, or V_max == V_min, gives 1.
uint8_t estimate_linear(uint16_t own, const uint16_t *others, size_t count,
                        const EstimationParams &p);

// (C) eqs. 29-30: rho from the square roots of (1023 - V) / V for V_n, V_max, V_min, S_n =
// 1 + min(floor(N_w * rho), N_w - 1). Readings of 0 count as 1 and readings above 1023 as 1023
// (a root of 0: at the lamp). The integer result equals the exact formula wherever N_w * rho is
// more than 2.5e-4 from a group boundary. The brightest particle and a uniform group give 1.
uint8_t estimate_nonlinear(uint16_t own, const uint16_t *others, size_t count,
                           const EstimationParams &p);

// (D) Algorithm 4 with a fixed order: the readings strictly stronger than own, taken strongest
// first; each one more than `tolerance` below the last counted level is a new level.
// S_n = 1 + levels. The SI counts in arrival order, which lets the same readings give different
// counts (and a farther particle a smaller S_n) depending on who spoke first; walking them in
// sorted order makes S_n depend only on the set of readings and never decrease with distance.
uint8_t estimate_counting(uint16_t own, const uint16_t *others, size_t count, int32_t tolerance);

// Dispatch on the protocol's method enum (0 DIRECT, 1 LINEAR, 2 NONLINEAR, 3 COUNTING).
uint8_t estimate(uint8_t method, uint16_t own, const uint16_t *others, size_t count,
                 const EstimationParams &p);

// Readings heard in one estimation round, one per sender: a later copy from the same sender
// replaces the earlier one; senders beyond the 32nd are ignored.
class IntensityRecord {
 public:
  static const uint8_t kCapacity = 32;

  IntensityRecord() : count_(0) {}
  void clear() { count_ = 0; }
  // False when the record is full and the sender is new.
  PB_MUST_USE bool add(uint8_t sender, uint16_t reading);
  uint8_t count() const { return count_; }
  const uint16_t *readings() const { return readings_; }

 private:
  uint16_t readings_[kCapacity];
  uint8_t senders_[kCapacity];
  uint8_t count_;
};

}  // namespace pb

#endif  // PARTICLEBOT_ESTIMATION_H
