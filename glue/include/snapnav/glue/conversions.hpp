#pragma once
// Conversions between message types and libnav types.

#include <string>
#include <vector>

#include <Eigen/Core>

#include "snapnav/nav/pose2.hpp"
#include "snapnav/odometry_t.hpp"
#include "snapnav/point_map_t.hpp"
#include "snapnav/pose_t.hpp"

namespace snapnav::glue {

// The increment of an odometry message, in the previous robot frame.
nav::Pose2 OdometryDelta(const odometry_t& msg);
// An odometry message from the cumulative pose and the increment over dt_s (velocities derived).
odometry_t ToOdometryMsg(int64_t utime, const std::string& sensor_name, const nav::Pose2& cumulative,
                         const nav::Pose2& delta, double dt_s);
// The cumulative odometry pose.
nav::Pose2 OdometryPose(const odometry_t& msg);

pose_t ToPoseMsg(int64_t utime, const std::string& estimator, const std::string& frame, const nav::Pose2& pose,
                 const Eigen::Matrix3d& covariance);
nav::Pose2 FromPoseMsg(const pose_t& msg);
Eigen::Matrix3d CovarianceOf(const pose_t& msg);

// A SLAM's point map (world frame, metres) as laser-slam and fused-slam publish it.
point_map_t ToPointMapMsg(int64_t utime, const std::string& estimator, double resolution_m,
                          const std::vector<Eigen::Vector2d>& points);

}  // namespace snapnav::glue

namespace snapnav::glue {

// Increments larger than these are garbage (no robot moves a kilometre or turns a hundred
// radians between two odometry messages); they would overflow a covariance to infinity.
inline constexpr double kMaxOdometryStepM = 1000.0;
inline constexpr double kMaxOdometryStepRad = 100.0;
// Positions farther than this from the origin are garbage too (1000 km): a map built from such a
// start would overflow its integer cells [m].
inline constexpr double kMaxPositionM = 1e6;

// Why an odometry message cannot be used, or "" when it can: its increment must be finite and
// within the bounds above, and with `cumulative` its cumulative pose must pass
// OdometryStartProblem too.
std::string OdometryProblem(const odometry_t& msg, bool cumulative);
// Why the cumulative pose of an odometry message cannot be a start pose, or "" when it can: it
// must be finite, its position within kMaxPositionM. (The first message of a stream fixes the
// start; its increment is relative to a message never seen.)
std::string OdometryStartProblem(const odometry_t& msg);

}  // namespace snapnav::glue
