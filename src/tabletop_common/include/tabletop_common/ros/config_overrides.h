// The ROS half of the one parameter style (tabletop_common/config_schema.h): a stage reads
// ~config_file (its package's config/<stage>.yaml by default) strictly, then every private
// parameter overrides the key (or alias) it names, through the same type checks. A private
// parameter that is neither a key of the file nor one the nodelet reads itself is an error, so
// that a typo in a launch file stops the stage with its name instead of silently keeping the
// default.
#pragma once

#include <set>
#include <sstream>
#include <stdexcept>
#include <string>

#include <ros/ros.h>
#include <xmlrpcpp/XmlRpcValue.h>
#include <yaml-cpp/yaml.h>

#include "tabletop_common/config_schema.h"

namespace tabletop_common {

namespace detail {

inline YAML::Node toYaml(XmlRpc::XmlRpcValue& v) {
  switch (v.getType()) {
    case XmlRpc::XmlRpcValue::TypeBoolean:
      return YAML::Node(static_cast<bool>(v));
    case XmlRpc::XmlRpcValue::TypeInt:
      return YAML::Node(static_cast<int>(v));
    case XmlRpc::XmlRpcValue::TypeDouble: {
      // Through text, so that 0.1 reads back as the double the file's "0.1" would give.
      std::ostringstream s;
      s.precision(17);
      s << static_cast<double>(v);
      return YAML::Node(s.str());
    }
    case XmlRpc::XmlRpcValue::TypeString:
      return YAML::Node(static_cast<std::string>(v));
    case XmlRpc::XmlRpcValue::TypeArray: {
      YAML::Node seq(YAML::NodeType::Sequence);
      for (int i = 0; i < v.size(); ++i) seq.push_back(toYaml(v[i]));
      return seq;
    }
    default:
      throw std::runtime_error("unsupported parameter type");
  }
}

}  // namespace detail

// Applies the private parameters of `pnh` to the schema. `nodelet_params` are the names (below
// the private namespace) that the nodelet reads itself and that are not keys of the file.
// Throws std::runtime_error "rosparam ~<name>: <problem>".
inline void applyPrivateOverrides(const ros::NodeHandle& pnh, const ConfigSchema& schema,
                                  std::set<std::string> nodelet_params) {
  nodelet_params.insert("config_file");
  const std::string ns = pnh.getNamespace() + "/";
  std::vector<std::string> names;
  ros::param::getParamNames(names);
  for (const std::string& full : names) {
    if (full.compare(0, ns.size(), ns) != 0) continue;
    const std::string name = full.substr(ns.size());
    if (nodelet_params.count(name)) continue;
    if (!schema.has(name)) {
      throw std::runtime_error("rosparam ~" + name +
                               ": unknown parameter (not a key of the config file; a typo?)");
    }
    XmlRpc::XmlRpcValue v;
    if (!pnh.getParam(name, v)) continue;  // deleted meanwhile
    YAML::Node node;
    try {
      node = detail::toYaml(v);
    } catch (const std::runtime_error& e) {
      throw std::runtime_error("rosparam ~" + name + ": " + e.what());
    }
    schema.set(name, node, "rosparam ~");
  }
}

// ~config_file (default `default_file`) through the schema, then the private overrides.
// Returns the file that was read.
inline std::string loadConfigWithOverrides(const ros::NodeHandle& pnh, const std::string& default_file,
                                           const ConfigSchema& schema,
                                           const std::set<std::string>& nodelet_params) {
  std::string file = default_file;
  pnh.param("config_file", file, file);
  schema.loadFile(file);
  applyPrivateOverrides(pnh, schema, nodelet_params);
  return file;
}

}  // namespace tabletop_common
