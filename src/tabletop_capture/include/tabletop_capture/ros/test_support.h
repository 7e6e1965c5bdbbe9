// Shared by the in-process integration tests (rostest gtests that host the nodelets themselves
// with a nodelet::Loader, i.e. one nodelet manager process, so zero-copy can be checked).
#pragma once

#include <functional>

#include <nodelet/loader.h>
#include <ros/ros.h>

namespace tabletop_capture {
namespace test_support {

// Polls `cond` every 20 ms (wall time) until it holds or `seconds` pass; returns cond().
inline bool waitFor(const std::function<bool()>& cond, double seconds) {
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(seconds);
  while (ros::WallTime::now() < end && !cond()) ros::WallDuration(0.02).sleep();
  return cond();
}

// The test process's nodelet loader. Never destroyed: with plugins from several libraries
// loaded, class_loader throws LibraryUnloadException from the loader's destructor at exit
// (after the tests passed). Call loader().clear() in main() before ros::shutdown() to unload
// the nodelets themselves (avoids the ROS 1 teardown race).
inline nodelet::Loader& loader() {
  static nodelet::Loader* l = new nodelet::Loader(false);
  return *l;
}

// Loads a nodelet into loader() with no remappings or arguments.
inline bool loadNodelet(const std::string& name, const std::string& type) {
  return loader().load(name, type, nodelet::M_string(), nodelet::V_string());
}

}  // namespace test_support
}  // namespace tabletop_capture
