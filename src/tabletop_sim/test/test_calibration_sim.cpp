// Intrinsic calibration end to end on the simulated rig (issue 18): a checkerboard rendered
// through each camera's own distortion at random poses (tabletop_sim/calibration_target.h),
// the corners detected in the images, the camera calibrated from them, and the result checked
// against the rig's true camera: focal length within 0.5 %, principal point within 0.3 px,
// reprojection error below 0.3 px (thesis: < 0.5 px on real cameras). Also measures the corner
// detector's own error against the projected truth (the noise the synthetic-corner test of
// tabletop_capture assumes).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include <opencv2/imgcodecs.hpp>

#include "tabletop_capture/calibration/board_poses.h"
#include "tabletop_capture/calibration/intrinsic_calibration.h"
#include "tabletop_capture/default_rig.h"
#include "tabletop_sim/calibration_target.h"

namespace tabletop_sim {
namespace {

using tabletop_capture::CameraModel;
using tabletop_capture::CheckerboardSpec;

// Views per camera (test_intrinsic_calibration: the principal point needs many at 320x240).
constexpr int kViews = 60;

TEST(CalibrationSim, IntrinsicsFromRenderedCheckerboards) {
  const auto rig = tabletop_capture::makeDefaultRig(tabletop_capture::DefaultRigOptions{8, 320, 240, true});
  const CheckerboardSpec board{9, 6, 0.03};
  for (int camera : {0, 5}) {
    const CameraModel& truth = rig.cameras[camera];
    const CheckerboardRenderer renderer(truth, board);
    const auto poses = tabletop_capture::randomBoardPoses(truth, board, kViews, 100 + camera);
    ASSERT_EQ(poses.size(), static_cast<size_t>(kViews));
    std::vector<std::vector<Eigen::Vector2d>> views;
    double err2 = 0;
    size_t corners = 0;
    int missed = 0;
    for (size_t k = 0; k < poses.size(); ++k) {
      const cv::Mat image = renderer.render(poses[k], 1000 * camera + k);
      std::vector<Eigen::Vector2d> found;
      if (!tabletop_capture::detectCheckerboard(image, board, &found)) {
        ++missed;
        continue;
      }
      // The detector may start at either end of the board (a 180 deg turn of a board with an
      // odd and an even corner count looks the same): compare in the order that matches.
      const auto points = board.boardPoints();
      double forward = 0, reverse = 0;
      for (size_t i = 0; i < found.size(); ++i) {
        Eigen::Vector2d q, r;
        ASSERT_TRUE(truth.projectCamera(poses[k] * points[i], &q));
        ASSERT_TRUE(truth.projectCamera(poses[k] * points[found.size() - 1 - i], &r));
        forward += (found[i] - q).squaredNorm();
        reverse += (found[i] - r).squaredNorm();
      }
      err2 += std::min(forward, reverse);
      corners += found.size();
      views.push_back(found);
    }
    ASSERT_GE(views.size(), kViews * 9 / 10) << missed << " boards not found in cam" << camera;
    const auto c = tabletop_capture::calibrateIntrinsics(views, board, truth.width, truth.height);
    std::printf("[ figures  ] cam%d: %zu of %d boards found, corner detection error %.3f px RMS; "
                "fx %.3f (true %.3f), fy %.3f (%.3f), cx %.3f (%.3f), cy %.3f (%.3f), k1 %.4f "
                "(%.4f), reprojection %.3f px, coverage %.2f\n", camera, views.size(), kViews,
                std::sqrt(err2 / corners), c.camera.fx, truth.fx, c.camera.fy, truth.fy, c.camera.cx,
                truth.cx, c.camera.cy, truth.cy, c.camera.distortion[0], truth.distortion[0], c.rms_px,
                c.coverage);
    EXPECT_NEAR(c.camera.fx, truth.fx, 0.005 * truth.fx) << "cam" << camera;
    EXPECT_NEAR(c.camera.fy, truth.fy, 0.005 * truth.fy) << "cam" << camera;
    EXPECT_NEAR(c.camera.cx, truth.cx, 0.3) << "cam" << camera;
    EXPECT_NEAR(c.camera.cy, truth.cy, 0.3) << "cam" << camera;
    EXPECT_LT(c.rms_px, 0.3) << "cam" << camera;
  }
}

// The calibrate_intrinsics tool's job on image files: progress per image, views evenly kept up
// to max_views, and clear errors for what it cannot use.
TEST(CalibrationSim, CalibrationFromImageFiles) {
  const auto rig = tabletop_capture::makeDefaultRig(tabletop_capture::DefaultRigOptions{8, 320, 240, true});
  const CameraModel& truth = rig.cameras[1];
  const CheckerboardSpec board{9, 6, 0.03};
  const CheckerboardRenderer renderer(truth, board);
  char dir_template[] = "/tmp/tabletop_calib_XXXXXX";
  ASSERT_NE(mkdtemp(dir_template), nullptr);
  const std::string dir = dir_template;
  std::vector<std::string> files;
  const auto poses = tabletop_capture::randomBoardPoses(truth, board, 40, 3);
  for (size_t k = 0; k < poses.size(); ++k) {
    files.push_back(dir + "/view_" + std::to_string(100 + k) + ".png");
    ASSERT_TRUE(cv::imwrite(files.back(), renderer.render(poses[k], k)));
  }
  files.push_back(dir + "/blank.png");  // no board in it
  ASSERT_TRUE(cv::imwrite(files.back(), cv::Mat(240, 320, CV_8UC3, cv::Scalar::all(110))));
  int reported = 0, without = 0;
  const auto r = tabletop_capture::calibrateIntrinsicsFromImages(
      files, board, 30, {}, [&](int, const std::string&, bool found) {
        ++reported;
        without += !found;
      });
  EXPECT_EQ(reported, 41);
  EXPECT_EQ(r.images, 41);
  EXPECT_EQ(r.boards_found, 41 - without);
  EXPECT_GE(r.boards_found, 36);
  EXPECT_EQ(r.used.size(), 30u);
  EXPECT_EQ(r.calibration.views, 30);
  EXPECT_NEAR(r.calibration.camera.fx, truth.fx, 0.005 * truth.fx);
  EXPECT_EQ(r.calibration.camera.width, 320);

  const std::string odd = dir + "/odd.png";
  ASSERT_TRUE(cv::imwrite(odd, cv::Mat(120, 160, CV_8UC3, cv::Scalar::all(0))));
  try {
    tabletop_capture::calibrateIntrinsicsFromImages({files[0], odd}, board, 30);
    ADD_FAILURE() << "images of two sizes accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("odd.png: 160x120"), std::string::npos) << e.what();
  }
  try {
    tabletop_capture::calibrateIntrinsicsFromImages({files.back()}, board, 30);
    ADD_FAILURE() << "a calibration without boards";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("found in 0 of 1 images"), std::string::npos) << e.what();
  }
  std::system(("rm -rf '" + dir + "'").c_str());
}

}  // namespace
}  // namespace tabletop_sim
