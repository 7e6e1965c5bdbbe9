// Ground truth of the simulated rig as messages (ground_truth/targets, ground_truth/body_pose).
#pragma once

#include <ros/time.h>

#include <tabletop_msgs/BodyPose.h>
#include <tabletop_msgs/TrackedTargets.h>
#include <tabletop_msgs/VoxelVolume.h>

#include "tabletop_sim/simulated_rig.h"
#include "tabletop_sim/tracking_evaluator.h"

namespace tabletop_sim {

// Targets: id 0 = left hand, 1 = right hand (HAND) at the centroid of the hand's visible skin
// (GroundTruth::*_hand_skin, the MPF's target), 2 = head (HEAD) at its centre; active while the
// person is present and the hand's (palm + fingers) or head's centroid is inside the workspace
// box. BodyPose carries the palm + fingers centroids (the body model's hands).
tabletop_msgs::TrackedTargets toTargetsMsg(const GroundTruth& truth, const ros::Time& stamp,
                                           const std::string& frame_id);
tabletop_msgs::BodyPose toBodyPoseMsg(const GroundTruth& truth, const ros::Time& stamp,
                                      const std::string& frame_id);

// The oracle's occupancy on a workspace grid as VoxelVolumes (ground_truth/body_volume,
// ground_truth/skin_volume; 255 = inside, 0 = outside). The grid follows the pSfS rule: cubic
// voxels of the smallest workspace_size / dims edge, centred in the box along the other axes,
// so the truth lies on the same voxels as psfs/body_volume for the same box and dims.
void toTruthVolumeMsgs(const Oracle& oracle, const Eigen::Vector3d& workspace_min,
                       const Eigen::Vector3d& workspace_size, const Eigen::Vector3i& dims,
                       const ros::Time& stamp, const std::string& frame_id,
                       tabletop_msgs::VoxelVolume* body, tabletop_msgs::VoxelVolume* skin);

// For TrackingEvaluator: a tracker's hands/targets, and ground_truth/targets (ids 0 left
// hand, 1 right hand, 2 head; active = visible).
std::vector<TrackedPoint> toTrackedPoints(const tabletop_msgs::TrackedTargets& msg);
TruthPoints toTruthPoints(const tabletop_msgs::TrackedTargets& msg);

}  // namespace tabletop_sim
