#include "tabletop_capture/calibration/rig_layout_plot.h"

#include <algorithm>
#include <cstdio>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

namespace tabletop_capture {

cv::Scalar rigLayoutCameraColour(int index) {
  // Saturated, distinct, none grey (the box and the points are grey and black).
  static const cv::Scalar palette[] = {{40, 40, 220},  {40, 160, 40},  {220, 80, 30},  {0, 160, 230},
                                       {180, 40, 180}, {160, 160, 0},  {30, 100, 170}, {120, 60, 230}};
  return palette[index % 8];
}

cv::Mat drawRigLayout(const RigDescription& rig, const RigLayoutPlotOptions& o) {
  if (o.width < 200 || o.height < 100) throw std::invalid_argument("drawRigLayout: image smaller than 200x100");
  cv::Mat img(o.height, o.width, CV_8UC3, cv::Scalar(255, 255, 255));
  // Extent of everything drawn, world.
  Eigen::AlignedBox3d box = o.workspace;
  for (const auto& c : rig.cameras) {
    box.extend(c.center());
    box.extend(c.center() + o.arrow_length * c.world_T_camera.linear().col(2));
  }
  for (const auto& m : o.markers)
    for (const auto& p : m) box.extend(p);
  for (const auto& p : o.points) box.extend(p);
  const int title_h = o.title.empty() ? 0 : 28, label_h = 22, margin = 40;
  const int panel_w = o.width / 2;
  const int panel_h = o.height - title_h - label_h;
  const Eigen::Vector3d lo = box.min(), hi = box.max();
  // One scale (px per m) for both panels: top uses x-y, side x-z.
  const double sx = (panel_w - 2.0 * margin) / std::max(hi.x() - lo.x(), 1e-6);
  const double sy = (panel_h - 2.0 * margin) / std::max(hi.y() - lo.y(), 1e-6);
  const double sz = (panel_h - 2.0 * margin) / std::max(hi.z() - lo.z(), 1e-6);
  const double s = std::min({sx, sy, sz});
  const Eigen::Vector3d mid = (lo + hi) / 2;
  auto top = [&](const Eigen::Vector3d& p) {
    return cv::Point2d(panel_w / 2.0 + (p.x() - mid.x()) * s, title_h + label_h + panel_h / 2.0 - (p.y() - mid.y()) * s);
  };
  auto side = [&](const Eigen::Vector3d& p) {
    return cv::Point2d(panel_w + panel_w / 2.0 + (p.x() - mid.x()) * s,
                       title_h + label_h + panel_h / 2.0 - (p.z() - mid.z()) * s);
  };
  const auto font = cv::FONT_HERSHEY_SIMPLEX;
  if (!o.title.empty()) cv::putText(img, o.title, {10, 20}, font, 0.6, {0, 0, 0}, 1, cv::LINE_AA);
  cv::putText(img, "top view (x right, y up)", {10, title_h + 16}, font, 0.5, {0, 0, 0}, 1, cv::LINE_AA);
  cv::putText(img, "side view (x right, z up)", {panel_w + 10, title_h + 16}, font, 0.5, {0, 0, 0}, 1, cv::LINE_AA);
  cv::line(img, {panel_w, title_h}, {panel_w, o.height}, {200, 200, 200}, 1);
  const cv::Scalar grey(150, 150, 150);
  // Workspace box: rectangle in each view; the desk (z = 0) darker in the side view.
  const Eigen::Vector3d wl = o.workspace.min(), wh = o.workspace.max();
  cv::rectangle(img, top(wl), top(Eigen::Vector3d(wh.x(), wh.y(), 0)), grey, 1, cv::LINE_AA);
  cv::rectangle(img, side(wl), side(Eigen::Vector3d(wh.x(), 0, wh.z())), grey, 1, cv::LINE_AA);
  cv::line(img, side(Eigen::Vector3d(lo.x(), 0, 0)), side(Eigen::Vector3d(hi.x(), 0, 0)), {90, 90, 90}, 2);
  // Where the user sits (DESIGN.md section 3: y points from the user towards the screen).
  cv::putText(img, "user", top(Eigen::Vector3d(mid.x(), wl.y(), 0)) + cv::Point2d(-16, 18), font, 0.45,
              {100, 100, 100}, 1, cv::LINE_AA);
  // World axes at the origin (x red, y green, z blue as in rviz).
  const double ax = 0.1;
  cv::arrowedLine(img, top({0, 0, 0}), top({ax, 0, 0}), {0, 0, 255}, 2, cv::LINE_AA, 0, 0.25);
  cv::arrowedLine(img, top({0, 0, 0}), top({0, ax, 0}), {0, 170, 0}, 2, cv::LINE_AA, 0, 0.25);
  cv::arrowedLine(img, side({0, 0, 0}), side({ax, 0, 0}), {0, 0, 255}, 2, cv::LINE_AA, 0, 0.25);
  cv::arrowedLine(img, side({0, 0, 0}), side({0, 0, ax}), {255, 0, 0}, 2, cv::LINE_AA, 0, 0.25);
  for (const auto& m : o.markers) {
    std::vector<cv::Point> poly;
    for (const auto& p : m) poly.push_back(top(p));
    cv::polylines(img, poly, true, {0, 0, 0}, 2, cv::LINE_AA);
    cv::line(img, side(m[0]), side(m[2]), {0, 0, 0}, 3);
  }
  for (const auto& p : o.points) {
    cv::circle(img, top(p), 1, {60, 60, 60}, cv::FILLED);
    cv::circle(img, side(p), 1, {60, 60, 60}, cv::FILLED);
  }
  for (size_t i = 0; i < rig.cameras.size(); ++i) {
    const auto& c = rig.cameras[i];
    const cv::Scalar col = rigLayoutCameraColour(static_cast<int>(i));
    const Eigen::Vector3d tip = c.center() + o.arrow_length * c.world_T_camera.linear().col(2);
    for (auto view : {0, 1}) {
      const cv::Point2d p = view ? side(c.center()) : top(c.center());
      const cv::Point2d q = view ? side(tip) : top(tip);
      cv::arrowedLine(img, p, q, col, 2, cv::LINE_AA, 0, 0.15);
      cv::circle(img, p, 6, col, cv::FILLED, cv::LINE_AA);
      // Label right of the disc, or left of it near the panel's right edge.
      const double right_edge = view ? o.width : panel_w;
      const cv::Point2d at = p.x + 60 > right_edge ? p + cv::Point2d(-58, -8) : p + cv::Point2d(8, -8);
      cv::putText(img, c.name, at, font, 0.45, col, 1, cv::LINE_AA);
    }
  }
  char scale[64];
  std::snprintf(scale, sizeof scale, "grey: the workspace box; axes of 0.1 m at the world origin");
  cv::putText(img, scale, {10, o.height - 8}, font, 0.4, {100, 100, 100}, 1, cv::LINE_AA);
  return img;
}

}  // namespace tabletop_capture
