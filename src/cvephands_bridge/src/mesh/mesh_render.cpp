#include "cvephands_bridge/mesh/mesh_render.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <Eigen/Geometry>

namespace cvephands {
namespace {

constexpr double kNear = 0.05;  // m

struct View {
  Eigen::Matrix3d r;  // rows: camera x (right), y (down), z (forward) in world coordinates
  Eigen::Vector3d eye;
  double f, cx, cy;
};

View makeView(const RenderCamera& c) {
  const Eigen::Vector3d fwd = c.target - c.eye;
  if (!(fwd.norm() > 1e-9)) throw std::invalid_argument("renderMeshes: eye == target");
  if (c.width < 1 || c.height < 1) throw std::invalid_argument("renderMeshes: image size < 1");
  if (!(c.vertical_fov_deg > 0.0 && c.vertical_fov_deg < 180.0))
    throw std::invalid_argument("renderMeshes: vertical_fov_deg must be in (0, 180)");
  const Eigen::Vector3d z = fwd.normalized();
  const Eigen::Vector3d x = z.cross(c.up);
  if (!(x.norm() > 1e-9)) throw std::invalid_argument("renderMeshes: up is parallel to the view");
  View v;
  v.r.row(0) = x.normalized();
  v.r.row(2) = z;
  v.r.row(1) = z.cross(v.r.row(0).transpose()).normalized();
  v.eye = c.eye;
  v.f = 0.5 * c.height / std::tan(0.5 * c.vertical_fov_deg * M_PI / 180.0);
  v.cx = 0.5 * c.width;
  v.cy = 0.5 * c.height;
  return v;
}

}  // namespace

cv::Mat renderMeshes(const std::vector<RenderItem>& items, const RenderCamera& camera,
                     const cv::Vec3b& background) {
  const View view = makeView(camera);
  const int w = camera.width, h = camera.height;
  cv::Mat image(h, w, CV_8UC3, background);
  std::vector<float> depth(size_t(w) * h, std::numeric_limits<float>::infinity());
  // Head light, a little above the camera, so faces towards the viewer are bright.
  const Eigen::Vector3d light = -(view.r.row(2).transpose() - 0.4 * view.r.row(1).transpose()).normalized();
  for (const RenderItem& item : items) {
    if (!item.mesh) continue;
    const TriangleMesh& m = *item.mesh;
    const size_t nv = m.vertices.size();
    std::vector<Eigen::Vector3d> pc(nv);  // camera coordinates
    std::vector<float> shade(nv, 1.0f);
    for (size_t i = 0; i < nv; ++i) {
      pc[i] = view.r * (m.vertices[i].cast<double>() - view.eye);
      if (m.hasNormals())
        shade[i] = float(0.25 + 0.75 * std::max(0.0, m.normals[i].cast<double>().dot(light)));
    }
    for (size_t t = 0; t + 2 < m.triangles.size(); t += 3) {
      const uint32_t ia = m.triangles[t], ib = m.triangles[t + 1], ic = m.triangles[t + 2];
      if (ia >= nv || ib >= nv || ic >= nv) continue;
      const Eigen::Vector3d& a = pc[ia];
      const Eigen::Vector3d& b = pc[ib];
      const Eigen::Vector3d& c = pc[ic];
      if (a.z() < kNear || b.z() < kNear || c.z() < kNear) continue;
      float sa = shade[ia], sb = shade[ib], sc = shade[ic];
      if (!m.hasNormals()) {
        const Eigen::Vector3f n = (m.vertices[ib] - m.vertices[ia]).cross(m.vertices[ic] - m.vertices[ia]);
        const float s = n.norm() > 0 ? float(0.25 + 0.75 * std::max(0.0, n.normalized().cast<double>().dot(light))) : 0.25f;
        sa = sb = sc = s;
      }
      const double ax = view.f * a.x() / a.z() + view.cx, ay = view.f * a.y() / a.z() + view.cy;
      const double bx = view.f * b.x() / b.z() + view.cx, by = view.f * b.y() / b.z() + view.cy;
      const double cx = view.f * c.x() / c.z() + view.cx, cy = view.f * c.y() / c.z() + view.cy;
      const double area = (bx - ax) * (cy - ay) - (by - ay) * (cx - ax);
      if (std::abs(area) < 1e-12) continue;
      const int x0 = std::max(0, int(std::floor(std::min({ax, bx, cx}))));
      const int x1 = std::min(w - 1, int(std::ceil(std::max({ax, bx, cx}))));
      const int y0 = std::max(0, int(std::floor(std::min({ay, by, cy}))));
      const int y1 = std::min(h - 1, int(std::ceil(std::max({ay, by, cy}))));
      for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) {
          const double px = x + 0.5, py = y + 0.5;
          const double l0 = ((bx - px) * (cy - py) - (by - py) * (cx - px)) / area;
          const double l1 = ((cx - px) * (ay - py) - (cy - py) * (ax - px)) / area;
          const double l2 = 1.0 - l0 - l1;
          if (l0 < 0 || l1 < 0 || l2 < 0) continue;
          // 1/z is linear in screen space: perspective-correct depth.
          const float z = float(1.0 / (l0 / a.z() + l1 / b.z() + l2 / c.z()));
          float& d = depth[size_t(y) * w + x];
          if (z >= d) continue;
          d = z;
          const float s = float(l0 * sa + l1 * sb + l2 * sc);
          cv::Vec3b& px_out = image.at<cv::Vec3b>(y, x);
          px_out[0] = cv::saturate_cast<uint8_t>(255.0f * s * item.color.z());
          px_out[1] = cv::saturate_cast<uint8_t>(255.0f * s * item.color.y());
          px_out[2] = cv::saturate_cast<uint8_t>(255.0f * s * item.color.x());
        }
    }
  }
  return image;
}

RenderCamera framingCamera(const std::vector<RenderItem>& items, const Eigen::Vector3d& direction,
                           int width, int height) {
  Eigen::AlignedBox3d box;
  for (const RenderItem& item : items)
    if (item.mesh)
      for (const Eigen::Vector3f& v : item.mesh->vertices) box.extend(v.cast<double>());
  RenderCamera c;
  c.width = width;
  c.height = height;
  const Eigen::Vector3d centre = box.isEmpty() ? Eigen::Vector3d(Eigen::Vector3d::Zero()) : Eigen::Vector3d(box.center());
  const double radius = box.isEmpty() ? 0.1 : std::max(0.5 * box.diagonal().norm(), 0.01);
  const double fov = c.vertical_fov_deg * M_PI / 180.0 * std::min(1.0, double(width) / height);
  const double distance = 1.15 * radius / std::sin(0.5 * fov);
  const Eigen::Vector3d d = direction.norm() > 0 ? direction.normalized() : Eigen::Vector3d(0, 1, 0);
  c.target = centre;
  c.eye = centre - distance * d;
  c.up = std::abs(d.z()) > 0.99 ? Eigen::Vector3d(0, 1, 0) : Eigen::Vector3d(0, 0, 1);
  return c;
}

}  // namespace cvephands
