// Live tuning of a stage through dynamic_reconfigure (rqt_reconfigure, `rosrun
// dynamic_reconfigure dynparam set /tabletop/psfs skin_threshold 0.8`). The server starts from
// the values in force (the stage's file and rosparam overrides), not from the .cfg defaults, so
// that opening the tuning never changes anything. A new value the stage rejects is refused with
// one warning and the values in force are shown again.
//
// The names of a .cfg are keys (or aliases) of the stage's file. A dynamic_reconfigure server
// writes its values to the parameter server, where the next start of the stage would read them
// as overrides of the file: the ones that were not set before are removed again when the stage
// unloads, so that a reloaded stage starts from its file (a parameter set before it started is
// an override on purpose and stays).
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <boost/thread/recursive_mutex.hpp>
#include <dynamic_reconfigure/server.h>
#include <ros/ros.h>

namespace tabletop_common {

template <class ConfigT>
class LiveTuning {
 public:
  // `apply` takes a new set of values (called in a ROS callback thread) and throws
  // std::exception to refuse it; it hands the values to the stage's own thread if needed.
  LiveTuning(const ros::NodeHandle& pnh, const ConfigT& in_force, std::function<void(const ConfigT&)> apply,
             const std::string& stage)
      : in_force_(in_force),
        apply_(std::move(apply)),
        stage_(stage),
        pnh_(pnh) {
    for (const auto& d : ConfigT::__getParamDescriptions__())
      if (!pnh_.hasParam(d->name)) written_.push_back(d->name);
    // Our own mutex, held while we push the values in force: without it the server warns (as
    // the fault matrix's nodelet reload showed) that updateConfig() could race a callback.
    server_ = std::make_unique<dynamic_reconfigure::Server<ConfigT>>(mutex_, pnh_);
    {
      boost::recursive_mutex::scoped_lock lock(mutex_);
      server_->updateConfig(in_force_);
    }
    server_->setCallback([this](ConfigT& c, uint32_t /*level*/) { onChange(c); });
  }

  ~LiveTuning() {
    server_.reset();
    for (const std::string& name : written_) pnh_.deleteParam(name);
  }

 private:
  void onChange(ConfigT& c) {
    try {
      apply_(c);
      in_force_ = c;
    } catch (const std::exception& e) {
      ROS_WARN("%s: live tuning refused: %s (the values in force are kept)", stage_.c_str(), e.what());
      c = in_force_;  // what the server then publishes as the current values
    }
  }

  ConfigT in_force_;
  std::function<void(const ConfigT&)> apply_;
  std::string stage_;
  ros::NodeHandle pnh_;
  std::vector<std::string> written_;  // names the server wrote that were not set before it
  boost::recursive_mutex mutex_;      // the server's (it outlives the server)
  // Last: destroyed first, so that no callback runs on the members above while they go.
  std::unique_ptr<dynamic_reconfigure::Server<ConfigT>> server_;
};

}  // namespace tabletop_common
