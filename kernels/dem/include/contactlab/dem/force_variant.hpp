// How the DEM force pass runs in parallel, as a value: what `dem run --variant` parses, what
// `dem variants` times against the deterministic default, and what a tuner enumerates.
//
// Text form: ACCUMULATION/SCHEDULE, then the named parts `walls=serial` and `update=fused`
// when they are not the default, e.g. "ordered/static", "per-thread/dynamic,4",
// "atomic/guided,16/walls=serial".
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "contactlab/kernels/variant.hpp"

namespace contactlab::dem {

// Where a pair's two sides are summed.
// kOrdered: per particle in pair order (its own row, then its j sides; a j side for another
// thread's particle is left in the pair list for it): bit-identical for any thread count.
// kPerThread: one force/torque array per thread, summed per particle in thread order
// afterwards (Otsuka's report): the same result for the same thread count and schedule.
// kAtomic: one shared array, `omp atomic` adds: the order, hence the last bits, vary run to run.
// kFullList: each pair computed twice, once for each side, each particle's sums written only by
// the thread that owns it (no shared writes, any schedule): the sums of kOrdered in its order,
// bit-identical to it for any thread count and schedule, for twice the pair work.
enum class Accumulation { kOrdered, kPerThread, kAtomic, kFullList };

// Rows per block of the pair pass, the unit its schedule deals out (and the force model counts
// work in): enough pairs (about 4 a row) for full SIMD lanes, few enough that a block's records
// are still in L1 when their particles are summed.
inline constexpr std::size_t kRowsPerBlock = 64;

struct ForceVariant {
  Accumulation accumulation = Accumulation::kOrdered;
  // Of the blocks of 64 rows (kOrdered: "static" only, each thread one contiguous range).
  Schedule schedule;
  // Wall contacts by one thread after the pairs (the report's), not in each particle's finish.
  bool serial_walls = false;
  // The update (walls, gravity, kick) as soon as a particle's sums are complete, inside the
  // pair pass (the report's `nowait` loops), not in its own loop after all pairs. Separate is
  // the default: on the bed it was as fast on one thread and 1.14x faster on two (the fused
  // pass's last max_span particles of each range wait for the barrier).
  bool fused_update = false;
  friend bool operator==(const ForceVariant&, const ForceVariant&) = default;
};

std::string_view to_string(Accumulation accumulation);
std::string to_string(const ForceVariant& variant);
// Throws InputError with a one-line message naming the bad part, or the rule it breaks.
ForceVariant parse_force_variant(std::string_view text);
// The rule between parts that `variant` breaks, or nothing: ordered accumulation needs the
// static block partition; the update is fused only where a particle's sums are complete
// before all pairs are (ordered, full list), and never with serial walls.
std::optional<std::string_view> broken_rule(const ForceVariant& variant);
// Whether the trajectory is the same for any thread count and schedule (kOrdered, kFullList).
bool thread_count_invariant(const ForceVariant& variant);

// Every accumulation with static and, where allowed, static,k, dynamic,k and guided,k for each k
// in `chunks`, each with separate and (where allowed) fused update and parallel walls, plus the
// report's configuration (per-thread/dynamic,1 with serial walls).
std::vector<ForceVariant> force_variants(const std::vector<int>& chunks);

}  // namespace contactlab::dem
