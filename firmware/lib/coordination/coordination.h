// Run schedule of SI Algorithms 2-3: estimation rounds, common start, t_I, cycles, epochs, STOP.
#ifndef PARTICLEBOT_COORDINATION_H
#define PARTICLEBOT_COORDINATION_H

#include <stdint.h>

#include "actuation.h"
#include "protocol_gen.h"

namespace pb {

// Linear congruential generator (Numerical Recipes constants) for jitter and broadcast instants
// only, so size matters more than quality; the weak low bits are never used.
class Rng {
 public:
  explicit Rng(uint32_t seed) : state_(seed) {}
  // 16 random bits.
  uint16_t next();
  // Roughly uniform in 0 .. n-1 (0 when n is 0). 16 bits suffice: every interval it draws from
  // (a broadcast slot, a STATUS period) is at most 60 000 ms.
  uint16_t below(uint16_t n) { return n == 0 ? 0 : static_cast<uint16_t>(next() % n); }

 private:
  uint32_t state_;
};

// Everything a run needs, fixed at START (SET_PARAM is refused while running).
struct RunConfig {
  uint8_t run_id;
  uint8_t method;             // enum Method
  uint16_t cycle_steps;       // n: T = n * 20 ms
  uint8_t wave_size;          // N from START; 0: automatic
  uint8_t wave_size_param;    // WAVE_SIZE: method A's automatic N
  uint8_t broadcast_repeats;  // INTENSITY copies per round (methods B-D)
  bool phototaxis;            // Algorithm 3: finish when the intensity stops increasing
  uint32_t update_interval_ms;
  uint32_t round_ms;
};

// What the owner learnt in a round: its S_n, the particles heard (itself included) and the
// intensity it used.
struct RoundResult {
  uint8_t s_n;
  uint8_t group_size;
  uint16_t intensity;
};

// When an epoch's cycles happen, from the estimate of its round (times in ms).
struct EpochPlan {
  uint32_t first_cycle_ms;  // after the common start: t_I less whole wave periods
  uint32_t pause_ms;        // t_p between cycles
  uint32_t epoch_ms;        // from the round's start to the next round's
};

// The plan for a particle of estimate s_n (0 counts as 1) that heard group_size particles, itself
// included, in a run of `config`. N is the START's wave size, or when automatic WAVE_SIZE for
// method A and group_size otherwise. Pure, so the vectorised model can be checked against it.
//   t_p = (N - 1) T / 2 (eq. 3); the wave period is T + t_p = (N + 1) T / 2.
//   First cycle at ((S_n - 1) mod (N + 1)) T / 2 after the common start: eq. 5's t_I less whole
//   wave periods, so every cycle keeps eq. 5's phase relative to every other particle.
//   E = max(update interval, round + T + t_p + T / 2): the latest first cycle (N T / 2 + T)
//   ends inside it, so every particle runs at least one cycle per epoch whatever S_n, T, N and
//   the interval, as Algorithm 2 does. E depends on N, never on S_n, so particles that heard the
//   same group keep starting their rounds together.
// Why not eq. 5 as written: with t_I growing with S_n and cycles confined to a common epoch, the
// back of a deep wave would wait past the epoch's end and never move (77 of the 324 cases of
// T = 1.5, 3, 6 s, N and S_n = 1..9 at the protocol's shortest 10 s interval; S_n reaches 255),
// and lengthening the epoch by S_n would give each particle its own epoch and part the swarm's
// rounds. Taking t_I modulo the wave period is also how the published simulator phases its
// particles.
EpochPlan plan_epoch(const RunConfig &config, uint8_t s_n, uint8_t group_size);

// Timeline of one run, all times from the START receipt t0:
//   epoch k starts at t0 + sum of earlier epoch lengths, with a round of round_ms;
//   common start C = epoch start + round_ms; cycle j starts at C + first_cycle_ms + j (T + t_p)
//   (see plan_epoch); a cycle only starts if it ends by the epoch's end, so the body is
//   contracted at every boundary and a new S_n never makes it jump.
// poll() is a pure function of the stored schedule and now_ms: it can be called at any rate, and a
// late call catches up through every transition that fell due, each at its exact scheduled time.
class Coordinator {
 public:
  enum Event {
    kNone = 0,
    kRoundStart,  // a new round began: clear what was heard, take a fresh reading
    kBroadcast,   // send INTENSITY copy broadcast_repeat() now
    kRoundEnd,    // estimate, then call finish_round() before polling again
  };

  explicit Coordinator(Rng &rng);

  // Starts a run at now_ms with round 0. A body that is not contracted (START during a cycle,
  // wiggle or stop) first ramps down as after STOP. No kRoundStart is reported for round 0: the
  // owner prepares it right away, since readings for it may arrive before the next poll.
  void start(const RunConfig &config, uint32_t now_ms, uint32_t radius_now_um, const Geometry &g);
  // From any state: smoothly back to R_min from radius_now_um (STOPPING), then IDLE. Already
  // STOPPING or IDLE: nothing changes (a repeated STOP does not restart the ramp).
  void stop(uint32_t now_ms, uint32_t radius_now_um, const Geometry &g);
  // IDLE only: three wiggles (IDENTIFYING), then IDLE. False in any other state.
  PB_MUST_USE bool identify(uint32_t now_ms);

  // Advances the schedule to now_ms and returns the first event that needs the owner (kNone when
  // there is none). Call it again until kNone. can_broadcast holds INTENSITY back until the
  // round's reading is in.
  Event poll(uint32_t now_ms, bool can_broadcast);
  void finish_round(const RoundResult &result);

  State state() const { return static_cast<State>(state_); }
  bool running() const;  // in a run: ESTIMATING, WAITING, CYCLING, PAUSED or DONE
  const Motion &motion() const { return motion_; }
  // Position in the current cycle in 1/1000 of T; 0 outside a cycle.
  uint16_t cycle_phase_permille(uint32_t now_ms) const;

  uint8_t run_id() const { return config_.run_id; }
  uint8_t method() const { return config_.method; }
  uint16_t round() const { return round_; }
  uint8_t s_n() const { return s_n_; }
  uint8_t group_size() const { return group_size_; }
  uint8_t broadcast_repeat() const { return last_repeat_; }
  uint32_t epoch_start_ms() const { return epoch_start_ms_; }
  uint32_t epoch_end_ms() const { return epoch_end_ms_; }
  uint32_t pause_ms() const { return pause_ms_; }
  uint32_t period_ms() const { return static_cast<uint32_t>(config_.cycle_steps) * kStepMs; }

 private:
  void begin_round(uint32_t at_ms);
  void schedule_broadcast();
  bool cycle_fits(uint32_t start_ms) const;
  void settle_ramp(uint32_t now_ms);

  Rng &rng_;
  RunConfig config_;
  Motion motion_;
  uint32_t epoch_start_ms_;
  uint32_t epoch_end_ms_;
  uint32_t next_cycle_ms_;
  uint32_t pause_ms_;
  uint32_t next_broadcast_ms_;
  uint16_t round_;
  uint16_t previous_intensity_;
  uint8_t state_;
  uint8_t s_n_;
  uint8_t group_size_;
  uint8_t repeat_;       // next INTENSITY copy to send
  uint8_t last_repeat_;  // the copy the last kBroadcast asked for
  bool have_previous_;
  bool round_start_pending_;
};

}  // namespace pb

#endif  // PARTICLEBOT_COORDINATION_H
