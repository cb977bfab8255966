// Google Benchmark of DEM steps on a settled bed: particle-steps per second per thread count,
// and the phase split (neighbour list, pair forces, reduction, update, integration).
//
// The bed is the checkpoint of experiments/dem/settle-bed.json when CONTACTLAB_DEM_BENCH_CONFIG
// and CONTACTLAB_DEM_BENCH_CHECKPOINT name them; otherwise a small bed of
// CONTACTLAB_DEM_BENCH_N spheres (default 4096) settled here at t_c/10 (for the smoke test).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdlib>
#include <memory>
#include <string>

#include "contactlab/dem/checkpoint.hpp"
#include "contactlab/dem/config.hpp"
#include "contactlab/dem/engine.hpp"

namespace {

using namespace contactlab::dem;

struct Bed {
  EngineSettings settings;
  Particles initial;
  std::string checkpoint;  // empty: settled in `settled`
  std::unique_ptr<Engine> settled;
};

const char* env(const char* name) { return std::getenv(name); }

Bed& bed() {
  static Bed b = [] {
    Bed made;
    if (env("CONTACTLAB_DEM_BENCH_CONFIG") && env("CONTACTLAB_DEM_BENCH_CHECKPOINT")) {
      const DemConfig config = read_dem_config(env("CONTACTLAB_DEM_BENCH_CONFIG"));
      made.settings = config.settings;
      made.initial = make_particles(config);
      made.checkpoint = env("CONTACTLAB_DEM_BENCH_CHECKPOINT");
      return made;
    }
    const long n = env("CONTACTLAB_DEM_BENCH_N") ? std::atol(env("CONTACTLAB_DEM_BENCH_N")) : 4096;
    DemConfig config;
    config.materials = {{"glass", 2500.0}};
    EngineSettings& s = config.settings;
    s.law.kind = NormalLawKind::kStiffness;  // the settle-bed law (LAMMPS' numbers)
    s.law.normal_stiffness = 654.29;
    s.law.normal_damping = 7133.4989;
    s.law.friction = 0.5;
    s.gravity = {0, 0, -9.81};
    s.skin = 1e-4;
    s.warn_large_overlaps = false;
    const double side = 16e-3;
    s.domain.lo = {0, 0, 0};
    s.domain.hi = {side, side, 1.0};
    s.domain.periodic = {true, true, false};
    Wall floor;
    floor.name = "floor";
    s.walls.push_back(floor);
    LatticeSpec lattice;
    lattice.lo = {0, 0, 0};
    lattice.hi = {side, side, 1.0};
    lattice.count = static_cast<std::uint32_t>(n);
    lattice.radius_min = lattice.radius_max = 5e-4;
    lattice.material = "glass";
    lattice.gap = 0.1;
    config.lattices = {lattice};
    made.initial = make_particles(config);
    s.dt_s = 1e-5;  // settle at t_c/10, then time at t_c/50
    made.settled = std::make_unique<Engine>(s, made.initial);
    made.settled->run_steps(3000);
    s.dt_s = 2e-6;
    return made;
  }();
  return b;
}

std::unique_ptr<Engine> fresh_engine(int threads, bool fused) {
  Bed& b = bed();
  EngineSettings s = b.settings;
  s.threads = threads;
  s.force_variant.fused_update = fused;
  s.warn_large_overlaps = false;
  auto engine = std::make_unique<Engine>(s, b.initial);
  if (!b.checkpoint.empty()) {
    read_checkpoint(*engine, b.checkpoint);
  } else {
    engine->restore(b.settled->state(), b.settled->particles(), b.settled->pairs());
  }
  return engine;
}

// The default force variant (update in its own loop after the pairs: the phase shares split
// pair forces from update), or with the update fused into the pair pass.
void run_steps(benchmark::State& state, bool fused) {
  const int threads = static_cast<int>(state.range(0));
  std::unique_ptr<Engine> engine = fresh_engine(threads, fused);
  engine->run_steps(20);  // warm-up: first touches, one rebuild if due
  const PhaseTimes before = engine->phase_times();
  const std::uint64_t near_builds_before = engine->near_builds();
  // Batches of steps, as a run goes between outputs (each finish drifts the next step).
  constexpr std::uint64_t kBatch = 10;
  std::uint64_t steps = 0;
  while (state.KeepRunningBatch(kBatch)) {
    engine->run_steps(kBatch);
    steps += kBatch;
  }
  const PhaseTimes spent = engine->phase_times() - before;
  const double n = static_cast<double>(engine->particles().size());
  state.counters["particle_steps_per_s"] =
      benchmark::Counter(n * static_cast<double>(steps), benchmark::Counter::kIsRate);
  const double total = spent.total_s();
  state.counters["share_neighbor"] = spent.neighbor_s / total;
  state.counters["share_pair_forces"] = spent.pair_forces_s / total;
  state.counters["share_reduction"] = spent.reduction_s / total;
  state.counters["share_update"] = (spent.walls_s + spent.update_s) / total;
  state.counters["share_integration"] = spent.integrate_s / total;
  std::uint64_t touching = 0;  // pair and wall contacts with a force, each counted per particle
  for (const auto t : engine->particles().contacts) touching += t;
  state.counters["contacts_per_particle"] = static_cast<double>(touching) / n;
  state.counters["pairs_per_particle"] = static_cast<double>(engine->pairs().size()) / n;
  state.counters["max_span"] = static_cast<double>(engine->pairs().max_span);
  // The near pairs the force pass ran on (near_pairs.hpp), and how often they were chosen.
  state.counters["near_pairs_per_particle"] = static_cast<double>(engine->force_pairs().size()) / n;
  state.counters["steps_per_near_build"] =
      static_cast<double>(steps) /
      static_cast<double>(std::max<std::uint64_t>(1, engine->near_builds() - near_builds_before));
  // The instruction set the step ran on (CONTACTLAB_SIMD chooses another, as for detection).
  state.SetLabel("step on " + to_string(engine->instruction_set()));
}

void BM_DemStep(benchmark::State& state) { run_steps(state, false); }
void BM_DemStepFused(benchmark::State& state) { run_steps(state, true); }
BENCHMARK(BM_DemStep)
    ->Arg(1)
    ->Arg(2)
    ->ArgName("threads")
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_DemStepFused)
    ->Arg(1)
    ->Arg(2)
    ->ArgName("threads")
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
