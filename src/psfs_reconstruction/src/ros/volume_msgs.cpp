#include "psfs_reconstruction/ros/volume_msgs.h"

#include <cmath>

#include <sensor_msgs/point_cloud2_iterator.h>

namespace psfs {

void toVoxelVolumeMsg(const ProbabilityVolume& volume, const ros::Time& stamp,
                      const std::string& frame_id, tabletop_msgs::VoxelVolume* msg) {
  msg->header.stamp = stamp;
  msg->header.frame_id = frame_id;
  msg->origin.x = volume.grid.origin.x();
  msg->origin.y = volume.grid.origin.y();
  msg->origin.z = volume.grid.origin.z();
  msg->voxel_size = volume.grid.voxel_size;
  msg->size_x = static_cast<uint32_t>(volume.grid.dims.x());
  msg->size_y = static_cast<uint32_t>(volume.grid.dims.y());
  msg->size_z = static_cast<uint32_t>(volume.grid.dims.z());
  msg->data = volume.data;
}

bool fromVoxelVolumeMsg(const tabletop_msgs::VoxelVolume& msg, ProbabilityVolume* volume,
                        std::string* why) {
  VoxelGrid g;
  g.origin = Eigen::Vector3d(msg.origin.x, msg.origin.y, msg.origin.z);
  g.voxel_size = msg.voxel_size;
  g.dims = Eigen::Vector3i(static_cast<int>(msg.size_x), static_cast<int>(msg.size_y),
                           static_cast<int>(msg.size_z));
  try {
    if (msg.size_x > (1u << 20) || msg.size_y > (1u << 20) || msg.size_z > (1u << 20))
      throw std::invalid_argument("dimension above 2^20");
    g.validate();
  } catch (const std::exception& e) {
    if (why) *why = e.what();
    return false;
  }
  if (msg.data.size() != g.numVoxels()) {
    if (why)
      *why = "data has " + std::to_string(msg.data.size()) + " bytes, size_x * size_y * size_z = " +
             std::to_string(g.numVoxels());
    return false;
  }
  volume->grid = g;
  volume->data = msg.data;
  return true;
}

void toCloudMsg(const ProbabilityVolume& volume, uint8_t threshold_byte, const ros::Time& stamp,
                const std::string& frame_id, sensor_msgs::PointCloud2* msg) {
  msg->header.stamp = stamp;
  msg->header.frame_id = frame_id;
  size_t n = 0;
  for (uint8_t v : volume.data) n += v > threshold_byte;
  sensor_msgs::PointCloud2Modifier mod(*msg);
  mod.setPointCloud2Fields(4, "x", 1, sensor_msgs::PointField::FLOAT32, "y", 1,
                           sensor_msgs::PointField::FLOAT32, "z", 1,
                           sensor_msgs::PointField::FLOAT32, "probability", 1,
                           sensor_msgs::PointField::FLOAT32);
  mod.resize(n);
  msg->height = 1;
  msg->width = static_cast<uint32_t>(n);
  msg->is_dense = true;
  sensor_msgs::PointCloud2Iterator<float> x(*msg, "x"), y(*msg, "y"), z(*msg, "z"),
      p(*msg, "probability");
  for (size_t i = 0; i < volume.data.size(); ++i) {
    if (volume.data[i] <= threshold_byte) continue;
    const Eigen::Vector3d c = volume.grid.centre(i);
    *x = static_cast<float>(c.x());
    *y = static_cast<float>(c.y());
    *z = static_cast<float>(c.z());
    *p = volume.data[i] / 255.0f;
    ++x, ++y, ++z, ++p;
  }
}

}  // namespace psfs
