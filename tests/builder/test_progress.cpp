// The progress reporter (builder/progress.h): its line, its time left, and
// what it writes on a terminal and elsewhere, with an injected clock.
#include "builder/progress.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <string>

namespace kg {
namespace {

// Everything written to `f` so far.
std::string contents(std::FILE* f) {
  std::fflush(f);
  std::rewind(f);
  std::string out;
  for (int c = std::fgetc(f); c != EOF; c = std::fgetc(f)) out += static_cast<char>(c);
  return out;
}

const ProgressReporter::Settings kBuild{"build", "model", false, true};

TEST(Progress, DurationRoundsToSecondsAndShowsHours) {
  EXPECT_EQ(ProgressReporter::duration(0), "0:00");
  EXPECT_EQ(ProgressReporter::duration(31.4), "0:31");
  EXPECT_EQ(ProgressReporter::duration(59.6), "1:00");
  EXPECT_EQ(ProgressReporter::duration(725), "12:05");
  EXPECT_EQ(ProgressReporter::duration(3723), "1:02:03");
  EXPECT_EQ(ProgressReporter::duration(-5), "0:00");
}

TEST(Progress, LineHasCountPercentAndTimeLeft) {
  // 12 of 50 models in 12 s: 1 s a model, 38 left.
  EXPECT_EQ(ProgressReporter::line(kBuild, 12, 50, "exit-left", 12.0),
            "build: model 12/50 exit-left (24 %), 0:38 left");
  // Nothing done yet: no estimate.
  EXPECT_EQ(ProgressReporter::line(kBuild, 0, 50, "", 3.0), "build: model 0/50 (0 %)");
  // Done: the time it took.
  EXPECT_EQ(ProgressReporter::line(kBuild, 50, 50, "last", 95.0),
            "build: model 50/50 last (100 %), took 1:35");
  // Without a unit; a long `what` is cut.
  const ProgressReporter::Settings eval{"eval", "", false, false};
  EXPECT_EQ(ProgressReporter::line(eval, 1, 3, std::string(40, 'x'), 2.0),
            "eval: 1/3 " + std::string(29, 'x') + "... (33 %), 0:04 left");
}

TEST(Progress, PlainLinesEveryStepForBuild) {
  std::FILE* f = std::tmpfile();
  ASSERT_NE(f, nullptr);
  double now = 100.0;
  {
    ProgressReporter p(kBuild, f, [&now] { return now; });
    now = 102.0;
    p.update(1, 3, "a");
    now = 104.0;
    p.update(2, 3, "b");
    now = 106.0;
    p.update(3, 3, "c");
  }
  EXPECT_EQ(contents(f),
            "build: model 1/3 a (33 %), 0:04 left\n"
            "build: model 2/3 b (66 %), 0:02 left\n"
            "build: model 3/3 c (100 %), took 0:06\n");
  std::fclose(f);
}

TEST(Progress, PlainLinesEveryTenthOtherwise) {
  std::FILE* f = std::tmpfile();
  ASSERT_NE(f, nullptr);
  double now = 0;
  {
    ProgressReporter p({"synth", "frame", false, false}, f, [&now] { return now; });
    for (int done = 1; done <= 100; ++done) {
      now = done;
      p.update(done, 100, {});
    }
  }
  const std::string out = contents(f);
  // 1 % (the first tenth, 0), then 10 %, 20 %, ... 100 %: 11 lines.
  int lines = 0;
  for (const char c : out) lines += c == '\n';
  EXPECT_EQ(lines, 11);
  EXPECT_NE(out.find("synth: frame 1/100 (1 %), 1:39 left\n"), std::string::npos);
  EXPECT_NE(out.find("synth: frame 50/100 (50 %), 0:50 left\n"), std::string::npos);
  EXPECT_NE(out.find("synth: frame 100/100 (100 %), took 1:40\n"), std::string::npos);
  std::fclose(f);
}

TEST(Progress, TerminalLineIsRewrittenInPlaceAndCleared) {
  std::FILE* f = std::tmpfile();
  ASSERT_NE(f, nullptr);
  double now = 0;
  {
    ProgressReporter p({"eval", "case", true, false}, f, [&now] { return now; });
    now = 1;
    p.update(1, 4, "keygraph-mser, frame 1");
    now = 1.05;  // within the redraw interval: not shown
    p.update(2, 4, "skipped");
    now = 2;
    p.update(3, 4, "sift");
  }  // finish(): the line is cleared
  const std::string first = "eval: case 1/4 keygraph-mser, frame 1 (25 %), 0:03 left";
  const std::string second = "eval: case 3/4 sift (75 %), 0:01 left";
  const std::string pad(first.size() - second.size(), ' ');
  EXPECT_EQ(contents(f),
            "\r" + first + "\r" + second + pad + "\r" + std::string(second.size(), ' ') + "\r");
  std::fclose(f);
}

}  // namespace
}  // namespace kg
