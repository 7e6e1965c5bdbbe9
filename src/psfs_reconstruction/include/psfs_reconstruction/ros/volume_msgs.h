// Conversions between fused volumes and their messages (ROS layer only): VoxelVolume (the
// DESIGN.md section 3 contract: min-corner origin, cubic voxels, x fastest) and PointCloud2
// (x, y, z, probability per voxel above a threshold, for rviz).
#pragma once

#include <string>

#include <ros/time.h>
#include <sensor_msgs/PointCloud2.h>
#include <tabletop_msgs/VoxelVolume.h>

#include "psfs_reconstruction/probability_volume.h"

namespace psfs {

void toVoxelVolumeMsg(const ProbabilityVolume& volume, const ros::Time& stamp,
                      const std::string& frame_id, tabletop_msgs::VoxelVolume* msg);
// False (with the reason) for a message that breaks the contract: data size differing from
// size_x * size_y * size_z, a non-positive or non-finite voxel size or origin.
bool fromVoxelVolumeMsg(const tabletop_msgs::VoxelVolume& msg, ProbabilityVolume* volume,
                        std::string* why);
// Voxel centres with value > threshold_byte, fields x, y, z, probability (float32).
void toCloudMsg(const ProbabilityVolume& volume, uint8_t threshold_byte, const ros::Time& stamp,
                const std::string& frame_id, sensor_msgs::PointCloud2* msg);

}  // namespace psfs
