// The processes replay runs: one entry each. An entry reads the process's config as its main()
// does, lists the channels the node publishes, and builds the node on the replay bus.
#include <ostream>

#include "dead_reckoning_node.hpp"
#include "fused_slam_node.hpp"
#include "homing_node.hpp"
#include "landmarks_node.hpp"
#include "laser_slam_node.hpp"
#include "navigator_node.hpp"
#include "placecells_node.hpp"
#include "ratslam_node.hpp"
#include "replay.hpp"

namespace snapnav::replay {

using namespace processes;

const std::vector<NodeEntry>& ReplayRegistry() {
  static const std::vector<NodeEntry> entries = {
      {"dead-reckoning", "dead_reckoning.ini",
       [](NodeContext& c) {
         const auto config = DeadReckoningConfig::FromIni(c.ini, c.channel_prefix);
         config.Print(c.config_out);
         c.outputs = {config.pose_channel};
         return c.Hold<DeadReckoningNode>(
             [](const DeadReckoningNode& n, std::ostream& out) {
               out << "dead-reckoning: published " << n.published() << " poses\n";
               for (const auto& [reason, k] : n.rejected()) {
                 out << "dead-reckoning:   rejected (" << reason << "): " << k << "\n";
               }
             },
             nullptr, c.bus, config);
       }},
      {"laser-slam", "laser_slam.ini",
       [](NodeContext& c) {
         const auto config = LaserSlamConfig::FromIni(c.ini, c.channel_prefix);
         config.Print(c.config_out);
         c.outputs = {config.pose_channel, config.map_channel};
         return c.Hold<LaserSlamNode>(&LaserSlamNode::Report, nullptr, c.bus, config);
       }},
      {"landmarks", "landmarks.ini",
       [](NodeContext& c) {
         const auto config = LandmarksConfig::FromIni(c.ini, c.channel_prefix);
         config.Print(c.config_out);
         c.outputs = {config.landmarks_channel};
         return c.Hold<LandmarksNode>(&LandmarksNode::Report, nullptr, c.bus, config);
       }},
      {"homing", "homing.ini",
       [](NodeContext& c) {
         const auto config = HomingConfig::FromIni(c.ini, c.channel_prefix);
         config.Print(c.config_out);
         c.outputs = {config.homing_vector_channel};
         return c.Hold<HomingNode>(&HomingNode::Report, nullptr, c.bus, config);
       }},
      {"placecells", "placecells.ini",
       [](NodeContext& c) {
         const auto config = PlaceCellsConfig::FromIni(c.ini, c.channel_prefix);
         config.Print(c.config_out);
         c.outputs = {config.match_channel, config.pose_channel};
         return c.Hold<PlaceCellsNode>(&PlaceCellsNode::Report, [](PlaceCellsNode& n) { n.Save(); }, c.bus, config,
                                       c.log);
       }},
      {"navigator", "navigator.ini",
       [](NodeContext& c) {
         const auto config = NavigatorConfig::FromIni(c.ini, c.channel_prefix);
         config.Print(c.config_out);
         c.outputs = {config.drive_command_channel, config.status_channel};
         return c.Hold<NavigatorNode>(&NavigatorNode::Report, nullptr, c.bus, config);
       }},
      {"ratslam", "ratslam.ini",
       [](NodeContext& c) {
         const auto config = RatSlamConfig::FromIni(c.ini, c.channel_prefix);
         config.Print(c.config_out);
         c.outputs = {config.pose_channel, config.experience_map_channel};
         return c.Hold<RatSlamNode>(&RatSlamNode::Report, nullptr, c.bus, config, c.log);
       }},
      {"fused-slam", "fused_slam.ini",
       [](NodeContext& c) {
         const auto config = FusedSlamConfig::FromIni(c.ini, c.channel_prefix);
         config.Print(c.config_out);
         c.outputs = {config.pose_channel, config.map_channel, config.status_channel};
         return c.Hold<FusedSlamNode>(&FusedSlamNode::Report, nullptr, c.bus, config);
       }},
  };
  return entries;
}

}  // namespace snapnav::replay
