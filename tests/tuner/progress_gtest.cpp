// The progress bar: a few plain lines when its stream is not a terminal (logs, CI), one line
// redrawn in place when it is.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "contactlab/tuner/progress.hpp"

namespace contactlab::tuner {
namespace {

std::string written(std::FILE* file) {
  std::fflush(file);
  std::rewind(file);
  std::string text;
  for (int c = std::fgetc(file); c != EOF; c = std::fgetc(file))
    text.push_back(static_cast<char>(c));
  return text;
}

int count(const std::string& text, const std::string& what) {
  int n = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

TEST(ProgressBar, PlainLinesAtEachQuarterThenTheEnd) {
  std::FILE* file = std::tmpfile();
  ASSERT_NE(file, nullptr);
  {
    ProgressBar bar("calibrating", file, false);
    ProgressMeter meter = bar.meter();
    for (int k = 0; k <= 100; ++k) meter(k / 100.0, 100.0 - k);
    bar.finish(12.3);
  }
  const std::string text = written(file);
  std::fclose(file);
  EXPECT_EQ(count(text, "\n"), 4) << text;
  EXPECT_EQ(count(text, "\r"), 0) << text;
  EXPECT_NE(text.find("contactlab: calibrating: 25 % after"), std::string::npos) << text;
  EXPECT_NE(text.find("contactlab: calibrating: 50 %"), std::string::npos) << text;
  EXPECT_NE(text.find("contactlab: calibrating: 75 %"), std::string::npos) << text;
  EXPECT_NE(text.find("s left"), std::string::npos) << text;
  EXPECT_NE(text.find("contactlab: calibrating: 100 %, done in 12 s\n"), std::string::npos) << text;
}

TEST(ProgressBar, JumpsWriteOneLineAndUnknownTimeLeftIsNotShown) {
  std::FILE* file = std::tmpfile();
  ASSERT_NE(file, nullptr);
  {
    ProgressBar bar("calibrating", file, false);
    bar.update(0.6, -1.0);  // over two quarters at once: the last one reached
    bar.update(0.7, -1.0);
  }
  const std::string text = written(file);
  std::fclose(file);
  EXPECT_EQ(text, "contactlab: calibrating: 50 % after 0 s\n");
}

TEST(ProgressBar, TerminalRedrawsOneLineAndEndsIt) {
  std::FILE* file = std::tmpfile();
  ASSERT_NE(file, nullptr);
  {
    ProgressBar bar("calibrating", file, true);
    bar.update(0.5, 65.0);
    bar.update(0.6, 50.0);  // within 0.2 s of the last draw: not drawn
    bar.finish(130.0);
  }
  const std::string text = written(file);
  std::fclose(file);
  EXPECT_EQ(count(text, "\n"), 1) << text;
  EXPECT_EQ(count(text, "\r"), 2) << text;
  EXPECT_NE(text.find(" 50 %, about 1 min 05 s left"), std::string::npos) << text;
  EXPECT_EQ(text.find(" 60 %"), std::string::npos) << text;
  EXPECT_NE(text.find("100 %, done in 2 min 10 s\n"), std::string::npos) << text;
}

TEST(ProgressBar, AnUnfinishedTerminalLineIsEndedByTheDestructor) {
  std::FILE* file = std::tmpfile();
  ASSERT_NE(file, nullptr);
  { ProgressBar("calibrating", file, true).update(0.1, 9.0); }
  const std::string text = written(file);
  std::fclose(file);
  ASSERT_FALSE(text.empty());
  EXPECT_EQ(text.back(), '\n');
}

TEST(ProgressBar, PlainIntervalLinesCarryTheDetailBetweenQuarters) {
  std::FILE* file = std::tmpfile();
  ASSERT_NE(file, nullptr);
  {
    ProgressBar bar("dem run", file, false);
    bar.set_plain_interval(1e-9);  // every update is due
    bar.update(0.1, 7300.0, "t = 0.06 s");
    bar.update(0.3, -1.0, "t = 0.18 s");  // a quarter crossed: the quarter's line
  }
  const std::string text = written(file);
  std::fclose(file);
  EXPECT_EQ(text,
            "contactlab: dem run: 10.0 % after 0 s, t = 0.06 s, about 2 h 01 min left\n"
            "contactlab: dem run: 25 % after 0 s, t = 0.18 s\n");
}

TEST(ProgressBar, HoursAreShownAsHoursAndMinutes) {
  EXPECT_EQ(format_seconds(59.4), "59 s");
  EXPECT_EQ(format_seconds(3599.0), "59 min 59 s");
  EXPECT_EQ(format_seconds(3600.0 + 7 * 60 + 59), "1 h 07 min");
}

}  // namespace
}  // namespace contactlab::tuner
