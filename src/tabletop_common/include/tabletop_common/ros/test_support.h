// Shared by the in-process integration tests (rostest gtests that host the nodelets themselves
// with a nodelet::Loader, i.e. one nodelet manager process, so zero-copy can be checked).
#pragma once

#include <functional>
#include <map>
#include <mutex>
#include <string>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <gtest/gtest.h>
#include <nodelet/loader.h>
#include <ros/ros.h>

namespace tabletop_common {
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
inline bool loadNodelet(const std::string& name, const std::string& type,
                        const nodelet::M_string& remappings = nodelet::M_string()) {
  return loader().load(name, type, remappings, nodelet::V_string());
}

// The latest key/value pairs (and summary message) of the /diagnostics status whose name
// contains `status_name`, kept up to date by its own subscription. Thread-safe.
class DiagnosticsValues {
 public:
  explicit DiagnosticsValues(const std::string& status_name) : name_(status_name) {
    ros::NodeHandle nh;
    sub_ = nh.subscribe("/diagnostics", 50, &DiagnosticsValues::onDiagnostics, this);
  }
  bool has(const std::string& key) const {
    std::lock_guard<std::mutex> l(m_);
    return values_.count(key) > 0;
  }
  std::string get(const std::string& key) const {  // "" until reported
    std::lock_guard<std::mutex> l(m_);
    auto it = values_.find(key);
    return it == values_.end() ? std::string() : it->second;
  }
  std::string message() const {
    std::lock_guard<std::mutex> l(m_);
    return message_;
  }

 private:
  void onDiagnostics(const diagnostic_msgs::DiagnosticArray::ConstPtr& d) {
    std::lock_guard<std::mutex> l(m_);
    for (const auto& s : d->status) {
      if (s.name.find(name_) == std::string::npos) continue;
      for (const auto& kv : s.values) values_[kv.key] = kv.value;
      message_ = s.message;
    }
  }
  const std::string name_;
  mutable std::mutex m_;
  std::map<std::string, std::string> values_;
  std::string message_;
  ros::Subscriber sub_;
};

// main() of an in-process nodelet test: gtest and ROS set up, callbacks served by an
// AsyncSpinner of `threads`, and `unload` (default: loader().clear()) run before ros::shutdown()
// so the nodelets go before ROS does (avoids the ROS 1 teardown race).
inline int runNodeletTests(int argc, char** argv, const char* node_name, int threads,
                           const std::function<void()>& unload = [] { loader().clear(); }) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, node_name);
  ros::AsyncSpinner spinner(threads);
  spinner.start();
  const int rc = RUN_ALL_TESTS();
  unload();
  spinner.stop();
  ros::shutdown();
  return rc;
}

}  // namespace test_support
}  // namespace tabletop_common
