// A progress bar for a long step on stderr (the first calibration): one line redrawn in place on
// a terminal, a few plain lines otherwise, so that logs and CI stay readable and stdout (reports,
// JSON) is never touched.
#pragma once

#include <cstdio>
#include <functional>
#include <string>

namespace contactlab::tuner {

// Receives the share of a step done (0 to 1) and the estimated seconds left (negative: not known
// yet). Called often (after every timed run); the receiver decides what to show.
using ProgressMeter = std::function<void(double done, double seconds_left)>;

class ProgressBar {
 public:
  // `label` names the step ("calibrating"). `terminal`: redraw one line with '\r' (at most every
  // 0.2 s); else one plain line at each quarter (25, 50, 75 %) and one at the end. Each line
  // starts with "contactlab: ".
  ProgressBar(std::string label, std::FILE* out, bool terminal);
  // On stderr, as a terminal when stderr is one.
  explicit ProgressBar(std::string label);
  ~ProgressBar();
  ProgressBar(const ProgressBar&) = delete;
  ProgressBar& operator=(const ProgressBar&) = delete;

  // `detail` (e.g. "t = 0.2 s, 21 M particle-steps/s") follows the share on every line.
  void update(double done, double seconds_left, const std::string& detail = {});
  // Plain lines: also one whenever this many seconds have passed since the last (a run of
  // hours logs more than its quarters); 0 (the default): the quarters only.
  void set_plain_interval(double seconds) { plain_every_s_ = seconds; }
  // The last line: 100 % and the step's seconds (a terminal's line is ended).
  void finish(double seconds);
  ProgressMeter meter() {
    return [this](double done, double left) { update(done, left); };
  }

 private:
  std::string label_;
  std::FILE* out_;
  bool terminal_;
  bool open_line_ = false;  // a terminal line drawn and not yet ended
  bool finished_ = false;
  int quarters_shown_ = 0;     // plain lines: quarters already written
  double last_draw_s_ = -1.0;  // terminal: when the line was last drawn (steady clock)
  double plain_every_s_ = 0.0;
  double start_s_;
  double last_plain_s_;  // plain: when the last line was written
};

// "12 s", "3 min 05 s", "2 h 07 min".
std::string format_seconds(double seconds);

}  // namespace contactlab::tuner
