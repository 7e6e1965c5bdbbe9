#include "tabletop_capture/calibration/marker_layout.h"

#include <cmath>
#include <fstream>
#include <iomanip>
#include <set>
#include <sstream>

#include <yaml-cpp/yaml.h>

namespace tabletop_capture {
namespace {

struct DictionaryInfo {
  const char* name;
  int size, bits;
};
// OpenCV's predefined dictionaries (cv::aruco::PREDEFINED_DICTIONARY_NAME order).
constexpr DictionaryInfo kDictionaries[] = {
    {"DICT_4X4_50", 50, 4},     {"DICT_4X4_100", 100, 4},   {"DICT_4X4_250", 250, 4},
    {"DICT_4X4_1000", 1000, 4}, {"DICT_5X5_50", 50, 5},     {"DICT_5X5_100", 100, 5},
    {"DICT_5X5_250", 250, 5},   {"DICT_5X5_1000", 1000, 5}, {"DICT_6X6_50", 50, 6},
    {"DICT_6X6_100", 100, 6},   {"DICT_6X6_250", 250, 6},   {"DICT_6X6_1000", 1000, 6},
    {"DICT_7X7_50", 50, 7},     {"DICT_7X7_100", 100, 7},   {"DICT_7X7_250", 250, 7},
    {"DICT_7X7_1000", 1000, 7}, {"DICT_ARUCO_ORIGINAL", 1024, 5}};

const DictionaryInfo* info(const std::string& name) {
  for (const auto& d : kDictionaries)
    if (name == d.name) return &d;
  return nullptr;
}

}  // namespace

bool markerDictionaryKnown(const std::string& name) { return info(name) != nullptr; }
int markerDictionarySize(const std::string& name) { return info(name) ? info(name)->size : 0; }
int markerDictionaryBits(const std::string& name) { return info(name) ? info(name)->bits : 0; }

int MarkerLayout::find(int id) const {
  for (size_t i = 0; i < markers.size(); ++i)
    if (markers[i].id == id) return static_cast<int>(i);
  return -1;
}

std::array<Eigen::Vector3d, 4> MarkerLayout::corners(int index) const {
  const DeskMarker& m = markers.at(index);
  const double h = m.size / 2;
  const Eigen::Vector3d c(m.centre.x(), m.centre.y(), 0.0);
  return {{c + Eigen::Vector3d(-h, h, 0), c + Eigen::Vector3d(h, h, 0), c + Eigen::Vector3d(h, -h, 0),
           c + Eigen::Vector3d(-h, -h, 0)}};
}

void MarkerLayout::validate() const {
  if (!markerDictionaryKnown(dictionary))
    throw std::invalid_argument("marker layout: field 'dictionary': unknown dictionary '" + dictionary +
                                "' (e.g. DICT_4X4_50)");
  if (markers.empty()) throw std::invalid_argument("marker layout: field 'markers': no marker");
  std::set<int> ids;
  for (size_t i = 0; i < markers.size(); ++i) {
    const auto& m = markers[i];
    const std::string where = "marker layout: marker " + std::to_string(i) + " (id " + std::to_string(m.id) + "): ";
    if (m.id < 0 || m.id >= markerDictionarySize(dictionary))
      throw std::invalid_argument(where + "field 'id': not in " + dictionary);
    if (!ids.insert(m.id).second) throw std::invalid_argument(where + "field 'id': repeated");
    if (!(m.size > 0) || !std::isfinite(m.size)) throw std::invalid_argument(where + "field 'size': must be > 0 m");
    if (!m.centre.allFinite()) throw std::invalid_argument(where + "field 'x'/'y': not finite");
    for (size_t j = 0; j < i; ++j) {
      const auto& o = markers[j];
      const Eigen::Vector2d d = (m.centre - o.centre).cwiseAbs();
      if (d.x() < (m.size + o.size) / 2 && d.y() < (m.size + o.size) / 2)
        throw std::invalid_argument(where + "overlaps marker id " + std::to_string(o.id));
    }
  }
}

MarkerLayout MarkerLayout::scaled(double factor) const {
  MarkerLayout l = *this;
  for (auto& m : l.markers) {
    m.size *= factor;
    m.centre *= factor;
  }
  return l;
}

MarkerLayout defaultMarkerLayout() {
  MarkerLayout l;
  l.dictionary = "DICT_4X4_50";
  const double s = 0.15;
  l.markers = {{0, s, {0.0, 0.0}}, {1, s, {-0.35, -0.3}}, {2, s, {0.35, -0.3}},
               {3, s, {0.35, 0.3}}, {4, s, {-0.35, 0.3}}};
  return l;
}

MarkerLayout parseMarkerLayoutYaml(const std::string& text, const std::string& source) {
  MarkerLayout l;
  try {
    const YAML::Node root = YAML::Load(text);
    if (!root.IsMap()) throw std::runtime_error(source + ": not a YAML map");
    if (root["dictionary"]) l.dictionary = root["dictionary"].as<std::string>();
    const YAML::Node ms = root["markers"];
    if (!ms || !ms.IsSequence()) throw std::runtime_error(source + ": field 'markers': missing or not a list");
    for (size_t i = 0; i < ms.size(); ++i) {
      const YAML::Node n = ms[i];
      for (const char* f : {"id", "size", "x", "y"})
        if (!n[f]) throw std::runtime_error(source + ": marker " + std::to_string(i) + ": field '" + f + "' missing");
      DeskMarker m;
      m.id = n["id"].as<int>();
      m.size = n["size"].as<double>();
      m.centre = Eigen::Vector2d(n["x"].as<double>(), n["y"].as<double>());
      l.markers.push_back(m);
    }
  } catch (const YAML::Exception& e) {
    throw std::runtime_error(source + ": " + e.what());
  }
  try {
    l.validate();
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(source + ": " + e.what());
  }
  return l;
}

MarkerLayout loadMarkerLayoutYaml(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot read");
  std::stringstream s;
  s << in.rdbuf();
  return parseMarkerLayoutYaml(s.str(), path);
}

std::string markerLayoutToYaml(const MarkerLayout& layout) {
  std::ostringstream s;
  s << std::setprecision(9);
  s << "# Desk markers (tabletop_capture/calibration/marker_layout.h): size = the black square's\n"
       "# edge, x y = its centre on the desk in world (m); each marker's x along world x.\n";
  s << "dictionary: " << layout.dictionary << "\nmarkers:\n";
  for (const auto& m : layout.markers)
    s << "  - {id: " << m.id << ", size: " << m.size << ", x: " << m.centre.x() << ", y: " << m.centre.y() << "}\n";
  return s.str();
}

}  // namespace tabletop_capture
