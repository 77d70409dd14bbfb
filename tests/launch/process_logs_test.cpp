// log-report's reading of the launcher's process logs and the delivery comparison.
#include <gtest/gtest.h>

#include <sstream>

#include "process_logs.hpp"
#include "run_sections.hpp"

namespace snapnav::report {
namespace {

const char kHomingLog[] = R"(--- launch: homing run 1, pid 100: /bin/homing --home-first
homing: config /config/homing.ini
launch: homing: started (pid 100)
launch: homing: ended (killed by SIGKILL) after 30.4 s; restarting in 1.00 s (restart = on-failure, restart 1 of 3)
--- launch: homing run 2, pid 200: /bin/homing --home-first
launch: homing: restarted (pid 200, restart 1 of 3)
homing: frames 288, before any home 0
  HOMING_VECTOR            received 0, published 288, rejected 0, handler errors 0
  OMNI_FRAME               received 288, published 0, rejected 2, handler errors 1 (last: bad frame)
launch: homing: stopped (exit code 0, 0.01 s after the stop signal)
)";

const char kSimLog[] = R"(--- launch: sim run 1, pid 300: /bin/sim
sim: done at t=60.00 s: 600 frames
  DRIVE_COMMAND            received 3000, published 0, rejected 0, handler errors 0
  OMNI_FRAME               received 0, published 600, rejected 0, handler errors 0
  ODOMETRY                 received 0, published 3000, rejected 0, handler errors 0
)";

ProcessLog Parse(const std::string& name, const std::string& text) {
  std::istringstream in(text);
  return ParseProcessLog(name, in);
}

TEST(ProcessLogs, RunsCountsAndTheLaunchersLines) {
  const ProcessLog h = Parse("homing", kHomingLog);
  ASSERT_EQ(h.runs.size(), 2u);
  EXPECT_EQ(h.runs[0].pid, 100);
  EXPECT_FALSE(h.runs[0].reported);  // killed: no counts
  EXPECT_TRUE(h.runs[1].reported);
  EXPECT_FALSE(h.complete());
  EXPECT_EQ(h.runs[1].channels.at("OMNI_FRAME").received, 288u);
  EXPECT_EQ(h.runs[1].channels.at("OMNI_FRAME").rejected, 2u);
  EXPECT_EQ(h.runs[1].channels.at("OMNI_FRAME").handler_errors, 1u);
  EXPECT_EQ(h.Totals().at("HOMING_VECTOR").published, 288u);
  ASSERT_EQ(h.launcher_lines.size(), 4u);
  EXPECT_EQ(h.launcher_lines[1].rfind("homing: ended (killed by SIGKILL)", 0), 0u);
  // A log written without the launcher: one run.
  const ProcessLog plain = Parse("sim", "  OMNI_FRAME  received 0, published 5, rejected 0, handler errors 0\n");
  ASSERT_EQ(plain.runs.size(), 1u);
  EXPECT_TRUE(plain.complete());
  EXPECT_EQ(plain.Totals().at("OMNI_FRAME").published, 5u);
}

TEST(ProcessLogs, DeliveryComparesPublishedWithRecorded) {
  const std::vector<ProcessLog> logs{Parse("homing", kHomingLog), Parse("sim", kSimLog)};
  const std::map<std::string, int64_t> recorded{{"OMNI_FRAME", 600}, {"ODOMETRY", 2999}, {"HOMING_VECTOR", 587}};
  const auto d = CompareDelivery(logs, recorded);
  ASSERT_EQ(d.size(), 3u);  // channels someone published: HOMING_VECTOR, ODOMETRY, OMNI_FRAME
  EXPECT_EQ(d[0].channel, "HOMING_VECTOR");
  EXPECT_FALSE(d[0].exact);  // a homing run was killed
  EXPECT_EQ(d[0].published, 288u);
  EXPECT_EQ(d[0].recorded, 587u);
  EXPECT_EQ(d[1].channel, "ODOMETRY");
  EXPECT_TRUE(d[1].exact);
  EXPECT_EQ(d[1].published, 3000u);
  EXPECT_EQ(d[1].recorded, 2999u);
  EXPECT_EQ(d[2].channel, "OMNI_FRAME");
  ASSERT_EQ(d[2].received.size(), 1u);
  EXPECT_EQ(d[2].received[0], (std::pair<std::string, uint64_t>{"homing", 288}));
  const Section s = DeliverySection(logs, recorded);
  EXPECT_NE(s.markdown.find("| ODOMETRY | sim | 3000 | 2999 | 1 |"), std::string::npos) << s.markdown;
  EXPECT_NE(s.markdown.find("| HOMING_VECTOR | homing | >= 288 | 587 | unknown |"), std::string::npos) << s.markdown;
  EXPECT_EQ(s.json.at("delivery_lost_total"), 1);
}

// A subscriber that ran once, start to end, and has fewer messages of an exact channel than its
// publisher sent missed them; a restarted one is not judged (it was down for a while).
TEST(ProcessLogs, SubscribersThatMissedMessagesAreCountedAndListed) {
  const char kNavigatorLog[] = R"(--- launch: navigator run 1, pid 400: /bin/navigator
  ODOMETRY                 received 2990, published 0, rejected 0, handler errors 0
  DRIVE_COMMAND            received 0, published 3000, rejected 0, handler errors 0
)";
  const std::vector<ProcessLog> logs{Parse("homing", kHomingLog), Parse("sim", kSimLog), Parse("navigator", kNavigatorLog)};
  const std::map<std::string, int64_t> recorded{{"OMNI_FRAME", 600}, {"ODOMETRY", 3000}, {"DRIVE_COMMAND", 3000}};
  const Section s = DeliverySection(logs, recorded);
  EXPECT_NE(s.markdown.find("navigator 2990 (10 missed)"), std::string::npos) << s.markdown;
  EXPECT_NE(s.markdown.find("homing 288 |"), std::string::npos) << s.markdown;  // restarted: not judged
  EXPECT_EQ(s.json.at("delivery_missed_by_subscribers_total"), 10);
  EXPECT_EQ(s.json.at("delivery_lost_total"), 0);
  // delivery.csv: every process's counts per channel beside the log's.
  const std::string csv = DeliveryCsv(logs, recorded);
  EXPECT_EQ(csv.substr(0, csv.find('\n')), "process,runs,reported_runs,channel,published,received,rejected,handler_errors,recorded");
  EXPECT_NE(csv.find("\nhoming,2,1,OMNI_FRAME,0,288,2,1,600\n"), std::string::npos) << csv;
  EXPECT_NE(csv.find("\nnavigator,1,1,ODOMETRY,0,2990,0,0,3000\n"), std::string::npos) << csv;
}

// The error per window of message time: an estimator 1 cm off in the first half and 5 cm off in the
// second has windows of 1 and 5 cm, a positive trend and growth; a constant error has neither.
TEST(RunSections, AteWindowsShowAnErrorGrowingWithTime) {
  std::vector<nav::StampedPose> truth, growing, steady;
  const int64_t t0 = 1'000'000'000;
  for (int i = 0; i < 120; ++i) {  // 120 s at 1 Hz
    const int64_t t = t0 + i * 1'000'000LL;
    truth.push_back({t, {0.1 * i, 0, 0}});
    growing.push_back({t, {0.1 * i, i < 60 ? 0.01 : 0.05, 0}});
    steady.push_back({t, {0.1 * i + 0.02, 0, 0}});
  }
  const AteWindows g = EvaluateAteWindows(growing, truth, t0, 30);
  ASSERT_EQ(g.rmse_m.size(), 4u);
  EXPECT_EQ(g.start_s, (std::vector<double>{0, 30, 60, 90}));
  EXPECT_EQ(g.poses, (std::vector<int>{30, 30, 30, 30}));
  EXPECT_NEAR(g.rmse_m[0], 0.01, 1e-9);
  EXPECT_NEAR(g.rmse_m[3], 0.05, 1e-9);
  EXPECT_NEAR(g.growth_m, 0.04, 1e-9);  // last third (one window) minus the first third
  EXPECT_NEAR(g.max_m, 0.05, 1e-9);
  EXPECT_NEAR(g.mean_m, 0.03, 1e-9);
  EXPECT_GT(g.trend_m_per_h, 1.0);      // 4 cm over 1.5 minutes between window centres: about 1.6 m per hour
  const AteWindows s = EvaluateAteWindows(steady, truth, t0, 30);
  EXPECT_NEAR(s.growth_m, 0, 1e-9);
  EXPECT_NEAR(s.trend_m_per_h, 0, 1e-9);
  EXPECT_NEAR(s.mean_m, 0.02, 1e-9);
  EXPECT_THROW(EvaluateAteWindows(steady, truth, t0, 0), std::invalid_argument);
}

TEST(RunSections, HomingErrorAgainstTheTrueDirectionHome) {
  // The robot at (1, 0) heading +y; home at the origin: the true direction is +90 deg (left).
  std::vector<nav::StampedPose> truth{{1000, {1, 0, M_PI / 2}}, {2000, {2, 0, 0}}};
  homing_vector_t good{};
  good.utime = 1000;
  good.valid = true;
  good.direction_rad = static_cast<float>(M_PI / 2 + 0.1);
  homing_vector_t wrong = good;
  wrong.utime = 2000;
  wrong.direction_rad = 0;  // at (2, 0) heading +x, home is behind: 180 deg off
  homing_vector_t invalid = good;
  invalid.valid = false;
  const HomingErrors h = EvaluateHoming({good, wrong, invalid}, truth, {0, 0}, 0);
  EXPECT_EQ(h.vectors, 3);
  EXPECT_EQ(h.valid, 2);
  EXPECT_EQ(h.evaluated, 2);
  EXPECT_NEAR(h.error_deg[0], 0.1 * 180 / M_PI, 1e-3);
  EXPECT_NEAR(h.error_deg[1], 180, 1e-3);
  EXPECT_NEAR(h.within_45, 0.5, 1e-9);
}

TEST(RunSections, PlaceCellErrorIsTheMatchedCellsDistanceToTheTruth) {
  std::vector<nav::StampedPose> truth{{1000, {1, 1, 0}}};
  place_cell_match_t m{};
  m.utime = 1000;
  m.cell_id = 4;
  m.x_m = 1.3;
  m.y_m = 1.4;
  place_cell_match_t none = m;
  none.cell_id = -1;
  const PlaceCellErrors e = EvaluatePlaceCells({m, none}, truth, 0);
  EXPECT_EQ(e.matches, 2);
  EXPECT_EQ(e.unmatched, 1);
  EXPECT_EQ(e.evaluated, 1);
  EXPECT_NEAR(e.mean_m, 0.5, 1e-9);
}

}  // namespace
}  // namespace snapnav::report
