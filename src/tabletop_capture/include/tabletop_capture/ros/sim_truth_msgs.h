// Ground truth of the simulated rig as messages (ground_truth/targets, ground_truth/body_pose).
#pragma once

#include <ros/time.h>

#include <tabletop_msgs/BodyPose.h>
#include <tabletop_msgs/TrackedTargets.h>

#include "tabletop_capture/sim/simulated_rig.h"

namespace tabletop_capture {

// Targets: id 0 = left hand, 1 = right hand (HAND), 2 = head (HEAD); active while the person
// is present and the target's centroid is inside the workspace box.
tabletop_msgs::TrackedTargets toTargetsMsg(const sim::GroundTruth& truth, const ros::Time& stamp,
                                           const std::string& frame_id);
tabletop_msgs::BodyPose toBodyPoseMsg(const sim::GroundTruth& truth, const ros::Time& stamp,
                                      const std::string& frame_id);

}  // namespace tabletop_capture
