#include "contactlab/tuner_model/cost_calibration.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <stdexcept>

#include "contactlab/kernels/error.hpp"

namespace contactlab::tuner {

namespace {

constexpr std::size_t kConstants = kMachineCostFields.size();
using Vector = std::array<double, kConstants>;

Vector to_vector(const MachineCosts& costs) {
  Vector v{};
  for (std::size_t j = 0; j < kConstants; ++j) v[j] = costs.*kMachineCostFields[j].second;
  return v;
}

MachineCosts to_costs(const Vector& v) {
  MachineCosts costs;
  for (std::size_t j = 0; j < kConstants; ++j) costs.*kMachineCostFields[j].second = v[j];
  return costs;
}

// The coefficients of the constants (kMachineCostFields' order) in the loop time when `share`
// is the slowest thread.
Vector features(const ThreadShare& share, bool self_scheduled) {
  return {1.0,
          static_cast<double>(share.tests),
          static_cast<double>(share.iterations),
          static_cast<double>(share.homes),
          static_cast<double>(share.builds),
          self_scheduled ? 0.0 : static_cast<double>(share.chunks),
          static_cast<double>(share.grabs),
          static_cast<double>(share.stream_breaks),
          static_cast<double>(share.cold_tests)};
}

// Least squares min |A x - b| over the columns in `columns` by Householder QR; nullopt when
// those columns are (numerically) dependent. A is row-major, rows x kConstants.
std::optional<std::vector<double>> least_squares(const std::vector<Vector>& a,
                                                 const std::vector<double>& b,
                                                 const std::vector<std::size_t>& columns) {
  const std::size_t m = a.size(), n = columns.size();
  if (n == 0 || m < n) return std::nullopt;
  std::vector<std::vector<double>> r(n, std::vector<double>(m));  // column-major copy
  for (std::size_t j = 0; j < n; ++j) {
    for (std::size_t i = 0; i < m; ++i) r[j][i] = a[i][columns[j]];
  }
  std::vector<double> y = b;
  std::vector<double> norms(n);
  for (std::size_t j = 0; j < n; ++j) {
    double s = 0.0;
    for (const double value : r[j]) s += value * value;
    norms[j] = std::sqrt(s);
  }
  for (std::size_t k = 0; k < n; ++k) {
    double alpha = 0.0;
    for (std::size_t i = k; i < m; ++i) alpha += r[k][i] * r[k][i];
    alpha = std::sqrt(alpha);
    // A column that keeps almost nothing of its norm after the earlier reflections lies in the
    // span of the earlier columns.
    if (alpha <= 1e-9 * norms[k]) return std::nullopt;
    if (r[k][k] > 0) alpha = -alpha;
    std::vector<double> v(m, 0.0);
    for (std::size_t i = k; i < m; ++i) v[i] = r[k][i];
    v[k] -= alpha;
    double vv = 0.0;
    for (std::size_t i = k; i < m; ++i) vv += v[i] * v[i];
    if (vv == 0.0) continue;
    auto reflect = [&](std::vector<double>& column) {
      double dot = 0.0;
      for (std::size_t i = k; i < m; ++i) dot += v[i] * column[i];
      const double factor = 2.0 * dot / vv;
      for (std::size_t i = k; i < m; ++i) column[i] -= factor * v[i];
    };
    for (std::size_t j = k; j < n; ++j) reflect(r[j]);
    reflect(y);
  }
  std::vector<double> x(n, 0.0);
  for (std::size_t kk = n; kk-- > 0;) {
    double s = y[kk];
    for (std::size_t j = kk + 1; j < n; ++j) s -= r[j][kk] * x[j];
    x[kk] = s / r[kk][kk];
  }
  return x;
}

// Non-negative least squares by enumeration of the supports: the NNLS optimum is the
// unconstrained fit on its support, and with at most 9 constants the 511 supports are cheap
// and the answer exact (no active-set cycling to guard against).
Vector nonnegative_least_squares(const std::vector<Vector>& a, const std::vector<double>& b,
                                 const std::array<bool, kConstants>& usable) {
  std::vector<std::size_t> usable_columns;
  for (std::size_t j = 0; j < kConstants; ++j) {
    if (usable[j]) usable_columns.push_back(j);
  }
  // Columns scaled to unit largest entry, so that tests (~1e6) and the region (1) compare.
  std::array<double, kConstants> scale{};
  scale.fill(1.0);
  std::vector<Vector> scaled = a;
  for (const std::size_t j : usable_columns) {
    double largest = 0.0;
    for (const Vector& row : a) largest = std::max(largest, std::abs(row[j]));
    scale[j] = largest > 0.0 ? largest : 1.0;
    for (Vector& row : scaled) row[j] /= scale[j];
  }
  Vector best{};
  double best_residual = 0.0;
  for (const double value : b) best_residual += value * value;  // the all-zero fit
  const std::size_t subsets = std::size_t{1} << usable_columns.size();
  for (std::size_t mask = 1; mask < subsets; ++mask) {
    std::vector<std::size_t> columns;
    for (std::size_t bit = 0; bit < usable_columns.size(); ++bit) {
      if (mask & (std::size_t{1} << bit)) columns.push_back(usable_columns[bit]);
    }
    const auto solution = least_squares(scaled, b, columns);
    if (!solution ||
        std::any_of(solution->begin(), solution->end(), [](double x) { return x < 0.0; })) {
      continue;
    }
    double residual = 0.0;
    for (std::size_t i = 0; i < scaled.size(); ++i) {
      double predicted = 0.0;
      for (std::size_t c = 0; c < columns.size(); ++c) {
        predicted += scaled[i][columns[c]] * (*solution)[c];
      }
      residual += (predicted - b[i]) * (predicted - b[i]);
    }
    if (residual < best_residual * (1.0 - 1e-12)) {
      best_residual = residual;
      best.fill(0.0);
      for (std::size_t c = 0; c < columns.size(); ++c) {
        best[columns[c]] = (*solution)[c] / scale[columns[c]];
      }
    }
  }
  return best;
}

double median_of(std::vector<double> values) {
  if (values.empty()) return 0.0;
  const std::size_t middle = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(middle),
                   values.end());
  double upper = values[middle];
  if (values.size() % 2 == 1) return upper;
  const double lower =
      *std::max_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(middle));
  return 0.5 * (lower + upper);
}

struct Errors {
  double rms = 0.0;
  double max = 0.0;
};

}  // namespace

CalibrationResult calibrate_costs(std::span<const TimedRun> runs, const MachineCosts& fallback) {
  if (runs.empty()) throw std::invalid_argument("calibrate_costs: no timed runs");
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const TimedRun& run = runs[i];
    if (run.threads < 1 || !std::isfinite(run.seconds) || run.seconds <= 0.0) {
      throw std::invalid_argument("calibrate_costs: run " + std::to_string(i) +
                                  " has threads = " + std::to_string(run.threads) +
                                  ", seconds = " + number_text(run.seconds) +
                                  " (need threads >= 1 and seconds > 0)");
    }
    const Schedule& s = run.schedule;
    if (!has_valid_chunk(s)) {
      throw std::invalid_argument("calibrate_costs: run " + std::to_string(i) + " has schedule " +
                                  std::string(to_string(s.kind)) + "," + std::to_string(s.chunk));
    }
  }

  constexpr int kMaxRounds = 30;
  constexpr int kStaleRounds = 4;  // stop when this many fits in a row bring no improvement
  constexpr int kHuberPasses = 6;
  constexpr double kHuberTuning = 1.345;  // 95% efficiency at the normal distribution

  const Vector fallback_vector = to_vector(fallback);
  Vector current = fallback_vector;  // the costs the critical threads are found under
  CalibrationResult result;
  result.costs = fallback;
  Errors best_errors{std::numeric_limits<double>::infinity(), 0.0};
  std::array<bool, kConstants> identified{};
  int stale = 0;
  bool settled = false;

  // What each thread does depends on the costs only where threads race for chunks (dynamic or
  // guided with more than one thread); the other runs are simulated once.
  auto races = [](const TimedRun& run) {
    return run.threads > 1 && run.schedule.kind != ScheduleKind::kStatic &&
           run.schedule.kind != ScheduleKind::kBalanced;
  };
  // Runs of one loop share its prefix sums.
  std::vector<std::unique_ptr<PreparedWork>> prepared_works;
  std::vector<const PreparedWork*> prepared(runs.size());
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const WorkView& work = runs[i].work;
    for (std::size_t j = 0; j < i && !prepared[i]; ++j) {
      const WorkView& other = runs[j].work;
      if (work.tests.data() == other.tests.data() && work.size() == other.size() &&
          work.homes.data() == other.homes.data() && work.builds.data() == other.builds.data()) {
        prepared[i] = prepared[j];
      }
    }
    if (!prepared[i]) {
      prepared_works.push_back(std::make_unique<PreparedWork>(work));
      prepared[i] = prepared_works.back().get();
    }
  }
  std::vector<ScheduleOutcome> fixed(runs.size());
  for (std::size_t i = 0; i < runs.size(); ++i) {
    if (!races(runs[i]))
      fixed[i] = simulate_schedule(*prepared[i], runs[i].threads, runs[i].schedule);
  }

  // Round r simulates every racing run once under `current`: that scores the previous fit and
  // gives the critical threads for the next one.
  for (int round = 0;; ++round) {
    // Rows: the critical thread's coefficients, divided by the measured time so that the fit
    // minimises relative errors.
    std::vector<Vector> rows;
    Errors errors;
    identified.fill(false);
    for (std::size_t i = 0; i < runs.size(); ++i) {
      const TimedRun& run = runs[i];
      const ScheduleOutcome outcome =
          races(run) ? simulate_schedule(*prepared[i], run.threads, run.schedule, to_costs(current))
                     : ScheduleOutcome{};
      const ScheduleOutcome& shares = races(run) ? outcome : fixed[i];
      // The critical thread and the loop's time under `current` (region included in both).
      Vector row{};
      double predicted = -1.0;
      for (const ThreadShare& share : shares.threads) {
        const Vector f = features(share, shares.self_scheduled);
        double seconds = 0.0;
        for (std::size_t j = 0; j < kConstants; ++j) seconds += f[j] * current[j];
        if (seconds > predicted) {
          predicted = seconds;
          row = f;
        }
      }
      const double error = (predicted - run.seconds) / run.seconds;
      errors.rms += error * error;
      errors.max = std::max(errors.max, std::abs(error));
      for (std::size_t j = 0; j < kConstants; ++j) {
        identified[j] = identified[j] || row[j] != 0.0;
        row[j] /= run.seconds;
      }
      rows.push_back(row);
    }
    errors.rms = std::sqrt(errors.rms / static_cast<double>(runs.size()));
    if (round > 0) {  // `current` is a fit: keep the best one
      if (errors.rms < best_errors.rms * (1.0 - 1e-9)) {
        best_errors = errors;
        result.costs = to_costs(current);
        stale = 0;
      } else {
        ++stale;
      }
    }
    if (settled || stale >= kStaleRounds || round == kMaxRounds) break;

    std::vector<double> weights(runs.size(), 1.0);
    const std::vector<double> ones(runs.size(), 1.0);
    Vector fitted{};
    for (int pass = 0; pass < kHuberPasses; ++pass) {
      std::vector<Vector> weighted = rows;
      std::vector<double> targets = ones;
      for (std::size_t i = 0; i < rows.size(); ++i) {
        const double root = std::sqrt(weights[i]);
        for (double& value : weighted[i]) value *= root;
        targets[i] *= root;
      }
      fitted = nonnegative_least_squares(weighted, targets, identified);
      std::vector<double> residuals(rows.size());
      for (std::size_t i = 0; i < rows.size(); ++i) {
        double predicted = 0.0;
        for (std::size_t j = 0; j < kConstants; ++j) predicted += rows[i][j] * fitted[j];
        residuals[i] = std::abs(predicted - 1.0);
      }
      // Robust scale: the median absolute residual, as a normal sigma.
      const double sigma = 1.4826 * median_of(residuals);
      if (sigma <= 1e-12) break;
      for (std::size_t i = 0; i < rows.size(); ++i) {
        const double limit = kHuberTuning * sigma;
        weights[i] = residuals[i] <= limit ? 1.0 : limit / residuals[i];
      }
    }
    for (std::size_t j = 0; j < kConstants; ++j) {
      if (!identified[j]) fitted[j] = fallback_vector[j];
    }
    result.rounds = round + 1;
    double change = 0.0;
    for (std::size_t j = 0; j < kConstants; ++j) {
      const double size = std::max(std::abs(current[j]), std::abs(fitted[j]));
      if (size > 0.0) change = std::max(change, std::abs(fitted[j] - current[j]) / size);
    }
    settled = change < 1e-9;  // same critical threads again: one more scoring pass, then stop
    current = fitted;
  }

  for (std::size_t j = 0; j < kConstants; ++j) {
    if (!identified[j]) result.unidentified.emplace_back(kMachineCostFields[j].first);
  }
  result.rms_relative_error = best_errors.rms;
  result.max_relative_error = best_errors.max;
  return result;
}

WeighingFit calibrate_weighing(std::span<const WeighRun> runs) {
  if (runs.empty()) throw std::invalid_argument("calibrate_weighing: no weighings");
  std::vector<PreparedWork> works;
  works.reserve(runs.size());
  for (std::size_t i = 0; i < runs.size(); ++i) {
    if (runs[i].threads < 2 || !std::isfinite(runs[i].seconds) || runs[i].seconds <= 0.0) {
      throw std::invalid_argument("calibrate_weighing: run " + std::to_string(i) +
                                  " has threads = " + std::to_string(runs[i].threads) +
                                  ", seconds = " + number_text(runs[i].seconds) +
                                  " (need threads >= 2 and seconds > 0)");
    }
    works.emplace_back(runs[i].work);
  }
  using Row = std::array<double, 2>;  // a slice's iterations and builds
  // The slowest slice of each run under (per_iteration, per_build): simulate_balanced's slices.
  auto critical = [&](std::size_t i, double per_iteration, double per_build) {
    const std::uint64_t m = works[i].iterations();
    const auto p = static_cast<std::uint64_t>(runs[i].threads);
    Row slowest{};
    double longest = -1.0;
    for (std::uint64_t t = 0; t < p; ++t) {
      const std::uint64_t first = m * t / p, last = m * (t + 1) / p;
      const Row row{static_cast<double>(last - first),
                    static_cast<double>(works[i].builds(first, last))};
      const double seconds = row[0] * per_iteration + row[1] * per_build;
      if (seconds > longest) {
        longest = seconds;
        slowest = row;
      }
    }
    return slowest;
  };
  // Least squares of sum_i (r_i . x / s_i - 1)^2 over x >= 0: both constants, else the better
  // of each alone (the non-negative optimum lies on one of these supports).
  auto fit = [&](const std::vector<Row>& rows) {
    double aa = 0.0, ab = 0.0, bb = 0.0, a1 = 0.0, b1 = 0.0;
    for (std::size_t i = 0; i < rows.size(); ++i) {
      const double a = rows[i][0] / runs[i].seconds, b = rows[i][1] / runs[i].seconds;
      aa += a * a;
      ab += a * b;
      bb += b * b;
      a1 += a;
      b1 += b;
    }
    auto residual = [&](const Row& x) {
      double sum = 0.0;
      for (std::size_t i = 0; i < rows.size(); ++i) {
        const double e = (rows[i][0] * x[0] + rows[i][1] * x[1]) / runs[i].seconds - 1.0;
        sum += e * e;
      }
      return sum;
    };
    std::vector<Row> supports{{aa > 0.0 ? a1 / aa : 0.0, 0.0}, {0.0, bb > 0.0 ? b1 / bb : 0.0}};
    const double det = aa * bb - ab * ab;
    if (det > 1e-12 * aa * bb) {
      const Row both{(a1 * bb - b1 * ab) / det, (b1 * aa - a1 * ab) / det};
      if (both[0] >= 0.0 && both[1] >= 0.0) supports.push_back(both);
    }
    Row best = supports[0];
    for (const Row& x : supports) {
      if (residual(x) < residual(best)) best = x;
    }
    return best;
  };
  // Start from each slice's iterations alone (the slices are equal in them: the one with the
  // most builds), then refit while the slowest slices change.
  Row x{1.0, 1.0};
  std::vector<Row> rows;
  for (int round = 0; round < 20; ++round) {
    std::vector<Row> next;
    for (std::size_t i = 0; i < runs.size(); ++i) next.push_back(critical(i, x[0], x[1]));
    if (next == rows) break;
    rows = std::move(next);
    x = fit(rows);
  }
  WeighingFit result{x[0], x[1], 0.0};
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const double e = (rows[i][0] * x[0] + rows[i][1] * x[1]) / runs[i].seconds - 1.0;
    result.rms_relative_error += e * e;
  }
  result.rms_relative_error =
      std::sqrt(result.rms_relative_error / static_cast<double>(runs.size()));
  return result;
}

}  // namespace contactlab::tuner
