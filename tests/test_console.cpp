/// What the CLI prints besides results: stored text made safe, fitted tables, progress of
/// runs and studies.
#include <doctest/doctest.h>

#include <sstream>

#include "../src/cli/progress.hpp"
#include "../src/cli/study_progress.hpp"
#include "../src/cli/text_table.hpp"

using namespace pdamp;

TEST_CASE("printable: control characters and bytes that are not UTF-8 become escapes") {
  CHECK(printable("table1") == "table1");
  CHECK(printable("a\nb\tc\rd") == "a\\nb\\tc\\rd");
  CHECK(printable("\x1b[31mred\x07") == "\\x1b[31mred\\x07");
  CHECK(printable(std::string("nul\0byte", 8)) == "nul\\x00byte");
  CHECK(printable("del\x7f") == "del\\x7f");
  CHECK(printable("Kühlung ∆ 振動") == "Kühlung ∆ 振動");  // UTF-8 stays
  CHECK(printable("\xc2\x9b"
                  "2J") == "\\xc2\\x9b2J");                                // C1 control (CSI)
  CHECK(printable("\xff\xc3") == "\\xff\\xc3");                            // not UTF-8
  CHECK(printable("\xc0\xaf") == "\\xc0\\xaf");                            // overlong
  CHECK(printable("'; DROP TABLE runs; --") == "'; DROP TABLE runs; --");  // quotes are printable
  CHECK(display_width("Kühlung ∆") == 9);
}

TEST_CASE("a text table fits its columns to what they hold, and cuts what is too long") {
  TextTable table({{"id", true}, {"name", false, 12}, {"status"}});
  table.add_row({"7", "short", "completed"});
  table.add_row({"1234", "a name much longer than twelve", "failed"});
  table.add_row({"8", "tab\there", "running"});
  table.add_row({"9", "Kühlung", "running"});
  std::ostringstream out;
  table.print(out);
  CHECK(out.str() ==
        "  id  name          status\n"
        "   7  short         completed\n"
        "1234  a name much…  failed\n"
        "   8  tab\\there     running\n"
        "   9  Kühlung       running\n");
}

namespace {

/// A clock the test moves by hand.
struct FakeClock {
  std::chrono::steady_clock::time_point now{};
  Progress::Clock clock() {
    return [this] { return now; };
  }
  void advance(double seconds) {
    now += std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(seconds));
  }
};

}  // namespace

TEST_CASE("progress on a terminal: one line redrawn with percent and time left, messages on lines of their own") {
  FakeClock time;
  std::ostringstream out;
  Progress progress(out, true, time.clock());
  progress.begin("soft model", 1.5);
  progress.update(0.0);
  time.advance(1.0);
  progress.update(0.1);
  CHECK(out.str() == "\r  soft model: t = 0.1000 of 1.5000 s, 6.7 %\033[K");
  time.advance(0.1);  // sooner than a redraw
  progress.update(0.11);
  time.advance(2.9);  // 4 s after the first update, 0.4 of 1.5 s done: 11 s left
  out.str("");
  progress.update(0.4);
  CHECK(out.str() == "\r  soft model: t = 0.4000 of 1.5000 s, 26.7 %, 11 s left\033[K");
  out.str("");
  progress.message("pdamp: warning: contacts overlapped");
  CHECK(out.str() ==
        "\r\033[Kpdamp: warning: contacts overlapped\n  soft model: t = 0.4000 of 1.5000 s, 26.7 %, 11 s left");
  out.str("");
  progress.end();
  CHECK(out.str() == "\n");
  out.str("");
  progress.message("pdamp: settled");
  CHECK(out.str() == "pdamp: settled\n");
}

TEST_CASE("progress in a log: a line every 30 s, each complete") {
  FakeClock time;
  std::ostringstream out;
  Progress progress(out, false, time.clock());
  progress.begin("settling the bed");
  for (int second = 0; second <= 65; ++second) {
    progress.update(0.01 * second, "kinetic energy 1e-05 J");
    time.advance(1.0);
  }
  CHECK(out.str() ==
        "pdamp: settling the bed: t = 0.3000 s, kinetic energy 1e-05 J\n"
        "pdamp: settling the bed: t = 0.6000 s, kinetic energy 1e-05 J\n");
  out.str("");
  progress.message("pdamp: warning: w");
  progress.end();
  CHECK(out.str() == "pdamp: warning: w\n");
}

TEST_CASE("study progress: points done, the points running with their phase, the time left at the mean pace") {
  FakeClock time;
  std::ostringstream out;
  StudyProgress progress(out, false, "fill", 10, 2, 2, time.clock());
  progress.started(3);
  progress.started(4);
  progress.progressed(3, 0.0, "settling");
  progress.progressed(4, 0.0, "settling");
  progress.update(6);
  CHECK(out.str().empty());  // a log line every 30 s
  time.advance(30.0);
  progress.progressed(3, 0.5, "hard");
  progress.progressed(4, 0.01, "settling");
  progress.update(6);
  // Before any point completes, the pace is extrapolated from those past 2 %: 60 s a point,
  // 6 queued + 0.5 + 0.99 points left, 2 at a time.
  CHECK(out.str() == "pdamp: study fill: 2/10 done; running 3 (hard 50 %), 4 (settling); 3 min 45 s left\n");
  time.advance(30.0);
  progress.ended(3, true);
  progress.ended(4, false);
  progress.started(5);
  out.str("");
  progress.update(5);
  // One point completed in 60 s: 5 queued + 1 running, 2 at a time.
  CHECK(out.str() == "pdamp: study fill: 3/10 done, 1 not completed; running 5 (starting); 3 min 00 s left\n");
  out.str("");
  progress.message("pdamp: point 5: warning: w");
  progress.finish();
  CHECK(out.str() == "pdamp: point 5: warning: w\n");
}

// study resume: a point resumed from its checkpoint reports its first progress there; the
// work before was another process's, and counting it here made the time left too short.
TEST_CASE("study progress: the time left counts only the work done in this process") {
  FakeClock time;
  std::ostringstream out;
  StudyProgress progress(out, false, "fill", 4, 1, 1, time.clock());
  progress.started(2);
  time.advance(1.0);
  progress.progressed(2, 0.6, "hard");  // resumed at 60 %
  time.advance(29.0);
  progress.progressed(2, 0.8, "hard");
  progress.update(2);
  // 0.2 of a point in 29 s: 145 s a point; 2 queued + 0.2 left.
  CHECK(out.str() == "pdamp: study fill: 1/4 done; running 2 (hard 80 %); 5 min 19 s left\n");
  time.advance(29.0);
  progress.ended(2, true);
  progress.started(3);
  out.str("");
  time.advance(30.0);
  progress.update(1);
  // Point 2 did 0.4 of a point here in 58 s: 145 s a point, for 1 queued + 1 running.
  CHECK(out.str() == "pdamp: study fill: 2/4 done; running 3 (starting); 4 min 50 s left\n");
}

TEST_CASE("study progress on a terminal: the line redrawn in place, ended by a new line") {
  FakeClock time;
  std::ostringstream out;
  StudyProgress progress(out, true, "fill", 4, 0, 1, time.clock());
  progress.started(1);
  time.advance(1.0);
  progress.update(3);
  CHECK(out.str() == "\r  study fill: 0/4 done; running 1 (starting)\033[K");
  out.str("");
  progress.finish();
  CHECK(out.str() == "\n");
}

TEST_CASE("durations read as people write them") {
  CHECK(format_duration(std::chrono::seconds(45)) == "45 s");
  CHECK(format_duration(std::chrono::seconds(185)) == "3 min 05 s");
  CHECK(format_duration(std::chrono::seconds(7800)) == "2 h 10 min");
}
