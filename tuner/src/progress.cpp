#include "contactlab/tuner/progress.hpp"

#include <fmt/core.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>

namespace contactlab::tuner {
namespace {

double now_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

std::string time_left(double seconds_left) {
  return seconds_left >= 0.0 ? fmt::format(", about {} left", format_seconds(seconds_left))
                             : std::string();
}

}  // namespace

std::string format_seconds(double seconds) {
  const long s = std::lround(std::max(0.0, seconds));
  if (s < 60) return fmt::format("{} s", s);
  if (s < 3600) return fmt::format("{} min {:02} s", s / 60, s % 60);
  return fmt::format("{} h {:02} min", s / 3600, (s % 3600) / 60);
}

ProgressBar::ProgressBar(std::string label, std::FILE* out, bool terminal)
    : label_(std::move(label)),
      out_(out),
      terminal_(terminal),
      start_s_(now_s()),
      last_plain_s_(start_s_) {}

ProgressBar::ProgressBar(std::string label)
    : ProgressBar(std::move(label), stderr, ::isatty(STDERR_FILENO) != 0) {}

ProgressBar::~ProgressBar() {
  if (open_line_) {
    std::fputc('\n', out_);
    std::fflush(out_);
  }
}

void ProgressBar::update(double done, double seconds_left, const std::string& detail) {
  if (finished_) return;
  done = std::clamp(done, 0.0, 1.0);
  const double now = now_s();
  const std::string shown = detail.empty() ? std::string() : ", " + detail;
  if (terminal_) {
    if (last_draw_s_ >= 0.0 && now - last_draw_s_ < 0.2) return;
    last_draw_s_ = now;
    constexpr int kWidth = 30;
    const int filled = static_cast<int>(done * kWidth);
    // "\033[K" clears what a longer line before left behind.
    fmt::print(out_, "\r\033[Kcontactlab: {} [{}{}] {:3.0f} %{}{}", label_,
               std::string(filled, '#'), std::string(kWidth - filled, '.'), 100.0 * done, shown,
               time_left(seconds_left));
    std::fflush(out_);
    open_line_ = true;
    return;
  }
  // Below 100 %: the last quarter reached, once (a jump over two quarters writes one line).
  const int quarter = std::min(3, static_cast<int>(std::floor(done * 4.0 + 1e-9)));
  const bool interval_due = plain_every_s_ > 0.0 && now - last_plain_s_ >= plain_every_s_;
  if (quarter > quarters_shown_) {
    quarters_shown_ = quarter;
    fmt::print(out_, "contactlab: {}: {} % after {}{}{}\n", label_, 25 * quarter,
               format_seconds(now - start_s_), shown, time_left(seconds_left));
  } else if (interval_due) {
    fmt::print(out_, "contactlab: {}: {:.1f} % after {}{}{}\n", label_, 100.0 * done,
               format_seconds(now - start_s_), shown, time_left(seconds_left));
  } else {
    return;
  }
  last_plain_s_ = now;
  std::fflush(out_);
}

void ProgressBar::finish(double seconds) {
  if (finished_) return;
  finished_ = true;
  if (terminal_) {
    fmt::print(out_, "\r\033[Kcontactlab: {} [{}] 100 %, done in {}\n", label_,
               std::string(30, '#'), format_seconds(seconds));
  } else {
    fmt::print(out_, "contactlab: {}: 100 %, done in {}\n", label_, format_seconds(seconds));
  }
  std::fflush(out_);
  open_line_ = false;
}

}  // namespace contactlab::tuner
