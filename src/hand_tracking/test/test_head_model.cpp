// Head model: the head's centre from the body volume's cross-section profile, on synthetic
// volumes built like the simulator's head (ellipsoid with hair on top and at the back, a neck
// and shoulders below) at the tracker's 16 mm voxels.
#include <cmath>
#include <cstdio>
#include <functional>

#include <gtest/gtest.h>

#include "hand_tracking/head_model.h"

namespace {

using hand_tracking::fitHeadCentre;
using hand_tracking::HeadModelParams;
using Eigen::Vector3d;

bool inEllipsoid(const Vector3d& p, const Vector3d& c, const Vector3d& semi) {
  return ((p - c).array() / semi.array()).square().sum() <= 1.0;
}

// The workspace grid of DESIGN.md (64 x 64 x 48 over 1.0 x 1.0 x 0.75 m), voxels at p = 1
// where `inside` holds at the voxel centre.
psfs::ProbabilityVolume volume(const std::function<bool(const Vector3d&)>& inside) {
  psfs::ProbabilityVolume v;
  v.grid.origin = Vector3d(-0.5, -0.5, 0.0);
  v.grid.voxel_size = 1.0 / 64;
  v.grid.dims = Eigen::Vector3i(64, 64, 48);
  v.data.assign(v.grid.numVoxels(), 0);
  for (int z = 0; z < 48; ++z)
    for (int y = 0; y < 64; ++y)
      for (int x = 0; x < 64; ++x)
        if (inside(v.grid.centre(x, y, z))) v.data[v.grid.index(x, y, z)] = 255;
  return v;
}

// A seated person's upper body: head ellipsoid (the simulator's 0.075 x 0.095 x 0.115 m)
// centred at `c`, hair per `hair` (0 none, 1 short: on top and at the back), neck, shoulders.
std::function<bool(const Vector3d&)> person(const Vector3d& c, int hair) {
  return [c, hair](const Vector3d& p) {
    if (inEllipsoid(p, c, Vector3d(0.075, 0.095, 0.115))) return true;
    if (hair >= 1 && inEllipsoid(p, c + Vector3d(0, -0.025, 0.03), Vector3d(0.082, 0.092, 0.11)))
      return true;
    const Vector3d n = p - (c + Vector3d(0, -0.01, -0.15));  // neck: vertical cylinder
    if (n.head<2>().norm() < 0.055 && std::abs(n.z()) < 0.06) return true;
    const Vector3d t = p - (c + Vector3d(0, -0.02, -0.36));  // shoulders and chest
    return std::abs(t.x()) < 0.21 && std::abs(t.y()) < 0.12 && std::abs(t.z()) < 0.16;
  };
}

// The default parameters with the centre's x and y from the blob's axis alone (face_weight 0).
HeadModelParams axisOnly() {
  HeadModelParams p;
  p.face_weight = 0.0;
  return p;
}

}  // namespace

TEST(HeadModel, FindsTheCentreFromTheFace) {
  // The face centroid (what the skin-based MPF reports) lies in front of and below the
  // centre; the fit must recover the centre. On this exact hull the vertex is within half a
  // voxel (8 mm) of the blob's widest level, and the top-based estimate is off by the
  // difference between top_above_centre and the true height (0.115 m bald: -20 mm; 0.14 m
  // with hair: +5 mm); hair lifts the widest level by up to 19 mm and, lying at the back,
  // moves the axis back by as much. The top is read to a fraction of a level from the areas,
  // which on a cap is low by up to a voxel (16 mm). Bald: half of 20 + 16 mm from the top
  // (vertex_weight 0.5), half of the vertex's 8 mm: 22 mm; with hair within 12 mm in z and
  // 19 mm in y, plus 8 mm.
  // The centre's x and y here are the axis alone (face_weight 0; the blend: next test).
  const Vector3d centre(0.03, -0.30, 0.55);
  const Vector3d face = centre + Vector3d(0.0, 0.07, -0.04);
  for (int hair : {0, 1}) {
    const psfs::ProbabilityVolume v = volume(person(centre, hair));
    const auto fit = fitHeadCentre(v, face, axisOnly());
    ASSERT_TRUE(fit.ok) << "hair " << hair;
    EXPECT_FALSE(fit.clipped);
    EXPECT_FALSE(fit.from_top);  // the blend of vertex and top, not the top alone
    EXPECT_TRUE(std::isfinite(fit.vertex));
    const Vector3d e = fit.centre - centre;
    std::printf("hair %d: centre error (%.1f, %.1f, %.1f) mm, face was %.1f mm off; top %.3f m, "
                "%d levels\n", hair, 1e3 * e.x(), 1e3 * e.y(), 1e3 * e.z(),
                1e3 * (face - centre).norm(), fit.top, fit.levels);
    EXPECT_LT(std::abs(e.x()), 0.008);
    EXPECT_LT(e.norm(), hair ? std::hypot(0.012, 0.019) + 0.008 : 0.022);
    EXPECT_LT(e.norm(), (face - centre).norm() / 3);
  }
}

TEST(HeadModel, TheFaceEstimatePullsAHairedHeadForward) {
  // Hair at the back of the head moves the blob's axis back (the test above: up to 19 mm);
  // the face estimate lies 70 mm in front. With face_weight w the centre's x and y are
  // (1 - w) axis + w face, its height unchanged: at the default 0.25 the error along y is
  // 0.75 x (the axis' error) + 0.25 x 70 mm, smaller than the axis' own here.
  const Vector3d centre(0.03, -0.30, 0.55);
  const Vector3d face = centre + Vector3d(0.0, 0.07, -0.04);
  const psfs::ProbabilityVolume v = volume(person(centre, 1));
  const auto axis_fit = fitHeadCentre(v, face, axisOnly());
  const HeadModelParams blended;  // the default
  const auto fit = fitHeadCentre(v, face, blended);
  ASSERT_TRUE(axis_fit.ok);
  ASSERT_TRUE(fit.ok);
  const double w = blended.face_weight;
  EXPECT_EQ(w, 0.25);
  const double axis_error_y = axis_fit.centre.y() - centre.y();
  std::printf("axis alone: y error %.1f mm; with face_weight %.2f: %.1f mm\n",
              1e3 * axis_error_y, w, 1e3 * (fit.centre.y() - centre.y()));
  EXPECT_LT(axis_error_y, -0.008);  // hair at the back: the axis lies behind the centre
  EXPECT_NEAR(fit.centre.x(), (1 - w) * axis_fit.centre.x() + w * face.x(), 1e-12);
  EXPECT_NEAR(fit.centre.y(), (1 - w) * axis_fit.centre.y() + w * face.y(), 1e-12);
  EXPECT_EQ(fit.centre.z(), axis_fit.centre.z());
  EXPECT_LT(std::abs(fit.centre.y() - centre.y()), std::abs(axis_error_y));
  // All the weight on the face: its x and y.
  HeadModelParams face_only;
  face_only.face_weight = 1.0;
  const auto face_fit = fitHeadCentre(v, face, face_only);
  ASSERT_TRUE(face_fit.ok);
  EXPECT_NEAR((face_fit.centre - face).head<2>().norm(), 0.0, 1e-12);
}

TEST(HeadModel, AProfileWithoutAWidestLevelGivesTheTopBasedCentre) {
  // Long hair spread down over the shoulders like a cone from the crown: the blob's area only
  // grows downwards, so there is no vertex. The centre comes from the top alone, not from the
  // face (81 mm off; before: the face was reported): the head's 0.14 m with hair against
  // top_above_centre 0.135 m puts it 5 mm high, and the top's fractional read of a cap is
  // low by up to a voxel (15.6 mm): -10.6..+5 mm in z.
  const Vector3d centre(0.03, -0.30, 0.50);
  const Vector3d face = centre + Vector3d(0.0, 0.07, -0.04);
  auto body = person(centre, 1);
  const psfs::ProbabilityVolume v = volume([&](const Vector3d& p) {
    const double below_top = centre.z() + 0.14 - p.z();
    return body(p) || (below_top > 0.0 && below_top < 0.25 &&
                       (p - centre).head<2>().norm() < 0.13 * below_top / 0.20);
  });
  const auto fit = fitHeadCentre(v, face, HeadModelParams());
  ASSERT_TRUE(fit.ok);
  EXPECT_TRUE(fit.from_top);
  EXPECT_FALSE(fit.clipped);
  EXPECT_FALSE(std::isfinite(fit.vertex));
  EXPECT_NEAR(fit.centre.z(), fit.top - HeadModelParams().top_above_centre, 1e-12);
  const Vector3d e = fit.centre - centre;
  std::printf("no vertex: centre error (%.1f, %.1f, %.1f) mm\n", 1e3 * e.x(), 1e3 * e.y(),
              1e3 * e.z());
  EXPECT_GT(e.z(), 0.005 - 1.0 / 64 - 1e-3);
  EXPECT_LT(e.z(), 0.005 + 1e-3);
  EXPECT_LT(std::abs(e.x()), 0.008);  // the blob is symmetric in x: within half a voxel
  EXPECT_LT(e.norm(), (face - centre).norm() / 3);

  // The same head with its top above the workspace's ceiling (0.75 m): the top is unknown and
  // there is no vertex, so the fit gives up and the face estimate stays.
  const Vector3d tall(0.03, -0.30, 0.64);
  const psfs::ProbabilityVolume cut = volume([&](const Vector3d& p) {
    const double below_top = tall.z() + 0.14 - p.z();
    return person(tall, 1)(p) || (below_top > 0.0 && below_top < 0.25 &&
                                  (p - tall).head<2>().norm() < 0.13 * below_top / 0.20);
  });
  const Vector3d tall_face = tall + Vector3d(0.0, 0.07, -0.04);
  const auto cut_fit = fitHeadCentre(cut, tall_face, HeadModelParams());
  EXPECT_FALSE(cut_fit.ok);
  EXPECT_TRUE(cut_fit.clipped);
  EXPECT_EQ(cut_fit.centre, tall_face);
}

TEST(HeadModel, HeadCutOffByTheWorkspaceCeiling) {
  // A tall person: the head's top is above the workspace (0.75 m). The top is unknown, the
  // widest level is inside: the vertex alone, within a voxel. (The axis alone for x and y: a
  // bald head's face estimate, the skin of the whole head, lies nearer its centre than this
  // stand-in 70 mm in front.)
  const Vector3d centre(0.0, -0.30, 0.66);
  const psfs::ProbabilityVolume v = volume(person(centre, 0));
  const auto fit = fitHeadCentre(v, centre + Vector3d(0.0, 0.07, -0.04), axisOnly());
  ASSERT_TRUE(fit.ok);
  EXPECT_TRUE(fit.clipped);
  const Vector3d e = fit.centre - centre;
  std::printf("cut off: centre error (%.1f, %.1f, %.1f) mm\n", 1e3 * e.x(), 1e3 * e.y(), 1e3 * e.z());
  EXPECT_LT(e.norm(), 0.016);
}

TEST(HeadModel, IgnoresAHandRaisedAboveTheHead) {
  // A hand 10 cm above the head, past a gap: the top is still the head's.
  const Vector3d centre(0.0, -0.30, 0.50);
  auto body = person(centre, 1);
  const psfs::ProbabilityVolume with_hand = volume([&](const Vector3d& p) {
    return body(p) || inEllipsoid(p, centre + Vector3d(0.02, 0.0, 0.27), Vector3d(0.05, 0.02, 0.09));
  });
  const psfs::ProbabilityVolume without = volume(body);
  const Vector3d face = centre + Vector3d(0.0, 0.07, -0.04);
  const auto a = fitHeadCentre(with_hand, face, HeadModelParams());
  const auto b = fitHeadCentre(without, face, HeadModelParams());
  ASSERT_TRUE(a.ok && b.ok);
  EXPECT_NEAR((a.centre - b.centre).norm(), 0.0, 1e-9);
}

TEST(HeadModel, ImplausibleInputLeavesTheFaceEstimate) {
  const Vector3d face(0.0, -0.25, 0.5);
  // Nothing there.
  auto fit = fitHeadCentre(volume([](const Vector3d&) { return false; }), face, HeadModelParams());
  EXPECT_FALSE(fit.ok);
  EXPECT_EQ(fit.centre, face);
  // A column that never ends (no top within max_above): no head shape.
  fit = fitHeadCentre(volume([&](const Vector3d& p) { return (p - face).head<2>().norm() < 0.08; }),
                      face, HeadModelParams());
  EXPECT_FALSE(fit.ok);
  EXPECT_EQ(fit.centre, face);
  // Non-finite face.
  fit = fitHeadCentre(volume(person(Vector3d(0, -0.3, 0.5), 1)), Vector3d(NAN, 0, 0),
                      HeadModelParams());
  EXPECT_FALSE(fit.ok);
}

TEST(HeadModel, ValidatesParameters) {
  HeadModelParams p;
  p.radius = 0.0;
  EXPECT_THROW(p.validate(), std::invalid_argument);
  p = HeadModelParams();
  p.vertex_weight = 1.5;
  EXPECT_THROW(p.validate(), std::invalid_argument);
  p = HeadModelParams();
  p.face_weight = -0.1;
  EXPECT_THROW(p.validate(), std::invalid_argument);
  p.face_weight = 1.1;
  EXPECT_THROW(p.validate(), std::invalid_argument);
  p = HeadModelParams();
  p.threshold = 1.0;
  EXPECT_THROW(p.validate(), std::invalid_argument);
  p = HeadModelParams();
  p.iterations = 0;
  EXPECT_THROW(p.validate(), std::invalid_argument);
  EXPECT_NO_THROW(HeadModelParams().validate());
}
