#include "tabletop_capture/camera_calibration_file.h"

#include <cmath>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "tabletop_capture/rig_description.h"

namespace tabletop_capture {
namespace {

std::vector<double> readData(const YAML::Node& root, const std::string& field, size_t n,
                             const std::string& file) {
  const YAML::Node m = root[field];
  if (!m) throw RigError(file + ": field '" + field + "': missing");
  const YAML::Node d = m["data"];
  if (!d || !d.IsSequence() || d.size() != n)
    throw RigError(file + ": field '" + field + "/data': expected a list of " + std::to_string(n) + " numbers");
  std::vector<double> v;
  try {
    for (const auto& x : d) v.push_back(x.as<double>());
  } catch (const YAML::Exception&) {
    throw RigError(file + ": field '" + field + "/data': not a number");
  }
  return v;
}

}  // namespace

CameraModel loadCameraCalibrationYaml(const std::string& path_or_url, const std::string& camera_name) {
  const std::string path =
      path_or_url.rfind("file://", 0) == 0 ? path_or_url.substr(7) : path_or_url;
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::Exception& e) {
    throw RigError(path + ": cannot read: " + e.what());
  }
  if (!root.IsMap()) throw RigError(path + ": expected a map (camera_calibration's YAML format)");
  CameraModel c;
  c.name = camera_name;
  c.frame_id = camera_name + "_optical_frame";
  for (const char* field : {"image_width", "image_height"}) {
    if (!root[field]) throw RigError(path + ": field '" + field + "': missing");
    try {
      (std::string(field) == "image_width" ? c.width : c.height) = root[field].as<int>();
    } catch (const YAML::Exception&) {
      throw RigError(path + ": field '" + field + "': not an integer");
    }
  }
  const std::vector<double> k = readData(root, "camera_matrix", 9, path);
  if (k[1] != 0 || k[3] != 0 || k[6] != 0 || k[7] != 0 || k[8] != 1)
    throw RigError(path + ": field 'camera_matrix/data': not a pinhole matrix [fx 0 cx 0 fy cy 0 0 1]");
  c.fx = k[0];
  c.cx = k[2];
  c.fy = k[4];
  c.cy = k[5];
  std::string model = "plumb_bob";
  if (root["distortion_model"]) model = root["distortion_model"].as<std::string>();
  if (model != "plumb_bob" && model != "none")
    throw RigError(path + ": field 'distortion_model': '" + model + "' is not supported (plumb_bob or none)");
  if (model == "plumb_bob" && root["distortion_coefficients"]) {
    const std::vector<double> d = readData(root, "distortion_coefficients", 5, path);
    for (int i = 0; i < 5; ++i) c.distortion[i] = d[i];
  }
  validateCamera(c, path, 0);
  return c;
}

}  // namespace tabletop_capture
