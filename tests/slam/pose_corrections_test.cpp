// Corrections of published poses (libnav/slam/pose_corrections.hpp): the publisher's record of what
// its poses were relative to, the table it makes after a correction, and a consumer applying it.
#include "snapnav/nav/slam/pose_corrections.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <map>

namespace snapnav::nav {
namespace {

void ExpectPose(const Pose2& got, const Pose2& want, const char* what) {
  EXPECT_NEAR(got.x_m, want.x_m, 1e-12) << what;
  EXPECT_NEAR(got.y_m, want.y_m, 1e-12) << what;
  EXPECT_NEAR(got.theta_rad, want.theta_rad, 1e-12) << what;
}

// Two keyframes; poses published relative to them; then a correction moves keyframe 1 only: the
// poses published on keyframe 1 move with it, those on keyframe 0 and before any keyframe stay.
TEST(PoseCorrections, EachRangeMovesWithItsKeyframe) {
  std::map<int, Pose2> keyframes = {{0, {0, 0, 0}}, {1, {2, 0, 0.5}}};
  PublishedPoses record;
  const Pose2 relative{0.3, 0.1, 0.05};
  record.Note(100, -1, {});                  // before the first keyframe: the start's frame
  record.Note(200, 0, keyframes[0]);
  record.Note(300, 0, keyframes[0]);         // the same keyframe, unmoved: the same range
  record.Note(400, 1, keyframes[1]);
  const Pose2 published_at_400 = keyframes[1].Compose(relative);
  EXPECT_EQ(record.ranges(), 3u);
  keyframes[1] = {2.2, -0.1, 0.45};          // a loop closure moved keyframe 1
  const PoseCorrectionTable table = record.Table([&](int k) { return keyframes.at(k); });
  EXPECT_EQ(PoseCorrectionTableProblem(table), "");
  ASSERT_EQ(table.size(), 2u);               // ranges 100 and 200 are both unchanged: merged
  EXPECT_EQ(table[0].from_utime, 100);
  EXPECT_EQ(table[1].from_utime, 400);
  ExpectPose(CorrectPublishedPose(table, 450, published_at_400), keyframes[1].Compose(relative), "on keyframe 1");
  const Pose2 on_0 = keyframes[0].Compose(relative);
  ExpectPose(CorrectPublishedPose(table, 250, on_0), on_0, "on keyframe 0");
  ExpectPose(CorrectPublishedPose(table, 50, published_at_400), published_at_400, "before the first range");
  ExpectPose(CorrectPublishedPose({}, 450, published_at_400), published_at_400, "no table");
}

// A keyframe corrected while poses are published on it: the poses before the correction and after
// it are two ranges with their own transforms (what was published before moved; after, not yet).
TEST(PoseCorrections, ACorrectionStartsANewRangeOnTheSameKeyframe) {
  Pose2 k0{1, 1, 0};
  PublishedPoses record;
  record.Note(100, 0, k0);
  const Pose2 before = k0.Compose({0.5, 0, 0});
  k0 = {1.1, 0.9, 0.02};                     // first correction
  record.Note(200, 0, k0);
  const Pose2 after = k0.Compose({0.6, 0, 0});
  EXPECT_EQ(record.ranges(), 2u);
  k0 = {1.0, 1.0, 0.01};                     // second correction
  const PoseCorrectionTable table = record.Table([&](int) { return k0; });
  ASSERT_EQ(table.size(), 2u);
  ExpectPose(CorrectPublishedPose(table, 150, before), k0.Compose({0.5, 0, 0}), "published before the first");
  ExpectPose(CorrectPublishedPose(table, 250, after), k0.Compose({0.6, 0, 0}), "published after it");
}

// Two poses at one time keep the later's keyframe; a pose stamped before the last one (a scan out
// of order) starts no range and takes the range that holds its time; the record is kept.
TEST(PoseCorrections, APoseStampedBeforeTheLastStartsNoRange) {
  std::map<int, Pose2> k = {{0, {}}, {1, {1, 0, 0}}, {2, {2, 0, 0}}, {3, {3, 0, 0}}};
  PublishedPoses record;
  record.Note(100, 0, k[0]);
  record.Note(200, 1, k[1]);
  record.Note(200, 2, k[2]);
  EXPECT_EQ(record.ranges(), 2u);
  record.Note(150, 3, k[3]);  // out of order
  EXPECT_EQ(record.ranges(), 2u);
  record.Note(300, 3, k[3]);
  EXPECT_EQ(record.ranges(), 3u);
  k[0] = {0, 0.5, 0};  // a correction moves keyframe 0 only
  const PoseCorrectionTable table = record.Table([&](int i) { return k.at(i); });
  ExpectPose(CorrectPublishedPose(table, 150, {0.2, 0, 0}), {0.2, 0.5, 0}, "published at 150, on keyframe 0");
  ExpectPose(CorrectPublishedPose(table, 250, {2.2, 0, 0}), {2.2, 0, 0}, "published at 250, on keyframe 2");
}

TEST(PoseCorrections, ATableOutOfOrderOrNotFiniteIsNamed) {
  EXPECT_EQ(PoseCorrectionTableProblem({{1, {}}, {2, {}}}), "");
  EXPECT_NE(PoseCorrectionTableProblem({{2, {}}, {2, {}}}).find("range 1 starts at utime 2"), std::string::npos);
  EXPECT_NE(PoseCorrectionTableProblem({{1, {0, std::nan(""), 0}}}).find("range 0 has a non-finite"), std::string::npos);
  EXPECT_NE(PoseCorrectionTableProblem({{1, {}}, {2, {1e300, 0, 0}}}).find("range 1 has an absurd transform"),
            std::string::npos);
}

}  // namespace
}  // namespace snapnav::nav
