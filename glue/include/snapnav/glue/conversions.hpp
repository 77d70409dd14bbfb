#pragma once
// Conversions between message types and libnav types.

#include <string>

#include <Eigen/Core>

#include "snapnav/nav/pose2.hpp"
#include "snapnav/odometry_t.hpp"
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

}  // namespace snapnav::glue
