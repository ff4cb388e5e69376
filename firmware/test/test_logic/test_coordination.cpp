// Unit tests of the run schedule: rounds, common start, t_I, cycles, pauses, epochs, STOP.
#include <doctest.h>

#include "coordination.h"

namespace {

const pb::Geometry kPaper = {77500, 117500};

pb::RunConfig config(uint8_t method, uint16_t cycle_steps, uint8_t wave_size) {
  pb::RunConfig c;
  c.run_id = 1;
  c.method = method;
  c.cycle_steps = cycle_steps;
  c.wave_size = wave_size;
  c.wave_size_param = 5;
  c.broadcast_repeats = 5;
  c.phototaxis = false;
  c.update_interval_ms = 60000;
  c.round_ms = 3000;
  return c;
}

const uint8_t kCounting = static_cast<uint8_t>(pb::Method::COUNTING);
const uint8_t kDirect = static_cast<uint8_t>(pb::Method::DIRECT);

// Polls at every millisecond from `from` to `to`, finishing rounds with result r; returns the
// number of broadcasts seen.
int run(pb::Coordinator &c, uint32_t from, uint32_t to, const pb::RoundResult &r) {
  int broadcasts = 0;
  for (uint32_t t = from; t <= to; ++t) {
    for (;;) {
      const pb::Coordinator::Event e = c.poll(t, true);
      if (e == pb::Coordinator::kNone) break;
      if (e == pb::Coordinator::kBroadcast) ++broadcasts;
      if (e == pb::Coordinator::kRoundEnd) c.finish_round(r);
    }
  }
  return broadcasts;
}

pb::RoundResult result(uint8_t s_n, uint8_t group, uint16_t intensity) {
  pb::RoundResult r;
  r.s_n = s_n;
  r.group_size = group;
  r.intensity = intensity;
  return r;
}

}  // namespace

TEST_CASE("a run waits t_I after the common start, then cycles every T + t_p") {
  pb::Rng rng(1);
  pb::Coordinator c(rng);
  const uint32_t t0 = 5000;
  c.start(config(kCounting, 150, 4), t0, kPaper.r_min_um, kPaper);
  CHECK(c.state() == pb::State::ESTIMATING);
  CHECK(c.running());
  const uint32_t common = t0 + 3000;
  const uint32_t first = common + 2 * 1500;  // S_n = 3: t_I = 2 * T / 2
  run(c, t0, first - 1, result(3, 4, 500));
  CHECK(c.state() == pb::State::WAITING);
  CHECK(c.s_n() == 3);
  CHECK(c.pause_ms() == 3 * 1500);  // t_p = (N - 1) T / 2 with N = wave_size 4
  run(c, first, first, result(3, 4, 500));
  CHECK(c.state() == pb::State::CYCLING);
  CHECK(c.motion().start_ms == first);
  CHECK(c.cycle_phase_permille(first + 1500) == 500);
  run(c, first + 1, first + 2999, result(3, 4, 500));
  CHECK(c.state() == pb::State::CYCLING);
  run(c, first + 3000, first + 3000, result(3, 4, 500));
  CHECK(c.state() == pb::State::PAUSED);
  CHECK(c.cycle_phase_permille(first + 3000) == 0);
  run(c, first + 3001, first + 3000 + 4500, result(3, 4, 500));
  CHECK(c.state() == pb::State::CYCLING);
  CHECK(c.motion().start_ms == first + 3000 + 4500);
}

TEST_CASE("the wave size falls back to the group heard, or WAVE_SIZE for method A") {
  pb::Rng rng(1);
  pb::Coordinator c(rng);
  c.start(config(kCounting, 100, 0), 0, kPaper.r_min_um, kPaper);
  run(c, 0, 3000, result(1, 6, 500));
  CHECK(c.pause_ms() == 5 * 1000);
  c.start(config(kDirect, 100, 0), 10000, kPaper.r_min_um, kPaper);
  run(c, 10000, 13000, result(1, 1, 500));
  CHECK(c.pause_ms() == 4 * 1000);  // wave_size_param 5
}

TEST_CASE("copies of the intensity go out in the first 70 % of a round, none for method A") {
  pb::Rng rng(7);
  pb::Coordinator c(rng);
  c.start(config(kCounting, 150, 0), 0, kPaper.r_min_um, kPaper);
  CHECK(run(c, 0, 2099, result(1, 1, 1)) == 5);
  CHECK(run(c, 2100, 2999, result(1, 1, 1)) == 0);
  c.start(config(kDirect, 150, 0), 10000, kPaper.r_min_um, kPaper);
  CHECK(run(c, 10000, 13000, result(1, 1, 1)) == 0);
}

TEST_CASE("broadcasts wait until the owner has its reading") {
  pb::Rng rng(3);
  pb::Coordinator c(rng);
  c.start(config(kCounting, 150, 0), 0, kPaper.r_min_um, kPaper);
  for (uint32_t t = 0; t < 2100; ++t) CHECK(c.poll(t, false) == pb::Coordinator::kNone);
  int sent = 0;
  while (c.poll(2100, true) == pb::Coordinator::kBroadcast) ++sent;
  CHECK(sent == 5);
}

TEST_CASE("an epoch ends contracted and the next round starts at its boundary") {
  pb::Rng rng(1);
  pb::Coordinator c(rng);
  pb::RunConfig cfg = config(kCounting, 150, 3);
  cfg.update_interval_ms = 20000;
  c.start(cfg, 0, kPaper.r_min_um, kPaper);
  // S_n = 2: cycles start at 4500 + k * 6000 (T 3000 + t_p 3000); 16500 would end at 19500,
  // 22500 would end after the epoch (20000), so it is not started.
  int round_starts = 0;
  uint32_t last_cycle_start = 0;
  for (uint32_t t = 0; t < 20000; ++t) {
    for (;;) {
      const pb::Coordinator::Event e = c.poll(t, true);
      if (e == pb::Coordinator::kNone) break;
      if (e == pb::Coordinator::kRoundEnd) c.finish_round(result(2, 3, 500));
      if (e == pb::Coordinator::kRoundStart) ++round_starts;
    }
    if (c.state() == pb::State::CYCLING) last_cycle_start = c.motion().start_ms;
  }
  CHECK(last_cycle_start == 16500);
  CHECK(c.state() == pb::State::PAUSED);
  CHECK(round_starts == 0);
  CHECK(c.poll(20000, true) == pb::Coordinator::kRoundStart);
  CHECK(c.state() == pb::State::ESTIMATING);
  CHECK(c.round() == 1);
  CHECK(c.epoch_start_ms() == 20000);
}

TEST_CASE("an epoch is at least one round, one cycle, one pause and half a period long") {
  pb::Rng rng(1);
  pb::Coordinator c(rng);
  pb::RunConfig cfg = config(kCounting, 300, 5);
  cfg.update_interval_ms = 1000;
  c.start(cfg, 0, kPaper.r_min_um, kPaper);
  run(c, 0, 3000, result(5, 5, 500));
  CHECK(c.epoch_end_ms() == 3000 + 6000 + 4 * 3000 + 3000);
}

TEST_CASE("t_I is eq. 5's less whole wave periods, so the first cycle comes within one period") {
  pb::RunConfig cfg = config(kCounting, 100, 3);  // T = 2000, t_p = 2000, period 4000
  const uint32_t expected[] = {0, 1000, 2000, 3000, 0, 1000, 2000, 3000, 0};
  for (uint8_t s_n = 1; s_n <= 9; ++s_n) {
    CHECK(pb::plan_epoch(cfg, s_n, 9).first_cycle_ms == expected[s_n - 1]);
  }
  CHECK(pb::plan_epoch(cfg, 255, 9).first_cycle_ms == 254 % 4 * 1000);
  CHECK(pb::plan_epoch(cfg, 0, 9).first_cycle_ms == 0);  // no estimate counts as S_n = 1
  cfg.wave_size = 255;  // a wave period of 256 half periods: S_n never wraps
  CHECK(pb::plan_epoch(cfg, 255, 9).first_cycle_ms == 254u * 1000);
}

// Every cycle start of a run polled every servo step for three epochs, checked against eq. 5
// modulo the wave period; returns the fewest cycles any epoch held.
int fewest_cycles_per_epoch(uint16_t cycle_steps, uint8_t wave, uint8_t s_n, uint32_t interval) {
  pb::Rng rng(1);
  pb::Coordinator c(rng);
  pb::RunConfig cfg = config(kDirect, cycle_steps, wave);
  cfg.update_interval_ms = interval;
  c.start(cfg, 0, kPaper.r_min_um, kPaper);
  const uint32_t half = cycle_steps * 10u;
  const uint32_t wave_period = (wave + 1u) * half;
  int cycles[3] = {0, 0, 0};
  uint32_t last_start = 0xFFFFFFFFul;
  uint32_t epoch_start = 0;
  uint32_t epoch_end = 0;
  for (uint32_t t = 0;; t += pb::kStepMs) {
    for (;;) {
      const pb::Coordinator::Event e = c.poll(t, true);
      if (e == pb::Coordinator::kNone) break;
      if (e == pb::Coordinator::kRoundEnd) c.finish_round(result(s_n, 9, 500));
    }
    if (c.round() == 3) break;
    epoch_start = c.epoch_start_ms();
    epoch_end = c.epoch_end_ms();  // final once the round has ended
    if (c.state() != pb::State::CYCLING || c.motion().start_ms == last_start) continue;
    last_start = c.motion().start_ms;
    ++cycles[c.round()];
    const uint32_t since_common = last_start - epoch_start - cfg.round_ms;
    CHECK((since_common + wave_period - (s_n - 1u) * half % wave_period) % wave_period == 0);
    CHECK(last_start + cycle_steps * pb::kStepMs <= epoch_end);
  }
  int fewest = cycles[0];
  for (int k = 1; k < 3; ++k) fewest = cycles[k] < fewest ? cycles[k] : fewest;
  return fewest;
}

TEST_CASE("every particle cycles in every epoch, even at the shortest update interval") {
  // The grid: T = 1.5, 3, 6 s, N and S_n 1..9, at 10 s and 30 s; and the far back of a
  // deep wave. Eq. 5 as written left 77 of these 324 cases at 10 s without a single cycle.
  const uint16_t periods[] = {75, 150, 300};
  const uint32_t intervals[] = {10000, 30000};
  for (uint32_t interval : intervals) {
    for (uint16_t steps : periods) {
      for (uint8_t wave = 1; wave <= 9; ++wave) {
        for (uint8_t s_n = 1; s_n <= 9; ++s_n) {
          CAPTURE(interval);
          CAPTURE(steps);
          CAPTURE(wave);
          CAPTURE(s_n);
          CHECK(fewest_cycles_per_epoch(steps, wave, s_n, interval) >= 1);
        }
      }
    }
  }
  CHECK(fewest_cycles_per_epoch(300, 5, 200, 10000) >= 1);
  CHECK(fewest_cycles_per_epoch(75, 1, 255, 10000) >= 1);
}

TEST_CASE("phototaxis ends the run when the intensity stops increasing") {
  pb::Rng rng(1);
  pb::Coordinator c(rng);
  pb::RunConfig cfg = config(kCounting, 100, 1);
  cfg.update_interval_ms = 10000;
  cfg.phototaxis = true;
  c.start(cfg, 0, kPaper.r_min_um, kPaper);
  run(c, 0, 9999, result(1, 1, 500));
  run(c, 10000, 19999, result(1, 1, 520));  // brighter: carry on
  CHECK(c.state() != pb::State::DONE);
  run(c, 20000, 23000, result(1, 1, 520));  // not brighter: done
  CHECK(c.state() == pb::State::DONE);
  CHECK(c.running());
  CHECK(c.motion().radius_um(23000, kPaper) == kPaper.r_min_um);
}

TEST_CASE("STOP ramps down from the current radius and then idles") {
  pb::Rng rng(1);
  pb::Coordinator c(rng);
  c.start(config(kCounting, 150, 1), 0, kPaper.r_min_um, kPaper);
  run(c, 0, 3000 + 1500, result(1, 1, 500));  // halfway through the first cycle
  CHECK(c.state() == pb::State::CYCLING);
  const uint32_t r = c.motion().radius_um(4500, kPaper);
  c.stop(4500, r, kPaper);
  CHECK(c.state() == pb::State::STOPPING);
  CHECK_FALSE(c.running());
  CHECK(c.motion().radius_um(4500, kPaper) == r);
  run(c, 4501, 4500 + 599, result(1, 1, 500));
  CHECK(c.state() == pb::State::STOPPING);
  run(c, 5100, 5100, result(1, 1, 500));
  CHECK(c.state() == pb::State::IDLE);
  CHECK(c.motion().radius_um(5100, kPaper) == kPaper.r_min_um);
}

TEST_CASE("a repeated STOP neither restarts the ramp nor wakes an idle particle") {
  pb::Rng rng_once(1), rng_twice(1);
  pb::Coordinator once(rng_once), twice(rng_twice);
  pb::Coordinator *const both[] = {&once, &twice};
  for (pb::Coordinator *c : both) {
    c->start(config(kCounting, 150, 1), 0, kPaper.r_min_um, kPaper);
    run(*c, 0, 3000 + 1500, result(1, 1, 500));
    c->stop(4500, c->motion().radius_um(4500, kPaper), kPaper);
  }
  // A later copy of the same STOP, 300 ms into the ramp.
  twice.stop(4800, twice.motion().radius_um(4800, kPaper), kPaper);
  CHECK(twice.state() == pb::State::STOPPING);
  for (uint32_t t = 4800; t <= 5100; t += 20) {
    CHECK(twice.motion().radius_um(t, kPaper) == once.motion().radius_um(t, kPaper));
  }
  run(twice, 4801, 5100, result(1, 1, 500));
  CHECK(twice.state() == pb::State::IDLE);
  twice.stop(5200, kPaper.r_min_um, kPaper);
  CHECK(twice.state() == pb::State::IDLE);
}

TEST_CASE("IDENTIFY wiggles only an idle particle") {
  pb::Rng rng(1);
  pb::Coordinator c(rng);
  CHECK(c.identify(100));
  CHECK(c.state() == pb::State::IDENTIFYING);
  CHECK_FALSE(c.identify(200));
  run(c, 101, 100 + 1499, result(1, 1, 1));
  CHECK(c.state() == pb::State::IDENTIFYING);
  run(c, 1600, 1600, result(1, 1, 1));
  CHECK(c.state() == pb::State::IDLE);
  c.start(config(kCounting, 150, 1), 2000, kPaper.r_min_um, kPaper);
  CHECK_FALSE(c.identify(2001));
}

TEST_CASE("a late poll catches up through every transition at its scheduled time") {
  pb::Rng rng(1);
  pb::Coordinator c(rng);
  c.start(config(kCounting, 150, 2), 0, kPaper.r_min_um, kPaper);
  // One poll 10 s in: round end at 3000, cycles at 3000 and 3000 + 3000 + 1500 = 7500.
  for (;;) {
    const pb::Coordinator::Event e = c.poll(10000, true);
    if (e == pb::Coordinator::kNone) break;
    if (e == pb::Coordinator::kRoundEnd) c.finish_round(result(1, 2, 500));
  }
  CHECK(c.state() == pb::State::CYCLING);
  CHECK(c.motion().start_ms == 7500);
}

TEST_CASE("a START during motion ramps the body down before any cycle") {
  pb::Rng rng(1);
  pb::Coordinator c(rng);
  pb::RunConfig cfg = config(kCounting, 150, 1);
  cfg.round_ms = 200;  // shorter than the 600 ms ramp
  c.start(cfg, 0, kPaper.r_max_um, kPaper);
  CHECK(c.motion().radius_um(0, kPaper) == kPaper.r_max_um);
  run(c, 0, 2000, result(1, 1, 500));
  // The cycle due at 200 ms was skipped (the ramp ran until 600 ms); the next is at 200 + 3000.
  CHECK(c.state() == pb::State::WAITING);
  run(c, 2001, 3200, result(1, 1, 500));
  CHECK(c.state() == pb::State::CYCLING);
  CHECK(c.motion().start_ms == 3200);
}
