#include "body_tracking/silhouette_mask.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include <opencv2/imgproc.hpp>

namespace body_tracking {

using Eigen::Matrix3d;
using Eigen::Matrix4d;
using Eigen::Vector2d;
using Eigen::Vector3d;
using Eigen::Vector4d;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kBoxPadPx = 2.0;
// Boundary samples per edge of the undistorted box when mapping it through the distortion:
// distorted edges bow (barrel), so the corners alone can miss the extremes.
constexpr int kEdgeSamples = 8;

// A symmetric 3x3 form evaluated at (x, y, 1).
struct Form3 {
  double xx, xy2, yy, x2, y2, c;  // xx x^2 + xy2 x y + yy y^2 + x2 x + y2 y + c
  explicit Form3(const Matrix3d& M)
      : xx(M(0, 0)), xy2(2 * M(0, 1)), yy(M(1, 1)), x2(2 * M(0, 2)), y2(2 * M(1, 2)),
        c(M(2, 2)) {}
  double operator()(double x, double y) const {
    return x * (xx * x + xy2 * y + x2) + y * (yy * y + y2) + c;
  }
};

// The part in the camera frame, reduced to what the per-pixel test needs for the ray
// (x, y, 1) l: quadric a l^2 + 2 h l + k with a = A(x, y), h = b.(x, y, 1); planes o + s l;
// C the image conic in normalised coordinates.
struct CameraPart {
  Form3 A, C;
  Vector3d b;
  double k;
  int num_planes;
  Vector3d plane_dir[2];
  double plane_offset[2];
  bool inside;  // camera inside the untruncated quadric (k <= 0)

  CameraPart(const TruncatedQuadric& part, const Matrix4d& world_T_camera)
      : A(Matrix3d::Zero()), C(Matrix3d::Zero()) {
    const Matrix4d Qc = world_T_camera.transpose() * part.Q * world_T_camera;
    const Matrix3d Am = Qc.topLeftCorner<3, 3>();
    b = Qc.topRightCorner<3, 1>();
    k = Qc(3, 3);
    A = Form3(Am);
    C = Form3(b * b.transpose() - k * Am);
    inside = k <= 0;
    num_planes = part.num_planes;
    for (int i = 0; i < num_planes; ++i) {
      const Vector4d p = world_T_camera.transpose() * part.planes[i];
      plane_dir[i] = p.head<3>();
      plane_offset[i] = p[3];
    }
  }

  bool hit(double x, double y) const {
    // The conic: rays outside it miss the quadric. With the camera inside the quadric C is
    // positive semidefinite and every ray meets it; skipping the test there keeps the rays
    // along a cylinder's axis (where d^T C d is 0 up to rounding) from being lost.
    double disc = C(x, y);
    if (disc < 0) {
      if (!inside) return false;
      disc = 0;
    }
    // Root interval of a l^2 + 2 h l + k <= 0 in the cancellation-free form l = t / a, k / t.
    // a >= 0 for cylinders and ellipsoids; a = 0 (ray parallel to a cylinder's axis) leaves
    // the linear inequality, whose half line t / a = +-inf gives.
    const double a = std::max(0.0, A(x, y));
    const double h = b.x() * x + b.y() * y + b.z();
    const double t = -(h + std::copysign(std::sqrt(disc), h));
    double lo = 0.0, hi = kInf;  // l > 0: in front of the camera
    if (t != 0.0) {
      const double r1 = a > 0 ? t / a : (t > 0 ? kInf : -kInf);
      const double r2 = k / t;
      lo = std::max(lo, std::min(r1, r2));
      hi = std::min(hi, std::max(r1, r2));
    } else if (!(a == 0.0 && k <= 0)) {
      // h = 0 and a k = 0: either the camera on the surface (a single point) or a ray
      // parallel to a cylinder's axis outside it. Inside it, every l satisfies the quadric.
      return false;
    }
    for (int i = 0; i < num_planes; ++i) {
      const double s = plane_dir[i].x() * x + plane_dir[i].y() * y + plane_dir[i].z();
      const double o = plane_offset[i];
      if (s > 0)
        lo = std::max(lo, -o / s);
      else if (s < 0)
        hi = std::min(hi, -o / s);
      else if (o < 0)
        return false;
    }
    return lo <= hi && hi > 0;
  }
};

void prepareMask(const tabletop_capture::CameraModel& cam, bool clear, cv::Mat* mask) {
  if (mask->rows != cam.height || mask->cols != cam.width || mask->type() != CV_8UC1)
    *mask = cv::Mat::zeros(cam.height, cam.width, CV_8UC1);
  else if (clear)
    mask->setTo(0);
}

}  // namespace

SilhouetteProjector::SilhouetteProjector(const tabletop_capture::CameraModel& camera)
    : camera_(camera), camera_T_world_(camera.cameraTWorld()) {
  rays_.resize(2 * static_cast<size_t>(camera_.width) * camera_.height);
  float* r = rays_.data();
  for (int v = 0; v < camera_.height; ++v)
    for (int u = 0; u < camera_.width; ++u) {
      const Vector2d xn =
          camera_.undistort(Vector2d((u - camera_.cx) / camera_.fx, (v - camera_.cy) / camera_.fy));
      *r++ = static_cast<float>(xn.x());
      *r++ = static_cast<float>(xn.y());
    }
}

cv::Rect SilhouetteProjector::projectedBox(const TruncatedQuadric& part) const {
  const cv::Rect image(0, 0, camera_.width, camera_.height);
  // The box's pinhole projection is the hull of its corners' (when all are in front).
  double x0 = kInf, y0 = kInf, x1 = -kInf, y1 = -kInf;
  int in_front = 0;
  for (int i = 0; i < 8; ++i) {
    const Vector3d p =
        camera_T_world_ * part.bounds.corner(static_cast<Eigen::AlignedBox3d::CornerType>(i));
    if (!(p.z() > 1e-9)) continue;
    ++in_front;
    x0 = std::min(x0, p.x() / p.z());
    x1 = std::max(x1, p.x() / p.z());
    y0 = std::min(y0, p.y() / p.z());
    y1 = std::max(y1, p.y() / p.z());
  }
  if (in_front == 0) return cv::Rect();  // nothing of the part has l > 0
  if (in_front < 8) return image;        // straddles the camera plane: no finite projection
  // Distortion maps the undistorted rectangle's boundary onto its image's boundary.
  double u0 = kInf, v0 = kInf, u1 = -kInf, v1 = -kInf;
  const int n = camera_.hasDistortion() ? kEdgeSamples : 1;
  for (int e = 0; e < 4; ++e)
    for (int j = 0; j < n; ++j) {
      const double s = static_cast<double>(j) / n;
      const Vector2d xn = e == 0 ? Vector2d(x0 + s * (x1 - x0), y0)
                          : e == 1 ? Vector2d(x1, y0 + s * (y1 - y0))
                          : e == 2 ? Vector2d(x1 - s * (x1 - x0), y1)
                                   : Vector2d(x0, y1 - s * (y1 - y0));
      const Vector2d xd = camera_.distort(xn);
      const double u = camera_.fx * xd.x() + camera_.cx, v = camera_.fy * xd.y() + camera_.cy;
      u0 = std::min(u0, u);
      u1 = std::max(u1, u);
      v0 = std::min(v0, v);
      v1 = std::max(v1, v);
    }
  // Clamp before converting: a box grazing the camera plane projects far out.
  const auto clampPx = [](double p, int size) {
    return static_cast<int>(std::clamp(p, -1.0, static_cast<double>(size)));
  };
  const int c0 = clampPx(std::floor(u0 - kBoxPadPx), camera_.width);
  const int r0 = clampPx(std::floor(v0 - kBoxPadPx), camera_.height);
  const int c1 = clampPx(std::ceil(u1 + kBoxPadPx), camera_.width);
  const int r1 = clampPx(std::ceil(v1 + kBoxPadPx), camera_.height);
  return cv::Rect(c0, r0, c1 - c0 + 1, r1 - r0 + 1) & image;
}

void SilhouetteProjector::drawInBox(const TruncatedQuadric& part, const cv::Rect& box,
                                    cv::Mat* mask) const {
  if (box.empty()) return;
  const CameraPart q(part, camera_.world_T_camera.matrix());
  for (int v = box.y; v < box.y + box.height; ++v) {
    const float* ray = rays_.data() + 2 * (static_cast<size_t>(v) * camera_.width + box.x);
    uint8_t* out = mask->ptr<uint8_t>(v) + box.x;
    for (int u = 0; u < box.width; ++u, ray += 2)
      if (q.hit(ray[0], ray[1])) out[u] = 255;
  }
}

void SilhouetteProjector::drawPart(const TruncatedQuadric& part, cv::Mat* mask) const {
  prepareMask(camera_, false, mask);
  drawInBox(part, projectedBox(part), mask);
}

void SilhouetteProjector::draw(const BodyParts& parts, double margin_px, cv::Mat* mask) const {
  prepareMask(camera_, true, mask);
  cv::Rect drawn;
  for (const TruncatedQuadric& part : parts) {
    const cv::Rect box = projectedBox(part);
    drawInBox(part, box, mask);
    if (!box.empty()) drawn = drawn.empty() ? box : (drawn | box);
  }
  const int radius = static_cast<int>(std::floor(margin_px + 1e-9));
  if (radius < 1 || drawn.empty()) return;
  // A disc of radius margin_px exactly (getStructuringElement's ellipse is coarser), applied
  // only where something was drawn: the rest of the mask is zero and stays so.
  cv::Mat kernel(2 * radius + 1, 2 * radius + 1, CV_8UC1);
  for (int i = -radius; i <= radius; ++i)
    for (int j = -radius; j <= radius; ++j)
      kernel.at<uint8_t>(i + radius, j + radius) = i * i + j * j <= margin_px * margin_px + 1e-9;
  const cv::Rect roi =
      cv::Rect(drawn.x - radius, drawn.y - radius, drawn.width + 2 * radius,
               drawn.height + 2 * radius) &
      cv::Rect(0, 0, camera_.width, camera_.height);
  cv::Mat sub = (*mask)(roi);
  cv::dilate(sub, sub, kernel);
}

}  // namespace body_tracking
