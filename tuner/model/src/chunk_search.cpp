#include "contactlab/tuner_model/chunk_search.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>

namespace contactlab::tuner {

namespace {

bool overlaps(const MedianInterval& a, const MedianInterval& b) {
  return a.low <= b.high && b.low <= a.high;
}

void validate(const ChunkSearchOptions& options, const char* function) {
  const std::string name(function);
  if (options.grid.empty()) throw std::invalid_argument(name + ": the chunk grid is empty");
  for (std::size_t i = 0; i < options.grid.size(); ++i) {
    if (options.grid[i] < 1 || (i > 0 && options.grid[i] <= options.grid[i - 1])) {
      throw std::invalid_argument(name + ": grid[" + std::to_string(i) +
                                  "] = " + std::to_string(options.grid[i]) +
                                  ": the grid must be ascending, distinct and >= 1");
    }
  }
  if (!(options.level > 0.0 && options.level < 1.0)) {
    throw std::invalid_argument(name + ": level = " + std::to_string(options.level) +
                                " must be in (0, 1)");
  }
  if (options.budget.max_evaluations < 1 || !(options.budget.max_measure_seconds > 0.0)) {
    throw std::invalid_argument(
        name + ": budget of " + std::to_string(options.budget.max_evaluations) +
        " evaluations and " + std::to_string(options.budget.max_measure_seconds) +
        " s (need >= 1 and > 0)");
  }
  if (options.seed_chunk < 0 || options.confirmation_rounds < 0 || options.rounds < 1 ||
      !(options.equivalence_margin >= 0.0)) {
    throw std::invalid_argument(
        name + ": seed_chunk = " + std::to_string(options.seed_chunk) +
        ", confirmation_rounds = " + std::to_string(options.confirmation_rounds) +
        ", equivalence_margin = " + std::to_string(options.equivalence_margin) +
        " must be >= 0, rounds = " + std::to_string(options.rounds) + " >= 1");
  }
}

// The measurements made so far on the grid, the budget, and the final choice.
class GridSearch {
 public:
  GridSearch(const MeasureChunk& measure, const ChunkSearchOptions& options, bool budgeted,
             const char* function)
      : measure_(measure),
        options_(options),
        budgeted_(budgeted),
        function_(function),
        entries_(options.grid.size()) {
    for (std::size_t i = 0; i < options.grid.size(); ++i) entries_[i].chunk = options.grid[i];
    if (options.with_block) entries_.push_back(ChunkMeasurement{});  // chunk 0: the largest
  }

  std::size_t size() const { return entries_.size(); }
  bool measured(std::size_t i) const { return entries_[i].evaluations > 0; }

  // Calls measure(grid[i]) once more; false (nothing measured) when the budget is spent.
  bool measure_once(std::size_t i) {
    if (budgeted_ && evaluations_ >= options_.budget.max_evaluations) {
      stop_ = SearchStop::kEvaluationBudget;
      return false;
    }
    if (budgeted_ && measuring_seconds_ >= options_.budget.max_measure_seconds) {
      stop_ = SearchStop::kTimeBudget;
      return false;
    }
    ChunkMeasurement& entry = entries_[i];
    const auto start = std::chrono::steady_clock::now();
    const std::vector<double> samples = measure_(entry.chunk);
    measuring_seconds_ +=
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    ++evaluations_;
    if (samples.empty()) {
      throw std::invalid_argument(std::string(function_) + ": measure(" +
                                  std::to_string(entry.chunk) + ") returned no samples");
    }
    for (const double sample : samples) {
      if (!std::isfinite(sample) || sample < 0.0) {
        throw std::invalid_argument(std::string(function_) + ": measure(" +
                                    std::to_string(entry.chunk) + ") returned the sample " +
                                    std::to_string(sample) + " (need finite, >= 0)");
      }
      sampled_seconds_ += sample;
    }
    entry.samples_seconds.insert(entry.samples_seconds.end(), samples.begin(), samples.end());
    entry.evaluations += 1;
    entry.median_seconds = contactlab::median(entry.samples_seconds);
    entry.interval = median_interval(entry.samples_seconds, options_.level);
    return true;
  }

  // The median of grid[i], measuring it first if it has not been; nullopt: budget spent.
  std::optional<double> median(std::size_t i) {
    if (!measured(i) && !measure_once(i)) return std::nullopt;
    return entries_[i].median_seconds;
  }

  const MedianInterval& interval(std::size_t i) const { return entries_[i].interval; }

  // Smallest median; ties go to the larger chunk. Requires at least one measurement.
  std::size_t fastest() const {
    std::optional<std::size_t> best;
    for (std::size_t i = 0; i < entries_.size(); ++i) {
      if (measured(i) && (!best || entries_[i].median_seconds <= entries_[*best].median_seconds)) {
        best = i;
      }
    }
    return *best;
  }

  // Statistically and practically as fast as grid[best]: intervals overlap, and the median is
  // within the equivalence margin.
  bool equivalent(std::size_t i, std::size_t best) const {
    return measured(i) && overlaps(entries_[i].interval, entries_[best].interval) &&
           entries_[i].median_seconds <=
               (1.0 + options_.equivalence_margin) * entries_[best].median_seconds;
  }

  // The largest measured chunk equivalent to the fastest.
  std::size_t chosen() const {
    const std::size_t best = fastest();
    std::size_t choice = best;
    for (std::size_t i = best + 1; i < entries_.size(); ++i) {
      if (equivalent(i, best)) choice = i;
    }
    return choice;
  }

  ChunkSearchResult finish() const {
    ChunkSearchResult result;
    for (const ChunkMeasurement& entry : entries_) {
      if (entry.evaluations > 0) result.measured.push_back(entry);
    }
    if (!result.measured.empty()) {
      result.fastest_chunk = entries_[fastest()].chunk;
      result.chosen_chunk = entries_[chosen()].chunk;
    }
    result.evaluations = evaluations_;
    result.measuring_seconds = measuring_seconds_;
    result.sampled_seconds = sampled_seconds_;
    result.stop = stop_;
    return result;
  }

 private:
  const MeasureChunk& measure_;
  const ChunkSearchOptions& options_;
  bool budgeted_;
  const char* function_;
  std::vector<ChunkMeasurement> entries_;
  int evaluations_ = 0;
  double measuring_seconds_ = 0.0;
  double sampled_seconds_ = 0.0;
  SearchStop stop_ = SearchStop::kConverged;
};

std::size_t seed_index(const std::vector<int>& grid, int seed_chunk) {
  if (seed_chunk == 0) return grid.size() / 2;
  const double target = std::log2(static_cast<double>(seed_chunk));
  std::size_t best = 0;
  for (std::size_t i = 0; i < grid.size(); ++i) {
    const double distance = std::abs(std::log2(static_cast<double>(grid[i])) - target);
    const double best_distance = std::abs(std::log2(static_cast<double>(grid[best])) - target);
    if (distance <= best_distance) best = i;
  }
  return best;
}

// Steps 1 and 2 of search_chunk; false when the budget ran out.
bool bracket_and_golden_section(GridSearch& search, std::size_t seed) {
  const std::size_t last = search.size() - 1;
  auto median = [&](std::size_t i) { return search.median(i); };
  if (!median(seed)) return false;
  if (seed > 0 && !median(seed - 1)) return false;
  if (seed < last && !median(seed + 1)) return false;

  // Bracket: lo < centre < hi with the centre's median below both ends' (or centre at an edge).
  std::size_t centre = seed;
  if (seed > 0 && *median(seed - 1) < *median(centre)) centre = seed - 1;
  if (seed < last && *median(seed + 1) < *median(centre)) centre = seed + 1;
  std::size_t lo = seed > 0 ? seed - 1 : seed;
  std::size_t hi = seed < last ? seed + 1 : seed;
  if (centre != seed) {
    const bool up = centre > seed;
    std::size_t previous = seed;
    std::size_t step = 2;
    while (true) {
      const std::size_t next =
          up ? std::min(last, centre + step) : (centre >= step ? centre - step : 0);
      if (next == centre) {  // the minimum is at the grid's edge
        lo = up ? previous : centre;
        hi = up ? centre : previous;
        break;
      }
      const auto next_median = median(next);
      if (!next_median) return false;
      if (*next_median >= *median(centre)) {
        lo = std::min(previous, next);
        hi = std::max(previous, next);
        break;
      }
      previous = centre;
      centre = next;
      step *= 2;
    }
  }

  // Golden section on the integer index: probe the larger side at 0.382 of its width.
  constexpr double kGoldenFraction = 0.3819660112501051;  // 2 - golden ratio
  while (centre - lo > 1 || hi - centre > 1) {
    const std::size_t right = hi - centre, left = centre - lo;
    std::size_t probe;
    if (right >= left) {
      const auto offset =
          static_cast<std::size_t>(std::lround(kGoldenFraction * static_cast<double>(right)));
      probe = centre + std::clamp<std::size_t>(offset, 1, right - 1);
    } else {
      const auto offset =
          static_cast<std::size_t>(std::lround(kGoldenFraction * static_cast<double>(left)));
      probe = centre - std::clamp<std::size_t>(offset, 1, left - 1);
    }
    const auto probe_median = median(probe);
    if (!probe_median) return false;
    if (*probe_median < *median(centre)) {
      (probe > centre ? lo : hi) = centre;
      centre = probe;
    } else {
      (probe > centre ? hi : lo) = probe;
    }
  }
  return true;
}

// Step 3: measure the chunk above the current choice while it would extend the choice.
bool walk_up_through_ties(GridSearch& search) {
  while (true) {
    const std::size_t next = search.chosen() + 1;
    if (next >= search.size() || search.measured(next)) return true;
    if (!search.measure_once(next)) return false;
  }
}

}  // namespace

const ChunkMeasurement& ChunkSearchResult::at(int chunk) const {
  for (const ChunkMeasurement& entry : measured) {
    if (entry.chunk == chunk) return entry;
  }
  throw std::invalid_argument("ChunkSearchResult::at: chunk " + std::to_string(chunk) +
                              " was not measured");
}

ChunkSearchResult search_chunk(const MeasureChunk& measure, const ChunkSearchOptions& options) {
  if (options.with_block) {
    throw std::invalid_argument(
        "search_chunk: with_block is for exhaustive_chunk_sweep (the block is off the grid the "
        "search walks)");
  }
  validate(options, "search_chunk");
  GridSearch search(measure, options, true, "search_chunk");
  [&] {
    if (!bracket_and_golden_section(search, seed_index(options.grid, options.seed_chunk))) return;
    if (!walk_up_through_ties(search)) return;
    for (int round = 0; round < options.confirmation_rounds; ++round) {
      const std::size_t best = search.fastest();
      std::vector<std::size_t> contenders;
      for (std::size_t i = 0; i < search.size(); ++i) {
        if (search.equivalent(i, best)) {
          contenders.push_back(i);
        }
      }
      if (contenders.size() <= 1) return;
      for (const std::size_t i : contenders) {
        if (!search.measure_once(i)) return;
      }
      if (!walk_up_through_ties(search)) return;
    }
  }();
  return search.finish();
}

ChunkSearchResult exhaustive_chunk_sweep(const MeasureChunk& measure,
                                         const ChunkSearchOptions& options) {
  validate(options, "exhaustive_chunk_sweep");
  GridSearch search(measure, options, false, "exhaustive_chunk_sweep");
  std::vector<std::size_t> order(search.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::mt19937_64 random(options.order_seed);
  for (int round = 0; round < options.rounds; ++round) {
    std::shuffle(order.begin(), order.end(), random);
    for (const std::size_t i : order) search.measure_once(i);
  }
  return search.finish();
}

double regret(double chosen_seconds, double best_seconds) {
  if (!(best_seconds > 0.0) || !(chosen_seconds >= 0.0)) {
    throw std::invalid_argument("regret: chosen = " + std::to_string(chosen_seconds) +
                                " s, best = " + std::to_string(best_seconds) +
                                " s (need best > 0, chosen >= 0)");
  }
  return (chosen_seconds - best_seconds) / best_seconds;
}

double regret(const ChunkSearchResult& exhaustive, int chosen_chunk) {
  return regret(exhaustive.at(chosen_chunk).median_seconds,
                exhaustive.at(exhaustive.fastest_chunk).median_seconds);
}

}  // namespace contactlab::tuner
