#include "tabletop_sim/ros/sim_bag_writer.h"

#include <rosbag/bag.h>
#include <tf2_msgs/TFMessage.h>

#include <tabletop_msgs/BodyPose.h>
#include <tabletop_msgs/TrackedTargets.h>

#include "tabletop_capture/ros/conversions.h"
#include "tabletop_sim/ros/sim_truth_msgs.h"

namespace tabletop_sim {

void writeSimBag(const SimulatedRig& rig, const SimBagOptions& o,
                 const std::function<void(int, int)>& progress) {
  if (o.frames <= 0) throw std::runtime_error("writeSimBag: frames must be positive");
  if (!ros::Time::isValid()) ros::Time::init();
  rosbag::Bag bag(o.path, rosbag::bagmode::Write);
  if (o.lz4) bag.setCompression(rosbag::compression::LZ4);
  const tabletop_capture::RigDescription& desc = rig.rig();
  const std::string encoding = rig.options().bayer == "none" ? "rgb8" : rig.options().bayer;
  const ros::Time t0(o.start_time);

  // /tf_static once, marked latched so that `rosbag play` re-latches it for late subscribers.
  tf2_msgs::TFMessage tf;
  for (const tabletop_capture::CameraModel& cam : desc.cameras) {
    geometry_msgs::TransformStamped t;
    t.header.stamp = t0;
    t.header.frame_id = desc.world_frame;
    t.child_frame_id = cam.frame_id;
    t.transform = tabletop_capture::toTransform(cam.world_T_camera);
    tf.transforms.push_back(t);
  }
  auto latched = boost::make_shared<ros::M_string>();
  (*latched)["latching"] = "1";
  (*latched)["callerid"] = "/sim_bag_writer";
  // A connection header given to write() is used as is: it must describe the type too.
  (*latched)["type"] = ros::message_traits::datatype(tf);
  (*latched)["md5sum"] = ros::message_traits::md5sum(tf);
  (*latched)["message_definition"] = ros::message_traits::definition(tf);
  bag.write("/tf_static", t0, tf, latched);

  std::vector<sensor_msgs::CameraInfo> infos;
  for (const tabletop_capture::CameraModel& cam : desc.cameras) infos.push_back(tabletop_capture::toCameraInfo(cam));
  for (int f = 0; f < o.frames; ++f) {
    const SimFrame frame = rig.render(f);
    const ros::Time stamp = t0 + ros::Duration(frame.time);
    for (size_t i = 0; i < frame.images.size(); ++i) {
      const std::string base = o.ns + "/" + desc.cameras[i].name;
      sensor_msgs::Image img;
      tabletop_capture::toImageMsg(frame.images[i], encoding, &img);
      img.header.stamp = stamp;
      img.header.seq = f;
      img.header.frame_id = desc.cameras[i].frame_id;
      sensor_msgs::CameraInfo info = infos[i];
      info.header.stamp = stamp;
      info.header.seq = f;
      bag.write(base + "/camera_info", stamp, info);
      bag.write(base + "/image_raw", stamp, img);
    }
    bag.write(o.ns + "/ground_truth/targets", stamp,
              toTargetsMsg(frame.truth, stamp, desc.world_frame));
    bag.write(o.ns + "/ground_truth/body_pose", stamp,
              toBodyPoseMsg(frame.truth, stamp, desc.world_frame));
    if (progress) progress(f + 1, o.frames);
  }
  bag.close();
}

}  // namespace tabletop_sim
