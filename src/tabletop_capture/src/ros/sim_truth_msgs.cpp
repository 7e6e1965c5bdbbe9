#include "tabletop_capture/ros/sim_truth_msgs.h"

namespace tabletop_capture {
namespace {
geometry_msgs::Point toPoint(const Eigen::Vector3d& p) {
  geometry_msgs::Point q;
  q.x = p.x();
  q.y = p.y();
  q.z = p.z();
  return q;
}
}  // namespace

tabletop_msgs::TrackedTargets toTargetsMsg(const sim::GroundTruth& gt, const ros::Time& stamp,
                                           const std::string& frame_id) {
  tabletop_msgs::TrackedTargets msg;
  msg.header.stamp = stamp;
  msg.header.frame_id = frame_id;
  const struct {
    uint32_t id;
    uint8_t type;
    const Eigen::Vector3d& p;
    bool in;
  } items[] = {{0, tabletop_msgs::TrackedTarget::HAND, gt.left_hand, gt.left_hand_in_workspace},
               {1, tabletop_msgs::TrackedTarget::HAND, gt.right_hand, gt.right_hand_in_workspace},
               {2, tabletop_msgs::TrackedTarget::HEAD, gt.head, gt.head_in_workspace}};
  for (const auto& it : items) {
    tabletop_msgs::TrackedTarget t;
    t.id = it.id;
    t.type = it.type;
    t.position = toPoint(it.p);
    t.weight = 1.0;
    t.active = gt.person_present && it.in;
    msg.targets.push_back(t);
  }
  return msg;
}

tabletop_msgs::BodyPose toBodyPoseMsg(const sim::GroundTruth& gt, const ros::Time& stamp,
                                      const std::string& frame_id) {
  tabletop_msgs::BodyPose msg;
  msg.header.stamp = stamp;
  msg.header.frame_id = frame_id;
  for (int k = 0; k < 18; ++k) msg.state[k] = gt.body_state[k];
  msg.left_hand = toPoint(gt.left_hand);
  msg.right_hand = toPoint(gt.right_hand);
  msg.head = toPoint(gt.head);
  return msg;
}

}  // namespace tabletop_capture
