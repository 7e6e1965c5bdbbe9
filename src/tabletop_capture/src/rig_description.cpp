#include "tabletop_capture/rig_description.h"

#include <cmath>
#include <fstream>
#include <iomanip>
#include <set>
#include <sstream>

#include <yaml-cpp/yaml.h>

namespace tabletop_capture {
namespace {

std::string where(const std::string& source, int index, const std::string& camera) {
  std::ostringstream s;
  s << source << ": camera";
  if (!camera.empty()) s << " '" << camera << "'";
  s << " (index " << index << ")";
  return s.str();
}

[[noreturn]] void fail(const std::string& ctx, const std::string& field, const std::string& why) {
  throw RigError(ctx + ": field '" + field + "': " + why);
}

double readScalar(const YAML::Node& cam, const std::string& field, const std::string& ctx) {
  const YAML::Node n = cam[field];
  if (!n) fail(ctx, field, "missing");
  double v;
  try {
    v = n.as<double>();
  } catch (const YAML::Exception&) {
    fail(ctx, field, "not a number");
  }
  if (!std::isfinite(v)) fail(ctx, field, "not finite");
  return v;
}

std::string readString(const YAML::Node& node, const std::string& field, const std::string& ctx) {
  const YAML::Node n = node[field];
  if (!n) fail(ctx, field, "missing");
  if (!n.IsScalar()) fail(ctx, field, "must be a string, not a list or map");
  return n.as<std::string>();
}

// Double-quoted YAML scalar, so that names with '#', ':' or brackets survive a round trip.
std::string quoted(const std::string& text) {
  std::string q = "\"";
  for (char ch : text) {
    if (ch == '"' || ch == '\\') q += '\\';
    q += ch;
  }
  return q + "\"";
}

int readInt(const YAML::Node& cam, const std::string& field, const std::string& ctx) {
  const YAML::Node n = cam[field];
  if (!n) fail(ctx, field, "missing");
  try {
    return n.as<int>();
  } catch (const YAML::Exception&) {
    fail(ctx, field, "not an integer");
  }
}

std::vector<double> readList(const YAML::Node& cam, const std::string& field, size_t expected,
                             const std::string& ctx) {
  const YAML::Node n = cam[field];
  if (!n) fail(ctx, field, "missing");
  if (!n.IsSequence()) fail(ctx, field, "not a list");
  if (n.size() != expected)
    fail(ctx, field,
         "has " + std::to_string(n.size()) + " values, expected " + std::to_string(expected));
  std::vector<double> v;
  for (size_t i = 0; i < n.size(); ++i) {
    double x;
    try {
      x = n[i].as<double>();
    } catch (const YAML::Exception&) {
      fail(ctx, field, "value " + std::to_string(i) + " is not a number");
    }
    if (!std::isfinite(x)) fail(ctx, field, "value " + std::to_string(i) + " is not finite");
    v.push_back(x);
  }
  return v;
}

}  // namespace

int RigDescription::findCamera(const std::string& camera_name) const {
  for (size_t i = 0; i < cameras.size(); ++i)
    if (cameras[i].name == camera_name) return static_cast<int>(i);
  return -1;
}

void validateCamera(const CameraModel& c, const std::string& source, int index) {
  const std::string ctx = where(source, index, c.name);
  if (c.width <= 0) fail(ctx, "width", "must be positive, got " + std::to_string(c.width));
  if (c.height <= 0) fail(ctx, "height", "must be positive, got " + std::to_string(c.height));
  const std::pair<const char*, double> scalars[] = {{"fx", c.fx}, {"fy", c.fy}, {"cx", c.cx},
                                                    {"cy", c.cy}};
  for (const auto& s : scalars)
    if (!std::isfinite(s.second)) fail(ctx, s.first, "not finite");
  if (!(c.fx > 0)) fail(ctx, "fx", "focal length must be positive");
  if (!(c.fy > 0)) fail(ctx, "fy", "focal length must be positive");
  for (double d : c.distortion)
    if (!std::isfinite(d)) fail(ctx, "D", "not finite");
  const Eigen::Matrix3d R = c.world_T_camera.linear();
  const Eigen::Vector3d t = c.world_T_camera.translation();
  if (!R.allFinite()) fail(ctx, "rotation", "not finite");
  if (!t.allFinite()) fail(ctx, "translation", "not finite");
  const double orth = (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (orth > 1e-6) {
    std::ostringstream s;
    s << "not a rotation matrix (|R^T R - I| = " << orth << ")";
    fail(ctx, "rotation", s.str());
  }
  if (R.determinant() < 0) fail(ctx, "rotation", "not a rotation matrix (det = -1, a reflection)");
}

RigDescription parseRigYaml(const std::string& text, const std::string& source) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw RigError(source + ": not valid YAML: " + e.what());
  }
  if (!root.IsMap()) throw RigError(source + ": top level must be a map with 'cameras'");
  RigDescription rig;
  if (root["rig"]) rig.name = readString(root, "rig", source);
  if (root["world_frame"]) rig.world_frame = readString(root, "world_frame", source);
  const YAML::Node cams = root["cameras"];
  if (!cams) throw RigError(source + ": field 'cameras': missing");
  if (!cams.IsSequence() || cams.size() == 0)
    throw RigError(source + ": field 'cameras': must be a non-empty list");
  std::set<std::string> names;
  for (size_t i = 0; i < cams.size(); ++i) {
    const YAML::Node n = cams[i];
    const int idx = static_cast<int>(i);
    CameraModel c;
    if (!n.IsMap()) throw RigError(where(source, idx, "") + ": must be a map");
    c.name = readString(n, "name", where(source, idx, ""));
    const std::string ctx = where(source, idx, c.name);
    if (!names.insert(c.name).second) fail(ctx, "name", "duplicate camera name");
    c.frame_id = n["frame_id"] ? readString(n, "frame_id", ctx) : c.name + "_optical_frame";
    c.width = readInt(n, "width", ctx);
    c.height = readInt(n, "height", ctx);
    c.fx = readScalar(n, "fx", ctx);
    c.fy = readScalar(n, "fy", ctx);
    c.cx = readScalar(n, "cx", ctx);
    c.cy = readScalar(n, "cy", ctx);
    const std::string model =
        n["distortion_model"] ? readString(n, "distortion_model", ctx) : "plumb_bob";
    if (model == "plumb_bob") {
      if (n["D"]) {
        const auto d = readList(n, "D", 5, ctx);
        for (int k = 0; k < 5; ++k) c.distortion[k] = d[k];
      }
    } else if (model != "none") {
      fail(ctx, "distortion_model", "unknown model '" + model + "' (use plumb_bob or none)");
    }
    const auto t = readList(n, "translation", 3, ctx);
    const auto r = readList(n, "rotation", 9, ctx);
    Eigen::Matrix3d R;
    R << r[0], r[1], r[2], r[3], r[4], r[5], r[6], r[7], r[8];
    c.world_T_camera.linear() = R;
    c.world_T_camera.translation() = Eigen::Vector3d(t[0], t[1], t[2]);
    validateCamera(c, source, idx);
    rig.cameras.push_back(c);
  }
  return rig;
}

RigDescription loadRigYaml(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw RigError(path + ": cannot open rig file");
  std::stringstream ss;
  ss << in.rdbuf();
  return parseRigYaml(ss.str(), path);
}

std::string rigToYaml(const RigDescription& rig) {
  std::ostringstream s;
  s << std::setprecision(17);
  s << "# Rig description: see tabletop_sim/config/sim_rig.yaml for the format.\n";
  s << "rig: " << quoted(rig.name) << "\n";
  s << "world_frame: " << quoted(rig.world_frame) << "\n";
  s << "cameras:\n";
  for (const auto& c : rig.cameras) {
    const Eigen::Matrix3d R = c.world_T_camera.linear();
    const Eigen::Vector3d t = c.world_T_camera.translation();
    s << "  - name: " << quoted(c.name) << "\n";
    s << "    frame_id: " << quoted(c.frame_id) << "\n";
    s << "    width: " << c.width << "\n    height: " << c.height << "\n";
    s << "    fx: " << c.fx << "\n    fy: " << c.fy << "\n";
    s << "    cx: " << c.cx << "\n    cy: " << c.cy << "\n";
    s << "    distortion_model: plumb_bob\n";
    s << "    D: [" << c.distortion[0] << ", " << c.distortion[1] << ", " << c.distortion[2]
      << ", " << c.distortion[3] << ", " << c.distortion[4] << "]\n";
    s << "    translation: [" << t.x() << ", " << t.y() << ", " << t.z() << "]\n";
    s << "    rotation: [";
    for (int k = 0; k < 9; ++k) s << R(k / 3, k % 3) << (k < 8 ? ", " : "]\n");
  }
  return s.str();
}

void saveRigYaml(const RigDescription& rig, const std::string& path) {
  std::ofstream out(path);
  if (!out) throw RigError(path + ": cannot write rig file");
  out << rigToYaml(rig);
  if (!out) throw RigError(path + ": write failed");
}

}  // namespace tabletop_capture
