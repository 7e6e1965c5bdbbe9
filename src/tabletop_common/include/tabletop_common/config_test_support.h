// Test helpers for the stages' parameter files (tabletop_common/config_schema.h): what a loader
// throws for a file's text, and which keys a shipped file leaves out. ROS-free, gtest-based.
#pragma once

#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tabletop_common/config_schema.h"

namespace tabletop_common {
namespace config_test {

// Writes `text` to a temporary file, runs load(path) and returns what it threw ("" if it threw
// nothing). Every error must begin with the file's path.
inline std::string errorOf(const std::function<void(const std::string&)>& load, const std::string& text) {
  const std::string path = "/tmp/tabletop_cfg_" + std::to_string(::getpid()) + ".yaml";
  std::ofstream(path) << text;
  std::string what;
  try {
    load(path);
  } catch (const std::runtime_error& e) {
    what = e.what();
    EXPECT_EQ(what.rfind(path + ": ", 0), 0u) << what;
  }
  std::remove(path.c_str());
  return what;
}

// The keys of `schema` the file at `path` does not hold (a key left out of a shipped file would
// hide a default that differs from the file's documentation).
inline std::vector<std::string> keysMissingFrom(const ConfigSchema& schema, const std::string& path) {
  const YAML::Node root = YAML::LoadFile(path);
  std::vector<std::string> missing;
  for (const std::string& key : schema.keys()) {
    YAML::Node n = YAML::Clone(root);
    size_t begin = 0;
    bool found = true;
    while (found) {
      const size_t slash = key.find('/', begin);
      const std::string part = key.substr(begin, slash == std::string::npos ? std::string::npos : slash - begin);
      if (!n.IsMap() || !n[part]) {
        found = false;
        break;
      }
      n = n[part];
      if (slash == std::string::npos) break;
      begin = slash + 1;
    }
    if (!found) missing.push_back(key);
  }
  return missing;
}

}  // namespace config_test
}  // namespace tabletop_common
