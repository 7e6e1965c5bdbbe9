// Pairs the body and skin volumes of one frame set (psfs publishes them one after the other,
// with the same stamp) for the trackers that need both. Header-only, ROS layer.
#pragma once

#include <mutex>

#include <tabletop_msgs/VoxelVolume.h>

namespace psfs {

class VolumePairing {
 public:
  using Ptr = tabletop_msgs::VoxelVolume::ConstPtr;
  // Keeps m until the other volume of its stamp arrives; then returns true with both. A
  // pending volume whose partner never comes is replaced by the next of its kind.
  bool add(const Ptr& m, bool skin, Ptr* skin_out, Ptr* body_out) {
    std::lock_guard<std::mutex> lock(mutex_);
    Ptr& mine = skin ? pending_skin_ : pending_body_;
    Ptr& other = skin ? pending_body_ : pending_skin_;
    if (other && other->header.stamp == m->header.stamp) {
      *skin_out = skin ? m : other;
      *body_out = skin ? other : m;
      other.reset();
      return true;
    }
    mine = m;
    return false;
  }

 private:
  std::mutex mutex_;
  Ptr pending_skin_, pending_body_;
};

}  // namespace psfs
