#include "tabletop_capture/calibration/marker_detection.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <Eigen/Eigenvalues>

#include <opencv2/aruco.hpp>
#include <opencv2/imgproc.hpp>

#include "tabletop_capture/calibration/marker_layout.h"

namespace tabletop_capture {
namespace {

cv::Ptr<cv::aruco::Dictionary> dictionaryByName(const std::string& name) {
  static const char* names[] = {"DICT_4X4_50", "DICT_4X4_100", "DICT_4X4_250", "DICT_4X4_1000",
                                "DICT_5X5_50", "DICT_5X5_100", "DICT_5X5_250", "DICT_5X5_1000",
                                "DICT_6X6_50", "DICT_6X6_100", "DICT_6X6_250", "DICT_6X6_1000",
                                "DICT_7X7_50", "DICT_7X7_100", "DICT_7X7_250", "DICT_7X7_1000",
                                "DICT_ARUCO_ORIGINAL"};
  for (int i = 0; i < static_cast<int>(sizeof(names) / sizeof(names[0])); ++i)
    if (name == names[i])
      return cv::aruco::getPredefinedDictionary(static_cast<cv::aruco::PREDEFINED_DICTIONARY_NAME>(i));
  throw std::invalid_argument("marker detection: unknown dictionary '" + name + "'");
}

double sample(const cv::Mat& g, double x, double y) {  // bilinear, CV_32F, clamped
  x = std::clamp(x, 0.0, g.cols - 1.001);
  y = std::clamp(y, 0.0, g.rows - 1.001);
  const int x0 = static_cast<int>(x), y0 = static_cast<int>(y);
  const double ax = x - x0, ay = y - y0;
  const float* r0 = g.ptr<float>(y0);
  const float* r1 = g.ptr<float>(y0 + 1);
  return (1 - ay) * ((1 - ax) * r0[x0] + ax * r0[x0 + 1]) + ay * ((1 - ax) * r1[x0] + ax * r1[x0 + 1]);
}

// Refines the 4 corners (clockwise, image) of one marker of `cells` cells per side: points on
// each side where the profile across it crosses halfway between the black border and the
// paper, a line through them (in undistorted pixels with a camera), the corners where the
// lines meet. False (corners unchanged) if an edge has too few clean crossings.
bool refineByEdges(const cv::Mat& g, int cells, const CameraModel* cam, MarkerCorners* corners) {
  auto straight = [&](const Eigen::Vector2d& p) -> Eigen::Vector2d {
    if (!cam) return p;
    const Eigen::Vector2d x = cam->undistort(Eigen::Vector2d((p.x() - cam->cx) / cam->fx, (p.y() - cam->cy) / cam->fy));
    return {cam->fx * x.x() + cam->cx, cam->fy * x.y() + cam->cy};
  };
  auto bent = [&](const Eigen::Vector2d& p) -> Eigen::Vector2d {
    if (!cam) return p;
    const Eigen::Vector2d x = cam->distort(Eigen::Vector2d((p.x() - cam->cx) / cam->fx, (p.y() - cam->cy) / cam->fy));
    return {cam->fx * x.x() + cam->cx, cam->fy * x.y() + cam->cy};
  };
  MarkerCorners c = *corners;
  for (int pass = 0; pass < 2; ++pass) {
    Eigen::Vector3d lines[4];  // a x + b y + c = 0 in straightened pixels, (a, b) unit
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector2d p0 = c[k], p1 = c[(k + 1) % 4];
      const double len = (p1 - p0).norm();
      if (len < 6) return false;
      const Eigen::Vector2d t = (p1 - p0) / len;
      // Clockwise corners in an image (y down): the outside is to the left of the direction.
      const Eigen::Vector2d out(t.y(), -t.x());
      // Across the edge: into the border by less than a cell, out onto the paper as far.
      const double reach = std::clamp(0.45 * len / cells, 0.8, 2.5);
      std::vector<Eigen::Vector2d> pts;
      const int n = static_cast<int>(len * 2);
      for (int i = 0; i <= n; ++i) {
        const double s = 0.15 + 0.7 * i / n;  // away from the corners
        const Eigen::Vector2d q = p0 + s * (p1 - p0);
        const int m = 20;
        double prof[m + 1];
        for (int j = 0; j <= m; ++j) {
          const Eigen::Vector2d r = q + out * (-reach + 2 * reach * j / m);
          prof[j] = sample(g, r.x(), r.y());
        }
        // The levels of the border and of the paper: the darkest inside, the brightest outside
        // (the profile's far end may reach past the paper onto a darker desk).
        const double lo = *std::min_element(prof, prof + m / 2), hi = *std::max_element(prof + m / 2, prof + m + 1);
        if (hi - lo < 20) continue;  // no clean dark-to-light step here
        const double half = (lo + hi) / 2;
        int cross = -1;
        // The first crossing outwards from the darkest point inside.
        const int start = static_cast<int>(std::min_element(prof, prof + m / 2) - prof);
        const int end = static_cast<int>(std::max_element(prof + m / 2, prof + m + 1) - prof);
        for (int j = start; j < end; ++j)
          if (prof[j] < half && prof[j + 1] >= half) {
            if (cross >= 0) { cross = -2; break; }  // two crossings: not a clean edge
            cross = j;
          }
        if (cross < 0) continue;
        const double f = (half - prof[cross]) / (prof[cross + 1] - prof[cross]);
        const double d = -reach + 2 * reach * (cross + f) / m;
        pts.push_back(straight(q + out * d));
      }
      if (pts.size() < 6) return false;
      Eigen::Vector2d mean = Eigen::Vector2d::Zero();
      for (const auto& p : pts) mean += p / pts.size();
      Eigen::Matrix2d C = Eigen::Matrix2d::Zero();
      for (const auto& p : pts) C += (p - mean) * (p - mean).transpose();
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(C);
      const Eigen::Vector2d nrm = es.eigenvectors().col(0);  // smallest eigenvalue: the normal
      lines[k] = Eigen::Vector3d(nrm.x(), nrm.y(), -nrm.dot(mean));
    }
    MarkerCorners next;
    for (int k = 0; k < 4; ++k) {
      // Corner k lies on side k-1 (into it) and side k (out of it).
      const Eigen::Vector3d h = lines[(k + 3) % 4].cross(lines[k]);
      if (std::abs(h.z()) < 1e-9) return false;
      next[k] = bent(h.head<2>() / h.z());
      if ((next[k] - c[k]).norm() > 2.0) return false;  // not the corner the detector found
    }
    c = next;
  }
  *corners = c;
  return true;
}

}  // namespace

std::vector<DetectedMarker> detectMarkers(const cv::Mat& image, const std::string& dictionary,
                                          const CameraModel* camera) {
  if (image.empty()) throw std::invalid_argument("marker detection: empty image");
  const auto dict = dictionaryByName(dictionary);
  cv::Mat grey;
  if (image.channels() == 3) cv::cvtColor(image, grey, cv::COLOR_RGB2GRAY);  // symmetric enough for grey targets
  else grey = image;
  auto params = cv::aruco::DetectorParameters::create();
  // Sub-pixel corners as a start (a 5x5 window stays on the border and the paper); the edge
  // fit below replaces them.
  params->cornerRefinementMethod = cv::aruco::CORNER_REFINE_SUBPIX;
  params->cornerRefinementWinSize = 2;
  // Small markers: contours from 3 % of the image's larger side on. The bits are read on a
  // finer grid than the default 4 px per cell: on these blurred, foreshortened views the coarse
  // grid misread most of a 300 mm marker's views (0 of 16 found, 16 of 16 with 10 px). Smaller
  // adaptive-threshold windows than the default lost big markers too, so they stay.
  params->minMarkerPerimeterRate = 0.03;
  params->minCornerDistanceRate = 0.02;
  params->perspectiveRemovePixelPerCell = 10;
  std::vector<int> ids;
  std::vector<std::vector<cv::Point2f>> corners;
  cv::aruco::detectMarkers(grey, dict, corners, ids, params);
  cv::Mat g;
  grey.convertTo(g, CV_32F);
  std::vector<DetectedMarker> out;
  for (size_t i = 0; i < ids.size(); ++i) {
    DetectedMarker m;
    m.id = ids[i];
    for (int k = 0; k < 4; ++k) m.corners[k] = Eigen::Vector2d(corners[i][k].x, corners[i][k].y);
    refineByEdges(g, dict->markerSize + 2, camera, &m.corners);
    out.push_back(m);
  }
  return out;
}

cv::Mat markerCells(const std::string& dictionary, int id) {
  const auto dict = dictionaryByName(dictionary);
  if (id < 0 || id >= dict->bytesList.rows)
    throw std::invalid_argument("markerCells: id " + std::to_string(id) + " not in " + dictionary);
  cv::Mat cells;
  cv::aruco::drawMarker(dict, id, dict->markerSize + 2, cells, 1);
  return cells;
}

void MarkerSightings::add(const std::vector<DetectedMarker>& markers) {
  for (const auto& m : markers) {
    auto& s = sum_[m.id];
    if (count_[m.id]++ == 0)
      for (auto& p : s) p.setZero();
    for (int k = 0; k < 4; ++k) s[k] += m.corners[k];
  }
}

std::map<int, MarkerCorners> MarkerSightings::mean() const {
  std::map<int, MarkerCorners> out;
  for (const auto& [id, s] : sum_) {
    const double n = count_.at(id);
    for (int k = 0; k < 4; ++k) out[id][k] = s[k] / n;
  }
  return out;
}

}  // namespace tabletop_capture
