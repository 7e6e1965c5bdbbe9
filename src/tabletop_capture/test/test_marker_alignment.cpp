// The world-frame step of the rig calibration on exact synthetic corners (issue 18 step 3; the
// rendered images are tabletop_sim's test_desk_marker_sim): the layout file, triangulation, the
// similarity alignment of a rig known up to a similarity, its warnings, and the layout plot.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "tabletop_capture/calibration/camera_pose_errors.h"
#include "tabletop_capture/calibration/marker_alignment.h"
#include "tabletop_capture/calibration/rig_layout_plot.h"
#include "tabletop_capture/calibration/triangulation.h"
#include "tabletop_capture/default_rig.h"

namespace tabletop_capture {
namespace {

// The marker corners seen by each camera of `rig`, projected exactly, plus Gaussian noise.
std::vector<MarkerSightings> project(const RigDescription& rig, const MarkerLayout& layout, double sigma,
                                     unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma);
  std::vector<MarkerSightings> s(rig.cameras.size());
  for (size_t c = 0; c < rig.cameras.size(); ++c) {
    std::vector<DetectedMarker> found;
    for (size_t m = 0; m < layout.markers.size(); ++m) {
      DetectedMarker d;
      d.id = layout.markers[m].id;
      const auto w = layout.corners(static_cast<int>(m));
      bool ok = true;
      for (int k = 0; k < 4; ++k) {
        ok = ok && rig.cameras[c].projectWorld(w[k], &d.corners[k]) && rig.cameras[c].inImage(d.corners[k]);
        d.corners[k] += Eigen::Vector2d(noise(rng), noise(rng));
      }
      if (ok) found.push_back(d);
    }
    s[c].add(found);
  }
  return s;
}

RigDescription disturbed(const RigDescription& truth, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(3.0 * u(rng), Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized()).toRotationMatrix();
  return transformRig(truth, 0.6 + 0.3 * u(rng), R, Eigen::Vector3d(u(rng), u(rng), u(rng)) * 3.0);
}

TEST(MarkerLayout, YamlRoundTripAndValidation) {
  const MarkerLayout l = defaultMarkerLayout();
  const MarkerLayout r = parseMarkerLayoutYaml(markerLayoutToYaml(l), "test");
  ASSERT_EQ(r.markers.size(), l.markers.size());
  EXPECT_EQ(r.dictionary, l.dictionary);
  for (size_t i = 0; i < l.markers.size(); ++i) {
    EXPECT_EQ(r.markers[i].id, l.markers[i].id);
    EXPECT_DOUBLE_EQ(r.markers[i].size, l.markers[i].size);
    EXPECT_TRUE(r.markers[i].centre.isApprox(l.markers[i].centre));
  }
  // Corners: ArUco's order seen from above (top-left first, clockwise), on the desk.
  const auto c = l.corners(0);
  EXPECT_TRUE(c[0].isApprox(Eigen::Vector3d(-0.075, 0.075, 0)));
  EXPECT_TRUE(c[2].isApprox(Eigen::Vector3d(0.075, -0.075, 0)));
  EXPECT_THROW(parseMarkerLayoutYaml("dictionary: DICT_9X9\nmarkers: [{id: 0, size: 0.1, x: 0, y: 0}]", "t"),
               std::runtime_error);
  EXPECT_THROW(parseMarkerLayoutYaml("markers: [{id: 0, size: 0.1, x: 0, y: 0}, {id: 1, size: 0.1, x: 0.05, y: 0}]",
                                     "t"),
               std::runtime_error);  // overlapping
  EXPECT_THROW(parseMarkerLayoutYaml("markers: [{id: 60, size: 0.1, x: 0, y: 0}]", "t"), std::runtime_error);
  EXPECT_THROW(parseMarkerLayoutYaml("markers: [{id: 1, x: 0, y: 0}]", "t"), std::runtime_error);
}

// The shipped file (what a user prints and edits) is the built-in default.
TEST(MarkerLayout, ConfigFileIsTheDefault) {
  const MarkerLayout f = loadMarkerLayoutYaml(TABLETOP_CAPTURE_CONFIG_DIR "/desk_marker_layout.yaml");
  EXPECT_EQ(markerLayoutToYaml(f), markerLayoutToYaml(defaultMarkerLayout()));
}

TEST(Triangulation, ExactPixelsGiveThePoint) {
  const RigDescription rig = makeDefaultRig();
  const Eigen::Vector3d X(0.21, -0.13, 0.05);
  std::vector<const CameraModel*> cams;
  std::vector<Eigen::Vector2d> px;
  for (const auto& c : rig.cameras) {
    Eigen::Vector2d q;
    ASSERT_TRUE(c.projectWorld(X, &q));
    cams.push_back(&c);
    px.push_back(q);
  }
  const Triangulation t = triangulatePoint(cams, px);
  ASSERT_TRUE(t.ok);
  EXPECT_LT((t.point - X).norm(), 1e-9);
  EXPECT_LT(t.rms_px, 1e-6);
  EXPECT_FALSE(triangulatePoint({cams[0]}, {px[0]}).ok);  // one camera: no depth
}

// Bar of the issue: every camera within 2 mm and 0.2 deg. The corner noise is 0.1 px per axis
// (0.14 px RMS per corner), nearly twice the detector's measured error on the rendered images
// (test_desk_marker_sim: 0.08 px RMS per corner): room for real images; 3 random similarities.
TEST(MarkerAlignment, SyntheticCornersWithDetectionNoise) {
  const RigDescription truth = makeDefaultRig();
  const MarkerLayout layout = defaultMarkerLayout();
  for (unsigned seed : {1u, 2u, 3u}) {
    const auto a = alignRigToMarkers(disturbed(truth, seed), project(truth, layout, 0.1, seed), layout);
    EXPECT_TRUE(a.warnings.empty()) << a.warnings.front();
    EXPECT_EQ(a.markers_used.size(), layout.markers.size());
    EXPECT_EQ(a.cameras_with_marker, 8);
    for (size_t i = 0; i < truth.cameras.size(); ++i)
      EXPECT_DOUBLE_EQ(a.rig.cameras[i].fx, truth.cameras[i].fx);  // intrinsics unchanged
    const CameraPoseError worst = worstPoseError(cameraPoseErrors(a.rig, truth));
    const double worst_mm = worst.position_m * 1e3, worst_deg = worst.rotation_deg;
    std::printf("[ figures  ] seed %u: worst camera %.3f mm, %.4f deg; fit %.3f mm RMS; reprojection %.3f px\n",
                seed, worst_mm, worst_deg, a.fit_rms * 1e3, a.reprojection_rms_px);
    EXPECT_LT(worst_mm, 2.0);
    EXPECT_LT(worst_deg, 0.2);
    // Exact corners: exact rig.
    const auto e = alignRigToMarkers(disturbed(truth, seed), project(truth, layout, 0.0, seed), layout);
    for (size_t i = 0; i < truth.cameras.size(); ++i)
      EXPECT_LT((e.rig.cameras[i].center() - truth.cameras[i].center()).norm(), 1e-8);
    EXPECT_LT(e.fit_rms, 1e-9);
  }
}

TEST(MarkerAlignment, FewerThanTwoCamerasIsAnError) {
  const RigDescription truth = makeDefaultRig();
  const MarkerLayout layout = defaultMarkerLayout();
  auto s = project(truth, layout, 0.0, 1);
  for (size_t c = 1; c < s.size(); ++c) s[c] = MarkerSightings();
  EXPECT_THROW(alignRigToMarkers(truth, s, layout), MarkerAlignmentError);
  EXPECT_THROW(alignRigToMarkers(truth, std::vector<MarkerSightings>(8), layout), MarkerAlignmentError);
  EXPECT_THROW(alignRigToMarkers(truth, std::vector<MarkerSightings>(3), layout), std::invalid_argument);
}

// One sheet printed at the wrong size on a board: that marker is measured at its true size and
// the report names it.
TEST(MarkerAlignment, OneWrongMarkerSizeWarns) {
  const RigDescription truth = makeDefaultRig();
  const MarkerLayout layout = defaultMarkerLayout();
  MarkerLayout wrong = layout;
  wrong.markers[2].size = 0.13;
  const auto a = alignRigToMarkers(disturbed(truth, 4), project(truth, layout, 0.05, 4), wrong);
  bool named = false;
  for (const auto& w : a.warnings) named = named || w.find("marker id 2 measures") != std::string::npos;
  EXPECT_TRUE(named);
}

// A rig that looks at the desk from underneath (here: every camera mirrored below it, which a
// point-light reconstruction can converge to) still fits the markers, with every camera at
// z < 0: the alignment warns and keeps the result (no proper rotation can undo a reflection; the
// input rig must be redone).
TEST(MarkerAlignment, CamerasBelowTheDeskWarn) {
  RigDescription below = makeDefaultRig();
  for (auto& c : below.cameras) {
    Eigen::Vector3d p = c.center();
    p.z() = -p.z();
    c.world_T_camera = lookAt(p, Eigen::Vector3d(0, -0.05, -0.25));
  }
  const MarkerLayout layout = defaultMarkerLayout();
  const auto a = alignRigToMarkers(below, project(below, layout, 0.0, 5), layout);
  int warned = 0;
  for (const auto& w : a.warnings) warned += w.find("below the desk") != std::string::npos;
  EXPECT_EQ(warned, 8);
  EXPECT_LT(a.fit_rms, 1e-9);
}

TEST(RigLayoutPlot, DrawsEveryCameraInBothViews) {
  const RigDescription rig = makeDefaultRig();
  RigLayoutPlotOptions o;
  o.width = 900;
  o.height = 450;
  const MarkerLayout layout = defaultMarkerLayout();
  for (size_t m = 0; m < layout.markers.size(); ++m) o.markers.push_back(layout.corners(static_cast<int>(m)));
  o.points = {Eigen::Vector3d(0.1, 0.1, 0.3)};
  o.title = "default rig";
  const cv::Mat img = drawRigLayout(rig, o);
  ASSERT_EQ(img.cols, 900);
  ASSERT_EQ(img.rows, 450);
  ASSERT_EQ(img.type(), CV_8UC3);
  for (size_t i = 0; i < rig.cameras.size(); ++i) {
    const cv::Scalar col = rigLayoutCameraColour(static_cast<int>(i));
    int left = 0, right = 0;
    for (int y = 0; y < img.rows; ++y)
      for (int x = 0; x < img.cols; ++x) {
        const cv::Vec3b p = img.at<cv::Vec3b>(y, x);
        if (p[0] == col[0] && p[1] == col[1] && p[2] == col[2]) (x < img.cols / 2 ? left : right)++;
      }
    // A filled disc of radius 6 at the centre: ~100 px of the exact colour in each view.
    EXPECT_GT(left, 60) << rig.cameras[i].name;
    EXPECT_GT(right, 20) << rig.cameras[i].name;  // side view: discs may overlap
  }
  RigLayoutPlotOptions tiny;
  tiny.width = 100;
  tiny.height = 50;
  EXPECT_THROW(drawRigLayout(rig, tiny), std::invalid_argument);
}

}  // namespace
}  // namespace tabletop_capture
