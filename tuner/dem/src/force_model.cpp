#include "contactlab/tuner_dem/force_model.hpp"

#include <omp.h>

#include <algorithm>
#include <numeric>

#include "contactlab/kernels/error.hpp"
#include "contactlab/tuner_model/schedule_model.hpp"

namespace contactlab::dem {
namespace {

using tuner::MachineCosts;
using tuner::ScheduleOutcome;
using tuner::WorkView;

int index_of(Accumulation accumulation) { return static_cast<int>(accumulation); }

// The schedule the pass's block loop runs: ordered splits the rows into one contiguous range
// per thread (static block), the others take the variant's.
Schedule pass_schedule(const ForceVariant& variant) {
  return variant.accumulation == Accumulation::kOrdered ? Schedule{ScheduleKind::kStatic, 0}
                                                        : variant.schedule;
}

// A loop over the blocks with `tests` units of per-test cost and `homes` of per-home cost per
// block, and the grabs of a self-scheduled loop.
ScheduleOutcome replay(const std::vector<std::uint32_t>& tests,
                       const std::vector<std::uint32_t>& homes, int threads,
                       const Schedule& schedule, double per_test, double per_home, double per_grab,
                       bool record_chunks) {
  const std::vector<std::uint8_t> no_builds(tests.size(), 0);
  MachineCosts costs;
  for (const auto& [name, field] : tuner::kMachineCostFields) costs.*field = 0.0;
  costs.seconds_per_test = per_test;
  costs.seconds_per_home = per_home;
  costs.seconds_per_grab = per_grab;
  return tuner::simulate_schedule(WorkView(tests, homes, no_builds), threads, schedule, costs,
                                  record_chunks);
}

// Per thread, the j sides its blocks write into blocks another thread runs.
std::vector<std::uint64_t> foreign_j_sides(const ForceLoopWork& work, const ScheduleOutcome& run,
                                           int threads) {
  std::vector<int> owner(work.block_particles.size(), 0);
  for (const tuner::ChunkAssignment& chunk : run.chunks) {
    for (std::uint64_t b = chunk.begin; b < chunk.end; ++b) owner[b] = chunk.thread;
  }
  std::vector<std::uint64_t> foreign(static_cast<std::size_t>(threads), 0);
  for (std::size_t b = 0; b < owner.size(); ++b) {
    for (std::uint32_t e = work.reach_offsets[b]; e < work.reach_offsets[b + 1]; ++e) {
      if (owner[work.reach_block[e]] != owner[b]) {
        foreign[static_cast<std::size_t>(owner[b])] += work.reach_pairs[e];
      }
    }
  }
  return foreign;
}

std::vector<std::uint32_t> zeros_like(const std::vector<std::uint32_t>& v) {
  return std::vector<std::uint32_t>(v.size(), 0);
}

// The pair units of the pass: i sides, or both sides for the full list.
std::vector<std::uint32_t> pass_pairs(const ForceLoopWork& work, const ForceVariant& variant) {
  std::vector<std::uint32_t> pairs = work.own_pairs;
  if (variant.accumulation == Accumulation::kFullList) {
    for (std::size_t b = 0; b < pairs.size(); ++b) pairs[b] += work.j_side_pairs[b];
  }
  return pairs;
}

// The largest share of `units` one thread gets under `schedule`.
double max_share(const std::vector<std::uint32_t>& units, int threads, const Schedule& schedule) {
  return static_cast<double>(
      tuner::simulate_schedule(WorkView(units), threads, schedule).max_thread_tests);
}

}  // namespace

std::uint64_t ForceLoopWork::total_pairs() const {
  return std::accumulate(own_pairs.begin(), own_pairs.end(), std::uint64_t{0});
}

ForceLoopWork force_loop_work(const PairList& pairs, std::size_t particles) {
  ForceLoopWork work;
  work.particles = particles;
  const std::size_t blocks = (particles + kRowsPerBlock - 1) / kRowsPerBlock;
  work.reach_offsets.push_back(0);
  const std::size_t span_blocks = pairs.max_span / kRowsPerBlock + 2;
  std::vector<std::uint32_t> reach(span_blocks + 1, 0);  // by b - (j's block)
  // The j sides by the block of their j, counted from the pairs (the list's j-side index is
  // built only for the full list's pass).
  work.j_side_pairs.assign(blocks, 0);
  for (const std::uint32_t j : pairs.j) ++work.j_side_pairs[j / kRowsPerBlock];
  for (std::size_t b = 0; b < blocks; ++b) {
    const std::size_t first = b * kRowsPerBlock, last = std::min(particles, first + kRowsPerBlock);
    work.block_particles.push_back(static_cast<std::uint32_t>(last - first));
    work.own_pairs.push_back(pairs.rows[last] - pairs.rows[first]);
    for (std::size_t k = pairs.rows[first]; k < pairs.rows[last]; ++k) {
      const std::size_t back = b - pairs.j[k] / kRowsPerBlock;  // j <= i: never negative
      if (back > 0) ++reach[std::min(back, span_blocks)];
    }
    for (std::size_t back = 1; back <= span_blocks; ++back) {
      if (reach[back] == 0) continue;
      work.reach_block.push_back(static_cast<std::uint32_t>(b - back));
      work.reach_pairs.push_back(reach[back]);
      reach[back] = 0;
    }
    work.reach_offsets.push_back(static_cast<std::uint32_t>(work.reach_block.size()));
  }
  return work;
}

ForcePrediction predict_force_pass(const ForceLoopWork& work, const ForceVariant& variant,
                                   int threads, const ForceCosts& c) {
  const int a = index_of(variant.accumulation);
  const Schedule schedule = pass_schedule(variant);
  const bool fused = variant.fused_update;
  const double n = static_cast<double>(work.particles);
  const std::vector<std::uint32_t> pairs = pass_pairs(work, variant);
  const std::vector<std::uint32_t> none = zeros_like(pairs);
  const double per_foreign = c.per_foreign_j_side[a];
  const bool count_foreign = per_foreign > 0.0 && threads > 1;
  const ScheduleOutcome pass =
      replay(pairs, fused ? work.block_particles : none, threads, schedule, c.per_pair[a],
             fused ? c.per_particle_fused : 0.0, c.per_grab, count_foreign);
  ForcePrediction p;
  std::vector<std::uint64_t> foreign(static_cast<std::size_t>(threads), 0);
  if (count_foreign) foreign = foreign_j_sides(work, pass, threads);
  for (std::size_t t = 0; t < pass.threads.size(); ++t) {
    p.pass_seconds = std::max(
        p.pass_seconds, pass.threads[t].seconds + static_cast<double>(foreign[t]) * per_foreign);
  }
  if (variant.accumulation == Accumulation::kPerThread)
    p.reduction_seconds = n * c.per_particle_arrays;
  if (variant.serial_walls) p.walls_seconds = n * c.per_particle_serial_walls;
  if (!fused) {
    const double per_update = std::max(
        0.0, c.per_particle_update - (variant.serial_walls ? c.per_particle_serial_walls : 0.0));
    p.update_seconds =
        replay(none, work.block_particles, threads, schedule, 0.0, per_update, c.per_grab, false)
            .makespan_seconds;
  }
  p.seconds = p.pass_seconds + p.reduction_seconds + p.walls_seconds + p.update_seconds;
  return p;
}

ForceCosts calibrate_force_costs(const EngineFactory& make_engine, int threads,
                                 std::uint64_t steps) {
  if (steps == 0) throw InputError("calibration needs at least one timed step");
  const double start = omp_get_wtime();
  ForceCosts c;
  c.threads = threads;
  c.calibration_steps = steps;
  struct Timed {
    PhaseTimes per_step;  // seconds per step by phase
    ForceLoopWork work;   // of the pair list the timed steps started from
  };
  auto time = [&](const char* text) {
    std::unique_ptr<Engine> engine = make_engine(parse_force_variant(text), threads);
    engine->step();  // untimed: first touches of the variant's buffers
    Timed r{{}, force_loop_work(engine->force_pairs(), engine->particles().size())};
    const PhaseTimes before = engine->phase_times();
    engine->run_steps(steps);
    r.per_step = (engine->phase_times() - before) / static_cast<double>(steps);
    ++c.calibration_runs;
    return r;
  };
  const Schedule block{ScheduleKind::kStatic, 0};
  auto safe = [](double num, double den) { return den > 0 ? std::max(0.0, num / den) : 0.0; };

  const Timed ordered = time("ordered/static");
  const ForceLoopWork& w = ordered.work;
  const double n = static_cast<double>(w.particles);
  const double own_max = max_share(w.own_pairs, threads, block);
  const double part_max = max_share(w.block_particles, threads, block);
  const int o = index_of(Accumulation::kOrdered), pt = index_of(Accumulation::kPerThread),
            at = index_of(Accumulation::kAtomic), fl = index_of(Accumulation::kFullList);
  c.per_pair[o] = safe(ordered.per_step.pair_forces_s, own_max);
  c.per_particle_update = safe(ordered.per_step.update_s, part_max);

  const Timed fused = time("ordered/static/update=fused");
  c.per_particle_fused = safe(fused.per_step.pair_forces_s - c.per_pair[o] * own_max, part_max);

  const Timed full = time("full-list/static");
  c.per_pair[fl] =
      safe(full.per_step.pair_forces_s,
           max_share(pass_pairs(w, parse_force_variant("full-list/static")), threads, block));

  const Timed per_thread = time("per-thread/static");
  c.per_pair[pt] = safe(per_thread.per_step.pair_forces_s, own_max);
  c.per_particle_arrays = safe(per_thread.per_step.reduction_s, n);

  const Timed atomic = time("atomic/static");
  c.per_pair[at] = safe(atomic.per_step.pair_forces_s, own_max);

  const Timed serial = time("ordered/static/walls=serial");
  c.per_particle_serial_walls = safe(serial.per_step.walls_s, n);

  // The ordered pass twice more, apart from its first run: the calibration's own spread.
  {
    auto pass_s = [](const Timed& r) { return r.per_step.pair_forces_s + r.per_step.update_s; };
    std::vector<double> passes{pass_s(ordered), pass_s(time("ordered/static")),
                               pass_s(time("ordered/static"))};
    std::sort(passes.begin(), passes.end());
    c.calibration_spread = passes[1] > 0 ? (passes[2] - passes[0]) / passes[1] : 0.0;
  }

  // The schedules' own costs, from the pass's time over all threads: the pairs' cost plus G
  // grabs and X foreign j sides (counted on the schedule's replay): G g + X x = T pass - P p.
  // static,1 has no grabs (x alone); dynamic,1 then gives g.
  struct Equation {
    double grabs, foreign, rest;
  };
  auto equation = [&](const char* text) {
    const ForceVariant v = parse_force_variant(text);
    const Timed r = time(text);
    const std::vector<std::uint32_t> units = pass_pairs(w, v);
    const ScheduleOutcome sim =
        replay(units, zeros_like(units), threads, v.schedule, 1.0, 0.0, 0.0, threads > 1);
    double grabs = 0.0;
    for (const tuner::ThreadShare& share : sim.threads) grabs += static_cast<double>(share.grabs);
    double foreign = 0.0;
    if (threads > 1) {
      for (const std::uint64_t f : foreign_j_sides(w, sim, threads)) {
        foreign += static_cast<double>(f);
      }
    }
    const double units_total = std::accumulate(units.begin(), units.end(), 0.0);
    return Equation{
        grabs, foreign,
        threads * r.per_step.pair_forces_s - units_total * c.per_pair[index_of(v.accumulation)]};
  };
  if (threads > 1) {
    for (const auto& [text, accumulation] :
         {std::pair{"per-thread/static,1", pt}, std::pair{"full-list/static,1", fl},
          std::pair{"atomic/static,1", at}}) {
      const Equation e = equation(text);
      c.per_foreign_j_side[accumulation] = safe(e.rest, e.foreign);
    }
    // Ordered's few foreign j sides (at its range boundaries) cost what per-thread's do.
    c.per_foreign_j_side[o] = c.per_foreign_j_side[pt];
  }
  const Equation dynamic = equation("per-thread/dynamic,1");
  c.per_grab = safe(dynamic.rest - dynamic.foreign * c.per_foreign_j_side[pt], dynamic.grabs);
  c.calibration_seconds = omp_get_wtime() - start;
  return c;
}

std::vector<RankedVariant> rank_force_variants(const ForceLoopWork& work,
                                               const std::vector<ForceVariant>& candidates,
                                               int threads, const ForceCosts& costs) {
  std::vector<RankedVariant> ranked;
  ranked.reserve(candidates.size());
  for (const ForceVariant& v : candidates) {
    ranked.push_back({v, predict_force_pass(work, v, threads, costs)});
  }
  std::stable_sort(ranked.begin(), ranked.end(), [](const auto& x, const auto& y) {
    return x.prediction.seconds < y.prediction.seconds;
  });
  return ranked;
}

ForceRetuner::Decision ForceRetuner::decide(const Engine& engine,
                                            const ForceVariant& current) const {
  const ForceLoopWork work = force_loop_work(engine.force_pairs(), engine.particles().size());
  const int threads = engine.settings().threads;
  const std::vector<RankedVariant> ranked = rank_force_variants(work, candidates_, threads, costs_);
  const double now = predict_force_pass(work, current, threads, costs_).seconds;
  const RankedVariant& best = ranked.front();
  Decision d{current, best.variant,
             best.prediction.seconds > 0 ? now / best.prediction.seconds - 1.0 : 0.0, false};
  if (d.predicted_gain > margin_ && !(best.variant == current)) {
    d.variant = best.variant;
    d.switched = true;
  }
  return d;
}

}  // namespace contactlab::dem
