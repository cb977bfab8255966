// What watches a long `dem run` from outside the physics: where it stops (--steps, --until-time,
// the config's end), the progress on stderr (share done, simulated time, rate, time left), the
// checkpoints of --resume between outputs, and SIGINT/SIGTERM (a batch system's time limit)
// turned into a last checkpoint and a clean stop. None of it changes a single bit of the run:
// splitting the steps into shorter batches gives the same bits (dem_engine_gtest).
#pragma once

#include <csignal>
#include <cstdint>
#include <deque>
#include <optional>
#include <string>

#include "contactlab/dem/engine.hpp"
#include "contactlab/tuner/progress.hpp"

namespace contactlab::cli {

// The step a run stops at, from where it stands: `steps` more (when > 0), else up to
// `until_time_s` (absolute simulated time, when set: the same command resumed stops at the same
// step), else up to the config's end.
std::uint64_t last_step_of_run(std::uint64_t step_now, double time_now_s, double dt_s,
                               std::uint64_t steps, std::optional<double> until_time_s,
                               double config_end_s);

// Where a run's frames fall, and what the end of a batch writes; one process and --mpi alike.
// Frames come every `output_every_s` (in steps) from the cadence's origin: the run's first step,
// or step 0 under --resume, so that a resumed series is the unbroken run's. The last step writes
// one too, except a --resume stop short of the config's end, whose checkpoint holds it instead.
class OutputCadence {
 public:
  OutputCadence(double output_every_s, double dt_s, std::uint64_t first_step,
                std::uint64_t last_step, bool resumable, bool ends_at_config_end);
  std::uint64_t steps_to_next(std::uint64_t step) const {
    return every_ - (step - origin_) % every_;
  }
  // A frame and checkpoint after `step` (`forced`: the run stops there for another reason).
  bool frame_at(std::uint64_t step, bool forced) const;
  // Only a checkpoint after `step`: a --resume run's stop short of the config's end.
  bool checkpoint_only_at(std::uint64_t step) const { return resumable_ && step == last_step_; }

 private:
  std::uint64_t every_, origin_, last_step_;
  bool resumable_, ends_at_config_end_;
};

// "contactlab: stopped by signal N at step S ...: FILE holds the run; ..." on stderr.
void print_stopped_by_signal(int signal, std::uint64_t step, double time_s,
                             const std::string& checkpoint);

struct RunWatchOptions {
  double progress_every_s = 0.0;    // plain progress lines at least this often (0: none)
  bool terminal = false;            // stderr is a terminal: a bar redrawn in place
  double checkpoint_every_s = 0.0;  // wall seconds between checkpoints (0: outputs only)
  bool stop_on_signal = false;      // SIGINT/SIGTERM: stop after the batch (and checkpoint)
};

class RunWatch {
 public:
  // Where the run stands after a batch: over every rank for a decomposed run.
  struct Standing {
    std::uint64_t step = 0;
    double time_s = 0.0;
    double particle_steps = 0.0;  // since the engine was made (its particle_steps())
    double discharged = -1.0;     // the share of the mass the sink has taken; < 0: no sink
  };
  // `first` is where the run starts (its particle steps those of every rank, as after_batch's).
  RunWatch(const RunWatchOptions& options, const Standing& first, std::uint64_t last_step);
  ~RunWatch();
  RunWatch(const RunWatch&) = delete;
  RunWatch& operator=(const RunWatch&) = delete;

  // The most steps the next batch may take: about a second of the run's own rate when anything
  // watches (the first batch 8 steps), else no bound.
  std::uint64_t batch_steps(std::uint64_t wanted) const;
  // After each batch: the progress line.
  void after_batch(const Standing& standing);
  // True once `checkpoint_every_s` has passed since the last checkpoint; the caller writes one
  // and calls checkpoint_written().
  bool checkpoint_due() const;
  void checkpoint_written();
  // The signal that asked the run to stop (0: none).
  int stop_signal() const;
  // The bar's last line when the run reached its last step (a stop before it leaves the line).
  void finish(double wall_s, bool completed);

 private:
  RunWatchOptions options_;
  bool watching_;
  std::optional<tuner::ProgressBar> bar_;
  std::uint64_t first_step_, last_step_, last_batch_end_step_;
  double first_particle_steps_;
  double start_s_, last_batch_end_s_, last_checkpoint_s_;
  double steps_per_s_ = 0.0;  // the last batch's rate
  // (wall s, step, particle steps) after recent batches: the rate and the time left are taken
  // over the last fifth of the run (at least 30 s), since a filling silo slows as it lands.
  struct Sample {
    double wall_s;
    std::uint64_t step;
    double particle_steps;
  };
  std::deque<Sample> recent_;
  using Handler = void (*)(int);
  Handler previous_int_ = SIG_DFL, previous_term_ = SIG_DFL;
};

}  // namespace contactlab::cli
