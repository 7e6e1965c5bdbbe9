// Tests of CameraModel (pinhole + plumb_bob) against OpenCV 4 (cv::projectPoints,
// cv::undistortPoints) and of the default simulated rig's geometry.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <string>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

#include "tabletop_capture/camera_model.h"
#include "tabletop_capture/default_rig.h"

using namespace tabletop_capture;

namespace {

cv::Matx33d cvK(const CameraModel& cam) {
  return cv::Matx33d(cam.fx, 0, cam.cx, 0, cam.fy, cam.cy, 0, 0, 1);
}

cv::Mat cvD(const CameraModel& cam) {
  cv::Mat D(1, 5, CV_64F);
  for (int k = 0; k < 5; ++k) D.at<double>(0, k) = cam.distortion[k];
  return D;
}

// cv::undistortPoints with enough iterations to converge (the default does only 5).
const cv::TermCriteria kUndistortCriteria(cv::TermCriteria::COUNT, 1000, 0.0);

// OpenCV projection of world points with rvec/tvec from camera_T_world.
std::vector<Eigen::Vector2d> cvProject(const CameraModel& cam,
                                       const std::vector<Eigen::Vector3d>& world) {
  const Eigen::Isometry3d cTw = cam.cameraTWorld();
  cv::Matx33d R;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) R(r, c) = cTw.linear()(r, c);
  cv::Vec3d rvec;
  cv::Rodrigues(R, rvec);
  const cv::Vec3d tvec(cTw.translation().x(), cTw.translation().y(), cTw.translation().z());
  std::vector<cv::Point3d> obj;
  for (const auto& p : world) obj.emplace_back(p.x(), p.y(), p.z());
  std::vector<cv::Point2d> img;
  cv::projectPoints(obj, rvec, tvec, cvK(cam), cvD(cam), img);
  std::vector<Eigen::Vector2d> out;
  for (const auto& q : img) out.emplace_back(q.x, q.y);
  return out;
}

// Pixel grid over the whole image area [0,w] x [0,h] (corners included).
std::vector<cv::Point2d> pixelGrid(const CameraModel& cam, int nx = 41, int ny = 31) {
  std::vector<cv::Point2d> px;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i)
      px.emplace_back(cam.width * double(i) / (nx - 1), cam.height * double(j) / (ny - 1));
  return px;
}

// OpenCV's undistortion of pixels to normalised coordinates.
std::vector<Eigen::Vector2d> cvUndistort(const CameraModel& cam,
                                         const std::vector<cv::Point2d>& px) {
  std::vector<cv::Point2d> und;
  cv::undistortPoints(px, und, cvK(cam), cvD(cam), cv::noArray(), cv::noArray(),
                      kUndistortCriteria);
  std::vector<Eigen::Vector2d> out;
  for (const auto& q : und) out.emplace_back(q.x, q.y);
  return out;
}

struct Sample {
  Eigen::Vector2d pixel;   // the pixel the point was generated from
  Eigen::Vector3d world;   // a 3-D point on that pixel's ray at some depth
};

// 3-D points whose images cover the whole image incl. its corners, at depths 0.2 .. 3.2 m.
// Generated through OpenCV's undistortion (independent of the code under test).
std::vector<Sample> coveringSamples(const CameraModel& cam) {
  const auto px = pixelGrid(cam);
  const auto xn = cvUndistort(cam, px);
  std::vector<Sample> s;
  for (size_t i = 0; i < px.size(); ++i) {
    const double z = 0.2 + 3.0 * double((i * 7919) % 101) / 100.0;
    const Eigen::Vector3d pc(xn[i].x() * z, xn[i].y() * z, z);
    s.push_back({Eigen::Vector2d(px[i].x, px[i].y), cam.world_T_camera * pc});
  }
  return s;
}

// A camera looking at the workspace with the given plumb_bob coefficients.
CameraModel strongCamera(const std::array<double, 5>& d, int index) {
  CameraModel cam = makeDefaultRig().cameras.at(index % 8);
  cam.name = "strong" + std::to_string(index);
  cam.distortion = d;
  return cam;
}

// Cameras for the OpenCV comparisons: every default-rig camera plus strong distortions.
// (k1 = -0.3 alone folds over before the image corners at fx ~ 232 px on 320x240, i.e. the
// corners are images of no point; with k2 = 0.1 the model is monotonic there.)
std::vector<CameraModel> comparisonCameras() {
  std::vector<CameraModel> cams = makeDefaultRig().cameras;
  const std::array<double, 5> strong[] = {
      {{-0.3, 0.1, 0.0, 0.0, 0.0}},          // strong barrel
      {{0.3, 0.0, 0.0, 0.0, 0.0}},           // strong pincushion
      {{0.3, -0.05, 0.0, 0.0, 0.01}},        // pincushion + k3
      {{-0.2, 0.05, 0.0, 0.0, 0.02}},        // barrel + k3
      {{-0.1, 0.0, 0.01, -0.01, 0.0}},       // tangential
      {{0.0, 0.0, -0.008, 0.012, 0.0}},      // tangential only
      {{-0.25, 0.08, 0.006, -0.004, -0.01}}, // everything
  };
  int i = 0;
  for (const auto& d : strong) cams.push_back(strongCamera(d, i++));
  return cams;
}

std::string camDesc(const CameraModel& c) {
  std::ostringstream s;
  s << c.name << " D=[" << c.distortion[0] << "," << c.distortion[1] << "," << c.distortion[2]
    << "," << c.distortion[3] << "," << c.distortion[4] << "]";
  return s.str();
}

}  // namespace

// Kept from the original file.
TEST(CameraModel, DefaultRigRoundTrip) {
  const RigDescription rig = makeDefaultRig();
  ASSERT_EQ(rig.cameras.size(), 8u);
  for (const auto& cam : rig.cameras) {
    const Eigen::Vector3d p(0.1, -0.1, 0.3);
    Eigen::Vector2d px;
    ASSERT_TRUE(cam.projectWorld(p, &px));
    const Eigen::Vector3d ray = cam.rayWorld(px);
    const Eigen::Vector3d expected = (p - cam.center()).normalized();
    EXPECT_LT((ray - expected).norm(), 1e-9) << cam.name;
  }
}

TEST(CameraModel, ProjectionMatchesOpenCVOverWholeImage) {
  double max_diff = 0;
  for (const auto& cam : comparisonCameras()) {
    const auto samples = coveringSamples(cam);
    std::vector<Eigen::Vector3d> world;
    for (const auto& s : samples) world.push_back(s.world);
    const auto cv_px = cvProject(cam, world);
    double cam_max = 0;
    Eigen::Vector2d lo(1e9, 1e9), hi(-1e9, -1e9);
    for (size_t i = 0; i < samples.size(); ++i) {
      // The samples really cover the image: OpenCV maps each back onto its source pixel.
      ASSERT_LT((cv_px[i] - samples[i].pixel).norm(), 1e-6)
          << camDesc(cam) << " sample generation failed at pixel " << samples[i].pixel.transpose();
      Eigen::Vector2d px(-1, -1);
      ASSERT_TRUE(cam.projectWorld(samples[i].world, &px)) << camDesc(cam);
      const double d = (px - cv_px[i]).norm();
      cam_max = std::max(cam_max, d);
      EXPECT_LT(d, 1e-3) << camDesc(cam) << " at pixel " << samples[i].pixel.transpose()
                         << ": ours " << px.transpose() << " opencv " << cv_px[i].transpose();
      lo = lo.cwiseMin(px);
      hi = hi.cwiseMax(px);
    }
    // Corners of the image reached.
    EXPECT_NEAR(lo.x(), 0.0, 1e-3) << camDesc(cam);
    EXPECT_NEAR(lo.y(), 0.0, 1e-3) << camDesc(cam);
    EXPECT_NEAR(hi.x(), cam.width, 1e-3) << camDesc(cam);
    EXPECT_NEAR(hi.y(), cam.height, 1e-3) << camDesc(cam);
    max_diff = std::max(max_diff, cam_max);
  }
  std::cout << "[ INFO     ] max |projectWorld - cv::projectPoints| = " << std::scientific
            << max_diff << " px" << std::endl;
  RecordProperty("max_projection_diff_px", std::to_string(max_diff));
}

TEST(CameraModel, ProjectCameraMatchesOpenCVForRandomPoints) {
  // Points anywhere in front of the camera (also far outside the image).
  cv::RNG rng(12345);
  for (const auto& cam : comparisonCameras()) {
    std::vector<Eigen::Vector3d> world;
    for (int i = 0; i < 500; ++i) {
      const double z = rng.uniform(0.05, 5.0);
      const Eigen::Vector3d pc(rng.uniform(-0.8, 0.8) * z, rng.uniform(-0.6, 0.6) * z, z);
      world.push_back(cam.world_T_camera * pc);
    }
    const auto cv_px = cvProject(cam, world);
    for (size_t i = 0; i < world.size(); ++i) {
      Eigen::Vector2d px;
      ASSERT_TRUE(cam.projectWorld(world[i], &px));
      EXPECT_LT((px - cv_px[i]).norm(), 1e-6 * std::max(1.0, cv_px[i].norm())) << camDesc(cam);
    }
  }
}

TEST(CameraModel, UndistortMatchesOpenCV) {
  double max_diff = 0;
  for (const auto& cam : comparisonCameras()) {
    const auto px = pixelGrid(cam);
    const auto cv_xn = cvUndistort(cam, px);
    for (size_t i = 0; i < px.size(); ++i) {
      const Eigen::Vector2d xd((px[i].x - cam.cx) / cam.fx, (px[i].y - cam.cy) / cam.fy);
      const Eigen::Vector2d xn = cam.undistort(xd);
      const double d = (xn - cv_xn[i]).norm();
      max_diff = std::max(max_diff, d);
      EXPECT_LT(d, 1e-6) << camDesc(cam) << " pixel (" << px[i].x << "," << px[i].y << ")";
      // And it inverts distort().
      EXPECT_LT((cam.distort(xn) - xd).norm(), 1e-9) << camDesc(cam);
    }
  }
  std::cout << "[ INFO     ] max |undistort - cv::undistortPoints| = " << std::scientific
            << max_diff << " (normalised)" << std::endl;
}

TEST(CameraModel, DistortUndistortRoundTrip) {
  for (const auto& cam : comparisonCameras()) {
    for (double x = -0.6; x <= 0.6001; x += 0.05)
      for (double y = -0.45; y <= 0.4501; y += 0.05) {
        const Eigen::Vector2d xn(x, y);
        EXPECT_LT((cam.undistort(cam.distort(xn)) - xn).norm(), 1e-9) << camDesc(cam);
      }
  }
}

TEST(CameraModel, RayIsParallelToPointDirection) {
  for (const auto& cam : comparisonCameras()) {
    for (const auto& s : coveringSamples(cam)) {
      Eigen::Vector2d px;
      ASSERT_TRUE(cam.projectWorld(s.world, &px));
      const Eigen::Vector3d ray = cam.rayWorld(px);
      const Eigen::Vector3d dir = (s.world - cam.center()).normalized();
      EXPECT_NEAR(ray.norm(), 1.0, 1e-12);
      EXPECT_LT(ray.cross(dir).norm(), 1e-9) << camDesc(cam) << " pixel " << px.transpose();
      EXPECT_GT(ray.dot(dir), 0.0) << camDesc(cam);
      // rayCamera points forward (+z of the optical frame).
      EXPECT_GT(cam.rayCamera(px).z(), 0.0);
    }
  }
}

TEST(CameraModel, PointsBehindCameraAreRejected) {
  for (const auto& cam : comparisonCameras()) {
    const Eigen::Vector2d sentinel(-12345.0, 6789.0);
    for (const Eigen::Vector3d& pc :
         {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(0.1, 0.2, 0), Eigen::Vector3d(0, 0, -1),
          Eigen::Vector3d(0.3, -0.2, -0.5), Eigen::Vector3d(0, 0, -1e-12),
          Eigen::Vector3d(0, 0, 1e-10), Eigen::Vector3d(0, 0, 1e-9)}) {
      Eigen::Vector2d px = sentinel;
      EXPECT_FALSE(cam.projectCamera(pc, &px)) << camDesc(cam) << " " << pc.transpose();
      EXPECT_EQ(px, sentinel);
      if (pc.z() == 1e-9) continue;  // the exact boundary does not survive a world round trip
      px = sentinel;
      EXPECT_FALSE(cam.projectWorld(cam.world_T_camera * pc, &px)) << pc.transpose();
      EXPECT_EQ(px, sentinel);
    }
    // NaN depth is not "in front" either.
    Eigen::Vector2d px = sentinel;
    EXPECT_FALSE(cam.projectCamera(Eigen::Vector3d(0, 0, std::nan("")), &px));
    EXPECT_EQ(px, sentinel);
    // Just in front is accepted.
    EXPECT_TRUE(cam.projectCamera(Eigen::Vector3d(0, 0, 1e-6), &px));
    EXPECT_NEAR(px.x(), cam.cx, 1e-9);
    EXPECT_NEAR(px.y(), cam.cy, 1e-9);
    // A world point behind the camera (mirror of the workspace centre) is rejected.
    const Eigen::Vector3d behind = 2.0 * cam.center() - Eigen::Vector3d(0, 0, 0.375);
    px = sentinel;
    EXPECT_FALSE(cam.projectWorld(behind, &px)) << camDesc(cam);
    EXPECT_EQ(px, sentinel);
  }
}

TEST(CameraModel, NoDistortion) {
  CameraModel cam;
  cam.name = "pinhole";
  cam.width = 640;
  cam.height = 480;
  cam.fx = 500;
  cam.fy = 510;
  cam.cx = 319.5;
  cam.cy = 241.25;
  cam.world_T_camera = lookAt(Eigen::Vector3d(1.0, -0.7, 1.2), Eigen::Vector3d(0, 0, 0.3));
  EXPECT_FALSE(cam.hasDistortion());
  const Eigen::Vector2d xn(0.3, -0.2);
  EXPECT_EQ(cam.distort(xn), xn);
  EXPECT_EQ(cam.undistort(xn), xn);

  const Eigen::Vector3d pc(0.2, -0.1, 0.8);
  Eigen::Vector2d px;
  ASSERT_TRUE(cam.projectCamera(pc, &px));
  EXPECT_NEAR(px.x(), 500 * 0.25 + 319.5, 1e-12);
  EXPECT_NEAR(px.y(), 510 * -0.125 + 241.25, 1e-12);
  EXPECT_NEAR(cam.rayCamera(px).x(), pc.normalized().x(), 1e-12);
  EXPECT_NEAR(cam.rayCamera(px).y(), pc.normalized().y(), 1e-12);

  const auto samples = coveringSamples(cam);
  std::vector<Eigen::Vector3d> world;
  for (const auto& s : samples) world.push_back(s.world);
  const auto cv_px = cvProject(cam, world);
  for (size_t i = 0; i < samples.size(); ++i) {
    ASSERT_TRUE(cam.projectWorld(samples[i].world, &px));
    EXPECT_LT((px - cv_px[i]).norm(), 1e-9);
    EXPECT_LT((px - samples[i].pixel).norm(), 1e-9);
  }

  // Any single non-zero coefficient counts as distortion.
  for (int k = 0; k < 5; ++k) {
    CameraModel c = cam;
    c.distortion[k] = 1e-6;
    EXPECT_TRUE(c.hasDistortion()) << k;
  }
}

TEST(CameraModel, PoseConventions) {
  const CameraModel cam = makeDefaultRig().cameras[3];
  EXPECT_TRUE((cam.cameraTWorld() * cam.world_T_camera).matrix().isIdentity(1e-12));
  // The optical axis (+z camera) from the centre projects to the principal point.
  const Eigen::Vector3d on_axis = cam.world_T_camera * Eigen::Vector3d(0, 0, 2.0);
  Eigen::Vector2d px;
  ASSERT_TRUE(cam.projectWorld(on_axis, &px));
  EXPECT_NEAR(px.x(), cam.cx, 1e-9);
  EXPECT_NEAR(px.y(), cam.cy, 1e-9);
  // REP 103: camera +x is image right, +y is image down.
  ASSERT_TRUE(cam.projectCamera(Eigen::Vector3d(0.1, 0, 1), &px));
  EXPECT_GT(px.x(), cam.cx);
  ASSERT_TRUE(cam.projectCamera(Eigen::Vector3d(0, 0.1, 1), &px));
  EXPECT_GT(px.y(), cam.cy);
}

TEST(DefaultRig, EveryCameraSeesWorkspaceCentreAndBoxCorners) {
  const RigDescription rig = makeDefaultRig();
  ASSERT_EQ(rig.cameras.size(), 8u);
  const Eigen::Vector3d lo(-0.5, -0.5, 0.0), hi(0.5, 0.5, 0.75);
  std::vector<Eigen::Vector3d> pts = {Eigen::Vector3d(0, 0, 0.375)};
  for (int k = 0; k < 8; ++k)
    pts.emplace_back((k & 1) ? hi.x() : lo.x(), (k & 2) ? hi.y() : lo.y(),
                     (k & 4) ? hi.z() : lo.z());
  std::ostringstream report;
  report << std::fixed << std::setprecision(2);
  double worst_margin = 1e9;
  for (const auto& cam : rig.cameras) {
    EXPECT_EQ(cam.width, 320);
    EXPECT_EQ(cam.height, 240);
    EXPECT_TRUE(cam.hasDistortion()) << cam.name;
    report << cam.name << ":";
    for (size_t k = 0; k < pts.size(); ++k) {
      Eigen::Vector2d px(-1, -1);
      const bool front = cam.projectWorld(pts[k], &px);
      EXPECT_TRUE(front) << cam.name << " point " << pts[k].transpose() << " behind camera";
      EXPECT_TRUE(cam.inImage(px)) << cam.name << " point " << pts[k].transpose()
                                   << " projects to " << px.transpose() << " outside "
                                   << cam.width << "x" << cam.height;
      const double margin = std::min({px.x(), px.y(), cam.width - px.x(), cam.height - px.y()});
      worst_margin = std::min(worst_margin, margin);
      report << " (" << px.x() << "," << px.y() << ")";
    }
    report << "\n";
  }
  std::cout << "[ INFO     ] workspace centre + box corners per camera (px):\n"
            << report.str() << "[ INFO     ] smallest margin to the image border: " << worst_margin
            << " px" << std::endl;
}

TEST(DefaultRig, Options) {
  for (int n = 1; n <= 16; ++n) {
    DefaultRigOptions o;
    o.num_cameras = n;
    const RigDescription rig = makeDefaultRig(o);
    ASSERT_EQ(rig.cameras.size(), size_t(n));
    for (const auto& c : rig.cameras) {
      const Eigen::Matrix3d R = c.world_T_camera.linear();
      EXPECT_TRUE((R.transpose() * R).isIdentity(1e-12)) << n << " " << c.name;
      EXPECT_NEAR(R.determinant(), 1.0, 1e-12);
    }
  }
  DefaultRigOptions o;
  o.distortion = false;
  for (const auto& c : makeDefaultRig(o).cameras) EXPECT_FALSE(c.hasDistortion());
  o.num_cameras = 0;
  EXPECT_THROW(makeDefaultRig(o), std::invalid_argument);
  o.num_cameras = 17;
  EXPECT_THROW(makeDefaultRig(o), std::invalid_argument);
}
