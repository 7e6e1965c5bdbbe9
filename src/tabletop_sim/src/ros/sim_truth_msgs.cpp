#include "tabletop_sim/ros/sim_truth_msgs.h"

namespace tabletop_sim {
namespace {
geometry_msgs::Point toPoint(const Eigen::Vector3d& p) {
  geometry_msgs::Point q;
  q.x = p.x();
  q.y = p.y();
  q.z = p.z();
  return q;
}
}  // namespace

tabletop_msgs::TrackedTargets toTargetsMsg(const GroundTruth& gt, const ros::Time& stamp,
                                           const std::string& frame_id) {
  tabletop_msgs::TrackedTargets msg;
  msg.header.stamp = stamp;
  msg.header.frame_id = frame_id;
  const struct {
    uint32_t id;
    uint8_t type;
    const Eigen::Vector3d& p;
    bool in;
  } items[] = {{0, tabletop_msgs::TrackedTarget::HAND, gt.left_hand_skin, gt.left_hand_in_workspace},
               {1, tabletop_msgs::TrackedTarget::HAND, gt.right_hand_skin, gt.right_hand_in_workspace},
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

tabletop_msgs::BodyPose toBodyPoseMsg(const GroundTruth& gt, const ros::Time& stamp,
                                      const std::string& frame_id) {
  tabletop_msgs::BodyPose msg;
  msg.header.stamp = stamp;
  msg.header.frame_id = frame_id;
  for (int k = 0; k < 18; ++k) msg.state[k] = gt.body_state[k];
  msg.left_hand = toPoint(gt.left_hand);
  msg.right_hand = toPoint(gt.right_hand);
  msg.head = toPoint(gt.head);
  msg.left_shoulder = toPoint(gt.shoulder[0]);
  msg.right_shoulder = toPoint(gt.shoulder[1]);
  msg.left_elbow = toPoint(gt.elbow[0]);
  msg.right_elbow = toPoint(gt.elbow[1]);
  msg.left_wrist = toPoint(gt.wrist[0]);
  msg.right_wrist = toPoint(gt.wrist[1]);
  msg.valid = gt.person_present;
  return msg;
}

void toTruthVolumeMsgs(const Oracle& oracle, const Eigen::Vector3d& workspace_min,
                       const Eigen::Vector3d& workspace_size, const Eigen::Vector3i& dims,
                       const ros::Time& stamp, const std::string& frame_id,
                       tabletop_msgs::VoxelVolume* body, tabletop_msgs::VoxelVolume* skin) {
  const double voxel = (workspace_size.array() / dims.cast<double>().array()).minCoeff();
  const Eigen::Vector3d origin =
      workspace_min + 0.5 * (workspace_size - voxel * dims.cast<double>());
  std::vector<uint8_t> person, skin_occ;
  oracle.sampleGrid(origin, voxel, dims, &person, &skin_occ);
  for (const auto& pair : {std::make_pair(body, &person), std::make_pair(skin, &skin_occ)}) {
    tabletop_msgs::VoxelVolume* m = pair.first;
    m->header.stamp = stamp;
    m->header.frame_id = frame_id;
    m->origin.x = origin.x();
    m->origin.y = origin.y();
    m->origin.z = origin.z();
    m->voxel_size = voxel;
    m->size_x = dims.x();
    m->size_y = dims.y();
    m->size_z = dims.z();
    m->data.resize(pair.second->size());
    for (size_t i = 0; i < m->data.size(); ++i) m->data[i] = (*pair.second)[i] ? 255 : 0;
  }
}

std::vector<TrackedPoint> toTrackedPoints(const tabletop_msgs::TrackedTargets& msg) {
  std::vector<TrackedPoint> out;
  for (const auto& t : msg.targets) {
    TrackedPoint p;
    p.id = t.id;
    p.hand = t.type == tabletop_msgs::TrackedTarget::HAND;
    p.position = Eigen::Vector3d(t.position.x, t.position.y, t.position.z);
    p.active = t.active;
    out.push_back(p);
  }
  return out;
}

TruthPoints toTruthPoints(const tabletop_msgs::TrackedTargets& msg) {
  TruthPoints truth;
  for (const auto& t : msg.targets) {
    if (t.id > 2) continue;
    truth.position[t.id] = Eigen::Vector3d(t.position.x, t.position.y, t.position.z);
    truth.visible[t.id] = t.active;
  }
  return truth;
}

}  // namespace tabletop_sim
