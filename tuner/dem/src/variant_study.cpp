#include "contactlab/tuner_dem/variant_study.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>

namespace contactlab::dem {
namespace {

struct Run {
  double seconds = 0.0;
  double force_seconds = 0.0;
  std::size_t particles = 0;
  std::vector<double> position;  // x, y, z by stable id
  std::vector<double> diameter;  // by stable id
};

Run run(const std::function<std::unique_ptr<Engine>(const ForceVariant&, int)>& make_engine,
        const ForceVariant& variant, int threads, std::uint64_t steps) {
  std::unique_ptr<Engine> engine = make_engine(variant, threads);
  engine->step();  // untimed: first touches of the variant's buffers
  const PhaseTimes before = engine->phase_times();
  const double t0 = omp_get_wtime();
  engine->run_steps(steps);
  Run r;
  r.seconds = omp_get_wtime() - t0;
  r.force_seconds = (engine->phase_times() - before).force_s();
  const Particles& p = engine->particles();
  r.particles = p.size();
  std::uint32_t max_id = 0;
  for (const std::uint32_t id : p.id) max_id = std::max(max_id, id);
  r.position.assign(3 * (std::size_t{max_id} + 1), 0.0);
  r.diameter.assign(std::size_t{max_id} + 1, 0.0);
  for (std::size_t a = 0; a < p.size(); ++a) {
    const std::size_t id = p.id[a];
    r.position[3 * id] = p.x[a];
    r.position[3 * id + 1] = p.y[a];
    r.position[3 * id + 2] = p.z[a];
    r.diameter[id] = 2.0 * p.radius[a];
  }
  return r;
}

}  // namespace

std::vector<VariantStudyRow> variant_study(
    const std::function<std::unique_ptr<Engine>(const ForceVariant&, int)>& make_engine,
    const std::vector<ForceVariant>& variants, const std::vector<int>& thread_counts,
    std::uint64_t steps) {
  std::vector<VariantStudyRow> rows;
  for (const int threads : thread_counts) {
    const Run reference = run(make_engine, ForceVariant{}, threads, steps);
    for (const ForceVariant& variant : variants) {
      const Run r =
          variant == ForceVariant{} ? reference : run(make_engine, variant, threads, steps);
      VariantStudyRow row;
      row.variant = variant;
      row.threads = threads;
      row.seconds = r.seconds;
      row.force_seconds_per_step = r.force_seconds / static_cast<double>(steps);
      row.particle_steps_per_s =
          static_cast<double>(r.particles) * static_cast<double>(steps) / r.seconds;
      row.speedup = reference.seconds / r.seconds;
      row.bit_identical = r.position == reference.position;
      for (std::size_t id = 0; id < r.diameter.size() && id < reference.diameter.size(); ++id) {
        if (r.diameter[id] == 0.0) continue;  // no particle with this id (removed)
        const double d = std::hypot(r.position[3 * id] - reference.position[3 * id],
                                    r.position[3 * id + 1] - reference.position[3 * id + 1],
                                    r.position[3 * id + 2] - reference.position[3 * id + 2]);
        row.max_deviation = std::max(row.max_deviation, d / r.diameter[id]);
      }
      rows.push_back(row);
    }
  }
  return rows;
}

}  // namespace contactlab::dem
