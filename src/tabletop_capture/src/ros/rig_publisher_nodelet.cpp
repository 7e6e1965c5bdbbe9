// Rig publisher nodelet: publishes a rig YAML as latched cam<i>/camera_info and as static tf
// world -> cam<i>_optical_frame, so real cameras (whose drivers know nothing of the rig's
// calibration) meet the camera-input contract of DESIGN.md section 3.
#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>
#include <ros/ros.h>
#include <tf2_ros/static_transform_broadcaster.h>

#include "tabletop_capture/rig_description.h"
#include "tabletop_capture/ros/conversions.h"

namespace tabletop_capture {

class RigPublisherNodelet : public nodelet::Nodelet {
  void onInit() override {
    ros::NodeHandle& nh = getNodeHandle();
    ros::NodeHandle& pnh = getPrivateNodeHandle();
    std::string rig_file;
    bool publish_info = true;
    if (!pnh.getParam("rig_file", rig_file) || rig_file.empty()) {
      NODELET_FATAL("rig publisher: parameter ~rig_file (path of a rig YAML) is required");
      return;
    }
    pnh.param("publish_camera_info", publish_info, true);
    RigDescription rig;
    try {
      rig = loadRigYaml(rig_file);
    } catch (const RigError& e) {
      NODELET_FATAL("rig publisher: %s", e.what());
      return;
    }
    std::vector<geometry_msgs::TransformStamped> tfs;
    const ros::Time now = ros::Time::now();
    for (const CameraModel& cam : rig.cameras) {
      geometry_msgs::TransformStamped t;
      t.header.stamp = now;
      t.header.frame_id = rig.world_frame;
      t.child_frame_id = cam.frame_id;
      t.transform = toTransform(cam.world_T_camera);
      tfs.push_back(t);
      if (publish_info) {
        ros::Publisher pub =
            nh.advertise<sensor_msgs::CameraInfo>(cam.name + "/camera_info", 1, /*latch=*/true);
        sensor_msgs::CameraInfo info = toCameraInfo(cam);
        info.header.stamp = now;
        pub.publish(info);
        info_pubs_.push_back(pub);
      }
    }
    broadcaster_.sendTransform(tfs);
    NODELET_INFO("rig publisher: rig '%s' from %s: %zu cameras%s", rig.name.c_str(),
                 rig_file.c_str(), rig.cameras.size(),
                 publish_info ? " (latched camera_info + static tf)" : " (static tf only)");
  }

  std::vector<ros::Publisher> info_pubs_;
  tf2_ros::StaticTransformBroadcaster broadcaster_;
};

}  // namespace tabletop_capture

PLUGINLIB_EXPORT_CLASS(tabletop_capture::RigPublisherNodelet, nodelet::Nodelet)
