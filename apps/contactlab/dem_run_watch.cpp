#include "dem_run_watch.hpp"

#include <fmt/core.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace contactlab::cli {
namespace {

volatile std::sig_atomic_t g_stop_signal = 0;

extern "C" void ask_to_stop(int signal) { g_stop_signal = signal; }

}  // namespace

std::uint64_t last_step_of_run(std::uint64_t step_now, double time_now_s, double dt_s,
                               std::uint64_t steps, std::optional<double> until_time_s,
                               double config_end_s) {
  if (steps > 0) return step_now + steps;
  const double end = until_time_s.value_or(config_end_s);
  return step_now +
         static_cast<std::uint64_t>(std::llround(std::max(0.0, end - time_now_s) / dt_s));
}

OutputCadence::OutputCadence(double output_every_s, double dt_s, std::uint64_t first_step,
                             std::uint64_t last_step, bool resumable, bool ends_at_config_end)
    // Without an output interval the cadence never comes inside the run: frames only at its end.
    : every_(output_every_s > 0
                 ? std::max<std::uint64_t>(
                       1, static_cast<std::uint64_t>(std::llround(output_every_s / dt_s)))
                 : std::max<std::uint64_t>(1, last_step)),
      origin_(resumable ? 0 : first_step),
      last_step_(last_step),
      resumable_(resumable),
      ends_at_config_end_(ends_at_config_end) {}

bool OutputCadence::frame_at(std::uint64_t step, bool forced) const {
  return (step - origin_) % every_ == 0 || forced ||
         (step == last_step_ && (!resumable_ || ends_at_config_end_));
}

void print_stopped_by_signal(int signal, std::uint64_t step, double time_s,
                             const std::string& checkpoint) {
  fmt::print(stderr,
             "contactlab: stopped by signal {} at step {} (t = {:.6g} s): {} holds the run; the "
             "same command continues it\n",
             signal, step, time_s, checkpoint);
}

RunWatch::RunWatch(const RunWatchOptions& options, const Standing& first, std::uint64_t last_step)
    : options_(options),
      watching_(options.progress_every_s > 0.0 || options.terminal ||
                options.checkpoint_every_s > 0.0 || options.stop_on_signal),
      first_step_(first.step),
      last_step_(last_step),
      last_batch_end_step_(first_step_),
      first_particle_steps_(first.particle_steps),
      start_s_(omp_get_wtime()),
      last_batch_end_s_(start_s_),
      last_checkpoint_s_(start_s_) {
  if (options.progress_every_s > 0.0 || options.terminal) {
    bar_.emplace("dem run", stderr, options.terminal);
    bar_->set_plain_interval(options.progress_every_s);
  }
  if (options.stop_on_signal) {
    g_stop_signal = 0;
    previous_int_ = std::signal(SIGINT, ask_to_stop);
    previous_term_ = std::signal(SIGTERM, ask_to_stop);
  }
}

RunWatch::~RunWatch() {
  if (options_.stop_on_signal) {
    std::signal(SIGINT, previous_int_);
    std::signal(SIGTERM, previous_term_);
  }
}

std::uint64_t RunWatch::batch_steps(std::uint64_t wanted) const {
  if (!watching_) return wanted;
  const std::uint64_t about_a_second =
      steps_per_s_ > 0.0 ? static_cast<std::uint64_t>(std::max(1.0, steps_per_s_)) : 8;
  return std::min(wanted, about_a_second);
}

void RunWatch::after_batch(const Standing& standing) {
  const double now = omp_get_wtime();
  const std::uint64_t step = standing.step;
  if (now > last_batch_end_s_ && step > last_batch_end_step_) {
    steps_per_s_ = static_cast<double>(step - last_batch_end_step_) / (now - last_batch_end_s_);
  }
  last_batch_end_s_ = now;
  last_batch_end_step_ = step;
  if (!bar_) return;
  const double wall = now - start_s_;
  const double span = static_cast<double>(std::max<std::uint64_t>(1, last_step_ - first_step_));
  const double done = static_cast<double>(step - first_step_) / span;
  // The rate and the time left over the last fifth of the run, at least 30 s (a DEM run's rate
  // changes as its contacts do: a silo's fill ran 80 M particle-steps/s in its first minute and
  // 21 M after an hour, so the mean rate promised half the time it took).
  if (recent_.empty()) recent_.push_back({start_s_, first_step_, first_particle_steps_});
  recent_.push_back({now, step, standing.particle_steps});
  const double window = std::max(30.0, 0.2 * wall);
  while (recent_.size() > 2 && recent_[1].wall_s <= now - window) recent_.pop_front();
  const Sample& from = recent_.front();
  const double over = std::max(now - from.wall_s, 1e-9);
  const double rate = (standing.particle_steps - from.particle_steps) / over;
  const double steps_rate = static_cast<double>(step - from.step) / over;
  const double left = step > from.step ? static_cast<double>(last_step_ - step) / steps_rate : -1.0;
  std::string detail = fmt::format("step {}, t = {:.6g} s, {:.3g} M particle-steps/s", step,
                                   standing.time_s, rate / 1e6);
  if (standing.discharged >= 0.0) {
    detail += fmt::format(", {:.1f} % discharged", 100.0 * standing.discharged);
  }
  bar_->update(done, left, detail);
}

bool RunWatch::checkpoint_due() const {
  return options_.checkpoint_every_s > 0.0 &&
         omp_get_wtime() - last_checkpoint_s_ >= options_.checkpoint_every_s;
}

void RunWatch::checkpoint_written() { last_checkpoint_s_ = omp_get_wtime(); }

int RunWatch::stop_signal() const { return options_.stop_on_signal ? g_stop_signal : 0; }

void RunWatch::finish(double wall_s, bool completed) {
  if (bar_ && completed) bar_->finish(wall_s);
}

}  // namespace contactlab::cli
