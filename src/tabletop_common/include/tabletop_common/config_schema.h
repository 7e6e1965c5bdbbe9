// One parameter style for every stage: a schema binds each key of a stage's YAML file to the
// variable it sets, and the same schema reads the file strictly (an unknown key, a wrong type or
// a wrong list length is an error naming the file and the key) and applies the rosparam
// overrides (tabletop_common/ros/config_overrides.h) with the same checks. A typo therefore
// never silently becomes the default.
//
// Keys of nested maps are paths ("fusion/body/threshold"). An alias is a second, flat name of a
// key (so that `~threads` can override `nodelet/threads`). ROS-free: the cores load their files
// with it and their unit tests check the shipped files against the defaults.
#pragma once

#include <functional>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <yaml-cpp/yaml.h>

namespace tabletop_common {

class ConfigSchema {
 public:
  // A scalar (bool, int, double, std::string, ...) or a std::vector of scalars.
  template <class T>
  ConfigSchema& add(const std::string& key, T* out) {
    setters_[key] = [out](const YAML::Node& n, const std::string& where) {
      try {
        *out = n.as<T>();
      } catch (const YAML::Exception&) {
        throw std::runtime_error(where + ": wrong type");
      }
    };
    return *this;
  }

  // A fixed-size vector, written as a list of N numbers.
  template <class S, int N>
  ConfigSchema& add(const std::string& key, Eigen::Matrix<S, N, 1>* out) {
    setters_[key] = [out](const YAML::Node& n, const std::string& where) {
      const std::string problem = where + ": expected a list of " + std::to_string(N) + " numbers";
      if (!n.IsSequence() || n.size() != static_cast<size_t>(N)) throw std::runtime_error(problem);
      Eigen::Matrix<S, N, 1> v;
      try {
        for (int i = 0; i < N; ++i) v[i] = n[i].as<S>();
      } catch (const YAML::Exception&) {
        throw std::runtime_error(problem);
      }
      *out = v;
    };
    return *this;
  }

  ConfigSchema& alias(const std::string& name, const std::string& key) {
    if (!setters_.count(key)) throw std::logic_error("ConfigSchema: alias " + name + " of unknown key " + key);
    aliases_[name] = key;
    return *this;
  }

  // The key a name stands for (itself or the key of an alias); "" if it is neither.
  std::string resolve(const std::string& name) const {
    if (setters_.count(name)) return name;
    auto it = aliases_.find(name);
    return it == aliases_.end() ? std::string() : it->second;
  }
  bool has(const std::string& name) const { return !resolve(name).empty(); }

  std::vector<std::string> keys() const {
    std::vector<std::string> k;
    for (const auto& kv : setters_) k.push_back(kv.first);
    return k;
  }

  // Sets one key (or alias). `where` prefixes the error ("<file>: " or "rosparam ").
  void set(const std::string& name, const YAML::Node& value, const std::string& where = "") const {
    const std::string key = resolve(name);
    if (key.empty()) throw std::runtime_error(where + name + ": unknown key");
    setters_.at(key)(value, where + name);
  }

  // Applies a YAML map whose keys (recursively) must all be known.
  void apply(const YAML::Node& root, const std::string& where = "") const { applyMap(root, "", where); }

  // Reads a file; errors read "<path>: <key>: <problem>".
  void loadFile(const std::string& path) const {
    YAML::Node root;
    try {
      root = YAML::LoadFile(path);
    } catch (const YAML::Exception& e) {
      throw std::runtime_error(path + ": cannot read: " + e.what());
    }
    try {
      apply(root, path + ": ");
    } catch (const YAML::Exception& e) {
      throw std::runtime_error(path + ": " + e.what());
    }
  }

 private:
  bool isSection(const std::string& prefix) const {
    auto it = setters_.lower_bound(prefix);
    return it != setters_.end() && it->first.compare(0, prefix.size(), prefix) == 0;
  }

  void applyMap(const YAML::Node& node, const std::string& prefix, const std::string& where) const {
    if (!node || node.IsNull()) return;  // an empty file or section: every default holds
    if (!node.IsMap()) {
      const std::string section = prefix.empty() ? "" : prefix.substr(0, prefix.size() - 1) + ": ";
      throw std::runtime_error(where + section + "expected a map");
    }
    for (const auto& kv : node) {
      const std::string key = prefix + kv.first.as<std::string>();
      if (setters_.count(key)) {
        setters_.at(key)(kv.second, where + key);
      } else if (isSection(key + "/")) {
        applyMap(kv.second, key + "/", where);
      } else {
        throw std::runtime_error(where + key + ": unknown key");
      }
    }
  }

  std::map<std::string, std::function<void(const YAML::Node&, const std::string&)>> setters_;
  std::map<std::string, std::string> aliases_;
};

}  // namespace tabletop_common
