// Analytic part silhouettes against silhouettes rendered from dense samples of the parts'
// surfaces, on the default simulated rig (with lens distortion), plus the degenerate views.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <opencv2/imgproc.hpp>

#include "body_tracking/body_parts.h"
#include "body_tracking/silhouette_mask.h"
#include "tabletop_capture/default_rig.h"

namespace body_tracking {
namespace {

using Eigen::Isometry3d;
using Eigen::Vector2d;
using Eigen::Vector3d;
using tabletop_capture::CameraModel;

BodyState seatedState() {
  BodyState s{};
  s[dof::TORSO_Y] = -0.48;
  s[dof::TORSO_Z] = -0.17;
  s[dof::SPINE_BEND] = 0.08;
  s[dof::L_SWING_1] = -0.9;
  s[dof::L_FLEX] = 0.9;
  s[dof::R_SWING_1] = -0.7;  // the right arm a little different, reaching further
  s[dof::R_SWING_2] = 0.2;
  s[dof::R_FLEX] = 1.1;
  return s;
}

const std::vector<CameraModel>& rigCameras() {
  static const std::vector<CameraModel> cams = tabletop_capture::makeDefaultRig().cameras;
  return cams;
}

// Calls f(p) for points covering the solid's surface (cylinders: side and both end caps) with
// spacing at most `step` (m).
template <typename F>
void forEachSurfacePoint(const TruncatedQuadric& q, double step, F f) {
  const double r = std::max(q.semi.x(), q.semi.z());
  const int n_theta = static_cast<int>(std::ceil(2 * M_PI * r / step)) + 1;
  if (q.shape == TruncatedQuadric::Shape::CYLINDER) {
    const int n_y = static_cast<int>(std::ceil(q.length / step)) + 1;
    for (int j = 0; j <= n_y; ++j)
      for (int i = 0; i < n_theta; ++i) {
        const double t = 2 * M_PI * i / n_theta;
        f(q.frame * Vector3d(q.semi.x() * std::cos(t), q.length * j / n_y, q.semi.z() * std::sin(t)));
      }
    const int n_rho = static_cast<int>(std::ceil(r / step)) + 1;
    for (double y : {0.0, q.length})
      for (int k = 0; k <= n_rho; ++k) {
        const double rho = static_cast<double>(k) / n_rho;
        const int n = std::max(1, static_cast<int>(std::ceil(2 * M_PI * rho * r / step)) + 1);
        for (int i = 0; i < n; ++i) {
          const double t = 2 * M_PI * i / n;
          f(q.frame * Vector3d(rho * q.semi.x() * std::cos(t), y, rho * q.semi.z() * std::sin(t)));
        }
      }
    return;
  }
  const double rmax = q.semi.maxCoeff();
  const int n_phi = static_cast<int>(std::ceil(M_PI * rmax / step)) + 1;
  for (int j = 0; j <= n_phi; ++j) {
    const double phi = -M_PI / 2 + M_PI * j / n_phi;
    const int n = std::max(1, static_cast<int>(std::ceil(2 * M_PI * rmax * std::cos(phi) / step)) + 1);
    for (int i = 0; i < n; ++i) {
      const double t = 2 * M_PI * i / n;
      const Vector3d u(std::cos(phi) * std::cos(t), std::cos(phi) * std::sin(t), std::sin(phi));
      f(q.frame * Vector3d(q.semi.cwiseProduct(u)));
    }
  }
}

// The reference silhouette from projected surface samples. The analytic mask tests pixel
// centres, so a pixel here counts as hit only when a projected sample falls within 1/(2N) px of
// its centre (N = 11) rather than anywhere in the pixel, which would grow the silhouette by
// ~half a pixel all round (as it is, it grows by <= 0.045 px). The samples are spaced at 1/16
// of the pixel footprint at the part's nearest depth (<= 0.0625 px in the image, so that every
// 1/11 px target cell, in any orientation of the sampling grid, gets one), and enclosed
// holes are then filled (flood fill from the border; projected convex solids have none) as a
// safety net for any cell the samples miss. Samples nearer than min_depth are skipped (used
// where a part straddles the camera plane; they must project outside the image).
cv::Mat sampledSilhouette(const TruncatedQuadric& part, const CameraModel& cam,
                          double min_depth = 0.0) {
  const Isometry3d camera_T_world = cam.cameraTWorld();
  double near = 1e9;
  for (int i = 0; i < 8; ++i)
    near = std::min(near, (camera_T_world *
                           part.bounds.corner(static_cast<Eigen::AlignedBox3d::CornerType>(i))).z());
  near = std::max(near, min_depth);
  const double step = near / std::max(cam.fx, cam.fy) / 16.0;
  constexpr double kHalfCell = 0.5 / 11.0;
  cv::Mat mask = cv::Mat::zeros(cam.height + 2, cam.width + 2, CV_8UC1);  // 1 px border
  forEachSurfacePoint(part, step, [&](const Vector3d& p) {
    if ((camera_T_world * p).z() < min_depth) return;
    Vector2d px;
    if (!cam.projectWorld(p, &px)) return;
    const double u = std::round(px.x()), v = std::round(px.y());
    if (std::abs(px.x() - u) > kHalfCell || std::abs(px.y() - v) > kHalfCell) return;
    if (u < 0 || v < 0 || u >= cam.width || v >= cam.height) return;
    mask.at<uint8_t>(static_cast<int>(v) + 1, static_cast<int>(u) + 1) = 255;
  });
  cv::Mat outside = mask.clone();
  cv::floodFill(outside, cv::Point(0, 0), 128);  // 4-connected: an 8-connected ring stops it
  mask.setTo(255, outside == 0);
  return mask(cv::Rect(1, 1, cam.width, cam.height)).clone();
}

// The least algebraic value within the clipping planes along pixel (u, v)'s ray, by marching
// it in 0.1 mm steps through the part's box: an independent check of a pixel's answer.
double marchedMinimum(const TruncatedQuadric& part, const CameraModel& cam, int u, int v) {
  const Vector3d c = cam.center(), d = cam.rayWorld(Vector2d(u, v));
  double l0 = 0, l1 = 1e9;
  for (int k = 0; k < 3; ++k) {
    if (std::abs(d[k]) < 1e-12) continue;
    const double a = (part.bounds.min()[k] - c[k]) / d[k], b = (part.bounds.max()[k] - c[k]) / d[k];
    l0 = std::max(l0, std::min(a, b));
    l1 = std::min(l1, std::max(a, b));
  }
  double best = 1e9;
  for (double l = l0; l <= l1; l += 1e-4)
    if (part.withinPlanes(c + l * d)) best = std::min(best, part.algebraic(c + l * d));
  return best;
}

double iou(const cv::Mat& a, const cv::Mat& b) {
  const int inter = cv::countNonZero(a & b), uni = cv::countNonZero(a | b);
  return uni == 0 ? 1.0 : static_cast<double>(inter) / uni;
}

cv::Mat discKernel(double radius) {
  const int r = static_cast<int>(std::floor(radius));
  cv::Mat k(2 * r + 1, 2 * r + 1, CV_8UC1);
  for (int i = -r; i <= r; ++i)
    for (int j = -r; j <= r; ++j) k.at<uint8_t>(i + r, j + r) = i * i + j * j <= radius * radius;
  return k;
}

// A distortion-free camera at `pose` with integer principal point, so that the centre pixel's
// ray is exactly the optical axis.
CameraModel plainCamera(const Isometry3d& pose) {
  CameraModel cam;
  cam.width = 160;
  cam.height = 120;
  cam.fx = cam.fy = 150;
  cam.cx = 80;
  cam.cy = 60;
  cam.world_T_camera = pose;
  return cam;
}

TEST(SilhouetteMask, SeatedPartsMatchSampledSurfaces) {
  const BodyParts parts = buildParts(BodyProfile(), seatedState());
  double worst = 1.0;
  int compared = 0, disagreements = 0, analytic_wrong = 0;
  for (const CameraModel& cam : rigCameras()) {
    ASSERT_TRUE(cam.hasDistortion());
    const SilhouetteProjector projector(cam);
    std::printf("%s IoU:", cam.name.c_str());
    for (int i = 0; i < kNumParts; ++i) {
      cv::Mat drawn;
      projector.drawPart(parts[i], &drawn);
      const cv::Mat reference = sampledSilhouette(parts[i], cam);
      const int area = cv::countNonZero(reference);
      if (area < 50) {
        std::printf(" %s skipped (%d px, too small for a meaningful IoU);", partName(Part(i)), area);
        continue;
      }
      const double value = iou(drawn, reference);
      std::printf(" %s %.4f (%d px)%s", partName(Part(i)), value, area,
                  i + 1 < kNumParts ? "," : "\n");
      EXPECT_GE(value, 0.95) << cam.name << " " << partName(Part(i));
      // Where the two disagree, march the ray: the analytic answer must be the right one (up
      // to rays grazing the surface within the march's resolution).
      for (int v = 0; v < cam.height; ++v)
        for (int u = 0; u < cam.width; ++u) {
          const bool hit = drawn.at<uint8_t>(v, u) != 0;
          if (hit == (reference.at<uint8_t>(v, u) != 0)) continue;
          ++disagreements;
          const double m = marchedMinimum(parts[i], cam, u, v);
          if (hit ? m > 1e-3 : m < -1e-3) {
            ++analytic_wrong;
            ADD_FAILURE() << cam.name << " " << partName(Part(i)) << " pixel (" << u << ", " << v
                          << ") drawn " << hit << ", marched minimum " << m;
          }
        }
      worst = std::min(worst, value);
      ++compared;
    }
  }
  std::printf("worst IoU over %d part views: %.4f; %d pixels disagree, the analytic mask is "
              "wrong on %d of them (marched rays)\n", compared, worst, disagreements, analytic_wrong);
  EXPECT_GE(compared, 3 * kNumParts);
}

// End-on, the near end cap hides the rest: the silhouette is the disc of pixels whose ray is
// within the cap's angular radius of the axis, the ray along the axis (a = 0) included.
TEST(SilhouetteMask, CylinderSeenEndOn) {
  // Exactly along the optical axis: a = 0 and h = 0 at the centre pixel, the camera inside the
  // untruncated cylinder (k < 0) 1 m before the near cap.
  {
    const CameraModel cam = plainCamera(Isometry3d::Identity());
    const Isometry3d frame(Eigen::AngleAxisd(M_PI / 2, Vector3d::UnitX()) *
                           Eigen::Translation3d(0, 1.0, 0));  // local y -> camera z
    const TruncatedQuadric cyl = TruncatedQuadric::cylinder(frame, 0.4, 0.1, 0.1);
    ASSERT_NEAR((cyl.frame * Vector3d(0, 0.4, 0)).z(), 1.4, 1e-12);
    cv::Mat drawn;
    SilhouetteProjector(cam).drawPart(cyl, &drawn);
    EXPECT_EQ(drawn.at<uint8_t>(60, 80), 255);
    int wrong = 0, inside = 0;
    for (int v = 0; v < cam.height; ++v)
      for (int u = 0; u < cam.width; ++u) {
        const double r = std::hypot(u - cam.cx, v - cam.cy) / cam.fx;  // tan of the ray angle
        if (std::abs(r - 0.1) < 1e-9) continue;                        // exactly on the rim
        inside += r < 0.1;
        wrong += (r < 0.1) != (drawn.at<uint8_t>(v, u) != 0);
      }
    std::printf("end-on on the optical axis: %d px in the cap's disc, %d wrong\n", inside, wrong);
    EXPECT_EQ(wrong, 0);
    // Turned away from the camera (it sits behind the cylinder): nothing.
    const Isometry3d flipped = Isometry3d(Eigen::AngleAxisd(M_PI, Vector3d::UnitY()));
    cv::Mat none;
    SilhouetteProjector(plainCamera(flipped)).drawPart(cyl, &none);
    EXPECT_EQ(cv::countNonZero(none), 0);
  }
  // A distorted rig camera, the axis along an off-centre pixel's ray.
  {
    const CameraModel& cam = rigCameras()[3];
    const Vector3d axis = cam.rayWorld(Vector2d(230, 60));
    Isometry3d frame = tabletop_capture::lookAt(cam.center() + 1.2 * axis, cam.center() + 2 * axis);
    frame.linear() = frame.linear() * Eigen::AngleAxisd(M_PI / 2, Vector3d::UnitX()).matrix();
    ASSERT_NEAR((frame.linear() * Vector3d::UnitY()).dot(axis), 1.0, 1e-12);
    const TruncatedQuadric cyl = TruncatedQuadric::cylinder(frame, 0.3, 0.06, 0.06);
    cv::Mat drawn;
    SilhouetteProjector(cam).drawPart(cyl, &drawn);
    EXPECT_EQ(drawn.at<uint8_t>(60, 230), 255);
    cv::Mat expected = cv::Mat::zeros(cam.height, cam.width, CV_8UC1);
    for (int v = 0; v < cam.height; ++v)
      for (int u = 0; u < cam.width; ++u)
        if (cam.rayWorld(Vector2d(u, v)).dot(axis) >= std::cos(std::atan(0.06 / 1.2)))
          expected.at<uint8_t>(v, u) = 255;
    const double value = iou(drawn, expected), sampled = iou(drawn, sampledSilhouette(cyl, cam));
    std::printf("end-on in %s: IoU %.4f against the cap's cone, %.4f against samples (%d px)\n",
                cam.name.c_str(), value, sampled, cv::countNonZero(expected));
    EXPECT_GE(value, 0.97);
    EXPECT_GE(sampled, 0.95);
  }
}

// Inside a solid every ray leaves it in front of the camera: the whole image is drawn. Inside
// the untruncated quadric but outside the slab, only the rays towards the solid draw.
TEST(SilhouetteMask, CameraInsideParts) {
  const CameraModel& cam = rigCameras()[1];
  const SilhouetteProjector projector(cam);
  const Isometry3d at_camera = cam.world_T_camera * Eigen::Translation3d(0.01, -0.02, 0.03);
  cv::Mat head;
  projector.drawPart(TruncatedQuadric::ellipsoid(at_camera, Vector3d(0.08, 0.10, 0.12)), &head);
  EXPECT_EQ(cv::countNonZero(head), cam.width * cam.height);
  // A cylinder across the camera, its axis through the camera centre.
  const Isometry3d across = at_camera * Eigen::Translation3d(0, -0.2, 0);
  cv::Mat arm;
  projector.drawPart(TruncatedQuadric::cylinder(across, 0.4, 0.05, 0.05), &arm);
  EXPECT_EQ(cv::countNonZero(arm), cam.width * cam.height);
  // Within the infinite cylinder, 0.1 m past its end cap and facing away from it: nothing.
  const Isometry3d behind = cam.world_T_camera *
                            Eigen::AngleAxisd(-M_PI / 2, Vector3d::UnitX()) *
                            Eigen::Translation3d(0, 0.1, 0);  // axis along camera -z, y 0.1..0.5
  cv::Mat back;
  projector.drawPart(TruncatedQuadric::cylinder(behind, 0.4, 0.05, 0.05), &back);
  EXPECT_EQ(cv::countNonZero(back), 0);
}

TEST(SilhouetteMask, MarginDilatesAndUnionIsOrOfParts) {
  const BodyParts parts = buildParts(BodyProfile(), seatedState());
  for (int c : {0, 4, 7}) {
    const CameraModel& cam = rigCameras()[c];
    const SilhouetteProjector projector(cam);
    cv::Mat plain, ored = cv::Mat::zeros(cam.height, cam.width, CV_8UC1), accumulated;
    projector.draw(parts, 0.0, &plain);
    for (const TruncatedQuadric& part : parts) {
      cv::Mat single;
      projector.drawPart(part, &single);
      ASSERT_EQ(single.size(), cv::Size(cam.width, cam.height));
      ored |= single;
      projector.drawPart(part, &accumulated);  // drawPart does not clear
    }
    EXPECT_EQ(cv::countNonZero(plain != ored), 0) << cam.name;
    EXPECT_EQ(cv::countNonZero(plain != accumulated), 0) << cam.name;

    std::vector<std::vector<cv::Point>> contours;
    cv::findContours(plain.clone(), contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_NONE);
    double perimeter = 0;
    for (const auto& contour : contours) perimeter += cv::arcLength(contour, true);
    const int base = cv::countNonZero(plain);
    for (double m : {1.0, 2.0, 3.5}) {
      cv::Mat dilated(cam.height, cam.width, CV_8UC1, cv::Scalar(255));  // draw() clears it
      projector.draw(parts, m, &dilated);
      cv::Mat expected;
      cv::dilate(plain, expected, discKernel(m));
      EXPECT_EQ(cv::countNonZero(dilated != expected), 0) << cam.name << " margin " << m;
      EXPECT_EQ(cv::countNonZero(plain & ~dilated), 0);
      // Steiner: a convex region grows by P m + pi m^2; the union's concavities grow less.
      const int added = cv::countNonZero(dilated) - base;
      std::printf("%s margin %.1f: +%d px (perimeter %.0f px x margin = %.0f)\n",
                  cam.name.c_str(), m, added, perimeter, perimeter * m);
      EXPECT_GE(added, 0.6 * perimeter * m);
      EXPECT_LE(added, perimeter * (m + 1.0) + M_PI * m * m * contours.size());
    }
    // A mask of the wrong size or type is reallocated.
    cv::Mat wrong(10, 10, CV_32FC1, cv::Scalar(1));
    projector.draw(parts, 0.0, &wrong);
    EXPECT_EQ(wrong.type(), CV_8UC1);
    EXPECT_EQ(cv::countNonZero(wrong != plain), 0);
  }
}

TEST(SilhouetteMask, BehindTheCameraDrawsNothing) {
  const CameraModel& cam = rigCameras()[2];
  const SilhouetteProjector projector(cam);
  // On the optical axis behind the camera, where a sign error would mirror it into view.
  const TruncatedQuadric head = TruncatedQuadric::ellipsoid(
      cam.world_T_camera * Eigen::Translation3d(0, 0, -0.6), Vector3d(0.08, 0.10, 0.12));
  cv::Mat mask;
  projector.drawPart(head, &mask);
  EXPECT_EQ(cv::countNonZero(mask), 0);
  EXPECT_TRUE(projector.projectedBox(head).empty());
  // Parallel to the optical axis, 0.35 m aside, from 1 m behind to 1.5 m in front: the box
  // straddles the camera plane, so the whole image is scanned; only the front part shows.
  const Isometry3d frame = cam.world_T_camera * Eigen::Translation3d(0.35, 0.05, -1.0) *
                           Eigen::AngleAxisd(M_PI / 2, Vector3d::UnitX());  // local y -> z
  const TruncatedQuadric arm = TruncatedQuadric::cylinder(frame, 2.5, 0.05, 0.05);
  ASSERT_EQ(projector.projectedBox(arm), cv::Rect(0, 0, cam.width, cam.height));
  cv::Mat front;
  projector.drawPart(arm, &front);
  // Samples nearer than 0.3 m are > 0.3 / 0.3 = 1 (normalised) aside: outside the image. The
  // cylinder is sampled in 0.1 m pieces (the union of their silhouettes is the whole's), each
  // at the spacing its own depth needs.
  cv::Mat reference = cv::Mat::zeros(cam.height, cam.width, CV_8UC1);
  for (double y = 0; y < arm.length - 1e-9; y += 0.1) {
    const TruncatedQuadric piece = TruncatedQuadric::cylinder(
        arm.frame * Eigen::Translation3d(0, y, 0), 0.1, arm.semi.x(), arm.semi.z());
    if ((cam.cameraTWorld() * piece.frame * Vector3d(0, 0.1, 0)).z() < 0.3) continue;
    reference |= sampledSilhouette(piece, cam, 0.3);
  }
  const double value = iou(front, reference);
  std::printf("straddling the camera plane: IoU %.4f (%d px)\n", value, cv::countNonZero(front));
  EXPECT_GE(value, 0.95);
  // The same cylinder moved wholly behind the camera.
  const TruncatedQuadric behind = TruncatedQuadric::cylinder(
      cam.world_T_camera * Eigen::Translation3d(0.35, 0.05, -3.0) *
          Eigen::AngleAxisd(M_PI / 2, Vector3d::UnitX()),
      2.5, 0.05, 0.05);
  cv::Mat none;
  projector.drawPart(behind, &none);
  EXPECT_EQ(cv::countNonZero(none), 0);
}

}  // namespace
}  // namespace body_tracking
