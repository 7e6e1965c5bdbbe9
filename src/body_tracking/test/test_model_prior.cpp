// The body volume with the tracked model as a prior (model_prior.h): the distance it measures,
// and what it keeps and removes on a volume drawn from the model (drawn_body.h) with a
// pSfS-like halo and phantom volume around it. Distances in m; the grid is the 15.6 mm
// workspace grid.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <stdexcept>

#include "body_tracking/kinematics.h"
#include "body_tracking/model_prior.h"
#include "drawn_body.h"

namespace body_tracking {
namespace {

using Eigen::Isometry3d;
using Eigen::Vector3d;

TEST(ModelPrior, SignedDistanceToCylindersAndEllipsoids) {
  // Circular cylinder r = 5 cm from the origin 30 cm along +y: exact distances.
  const TruncatedQuadric c = TruncatedQuadric::cylinder(Isometry3d::Identity(), 0.30, 0.05, 0.05);
  EXPECT_NEAR(signedDistance(c, Vector3d(0.08, 0.10, 0.0)), 0.03, 1e-12);    // beside it
  EXPECT_NEAR(signedDistance(c, Vector3d(0.0, 0.15, 0.0)), -0.05, 1e-12);    // on the axis
  EXPECT_NEAR(signedDistance(c, Vector3d(0.0, 0.15, 0.02)), -0.03, 1e-12);   // inside
  EXPECT_NEAR(signedDistance(c, Vector3d(0.0, 0.35, 0.0)), 0.05, 1e-12);     // beyond a cap
  EXPECT_NEAR(signedDistance(c, Vector3d(0.0, 0.29, 0.0)), -0.01, 1e-12);    // near a cap
  EXPECT_NEAR(signedDistance(c, Vector3d(0.08, 0.34, 0.0)), 0.05, 1e-12);    // off the rim: 3-4-5
  // Moved and turned: the same distances in its own frame.
  const Isometry3d T = Eigen::Translation3d(0.1, -0.2, 0.3) * Eigen::AngleAxisd(0.7, Vector3d(1, 2, 3).normalized());
  const TruncatedQuadric ct = TruncatedQuadric::cylinder(T, 0.30, 0.05, 0.05);
  EXPECT_NEAR(signedDistance(ct, T * Vector3d(0.08, 0.34, 0.0)), 0.05, 1e-12);
  // Sphere r = 10 cm.
  const TruncatedQuadric s = TruncatedQuadric::ellipsoid(T, Vector3d::Constant(0.10));
  EXPECT_NEAR(signedDistance(s, T * Vector3d(0.0, 0.25, 0.0)), 0.15, 1e-12);
  EXPECT_NEAR(signedDistance(s, T * Vector3d::Zero()), -0.10, 1e-12);
  // Ellipsoid 10 x 5 x 4 cm: exact along its axes (the ray from the centre meets the surface
  // square on there).
  const TruncatedQuadric e = TruncatedQuadric::ellipsoid(Isometry3d::Identity(), Vector3d(0.10, 0.05, 0.04));
  EXPECT_NEAR(signedDistance(e, Vector3d(0.12, 0, 0)), 0.02, 1e-12);
  EXPECT_NEAR(signedDistance(e, Vector3d(0, 0.03, 0)), -0.02, 1e-12);
  EXPECT_NEAR(signedDistance(e, Vector3d(0, 0, 0.07)), 0.03, 1e-12);
  // Inside <=> negative, for points all around.
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-0.2, 0.5);
  for (int i = 0; i < 2000; ++i) {
    const Vector3d p(u(rng), u(rng), u(rng));
    for (const TruncatedQuadric* q : {&ct, &s, &e})
      EXPECT_EQ(q->contains(p), signedDistance(*q, p) <= 0) << p.transpose();
  }
}

// A person in the middle of the grid, arms forward over the desk.
BodyFrames personFrames() {
  BodyState s{};
  s[dof::TORSO_Y] = -0.30;
  s[dof::SPINE_BEND] = 0.1;
  s[armDof(Side::LEFT, 0)] = -0.45;
  s[armDof(Side::LEFT, 3)] = 0.35;
  s[armDof(Side::RIGHT, 0)] = -0.9;
  s[armDof(Side::RIGHT, 3)] = 1.2;
  return forwardKinematics(BodyProfile(), s);
}
BodyParts person() { return buildParts(BodyProfile(), personFrames()); }

double distanceToModel(const BodyParts& parts, const Vector3d& p) {
  double d = INFINITY;
  for (const TruncatedQuadric& q : parts) d = std::min(d, signedDistance(q, p));
  return d;
}

TEST(ModelPrior, KeepsTheBodyAndRemovesTheHullsHaloAndPhantomVolume) {
  const BodyParts parts = person();
  const psfs::ProbabilityVolume truth = test::drawnVolume(parts);
  // What pSfS gives (docs/scenario_suite.md): the body, a one-voxel halo at p = 0.59 and sure
  // phantom wedges (here: p = 0.86 on every voxel 3-6 cm out from the model).
  psfs::ProbabilityVolume hull = truth;
  test::addHalo(&hull, 150);
  size_t phantom = 0;
  for (size_t i = 0; i < hull.data.size(); ++i) {
    const double d = distanceToModel(parts, hull.grid.centre(i));
    if (d > 0.03 && d < 0.06 && hull.data[i] == 0) hull.data[i] = 220, ++phantom;
  }
  ASSERT_GT(phantom, 1000u);
  psfs::ProbabilityVolume out;
  applyModelPrior(hull, parts, ModelPriorParams(), &out);
  ASSERT_EQ(out.data.size(), hull.data.size());
  EXPECT_EQ(out.grid, hull.grid);
  // Every voxel of the body stays occupied (its centre is inside the model: at most the 5 mm
  // inside the offset cost it log-odds 1, 255 -> 254); the halo (centres 0-16 mm out at
  // p = 0.59) and the phantom volume go below 0.5.
  size_t kept = 0, halo_left = 0;
  for (size_t i = 0; i < out.data.size(); ++i) {
    if (truth.data[i]) {
      kept += out.data[i] > 127;
      EXPECT_GE(out.data[i], 250) << "voxel " << i;
    } else if (hull.data[i] == 150) {
      halo_left += out.data[i] > 127;
    }
  }
  EXPECT_EQ(kept, psfs::countAbove(truth, 127));
  EXPECT_EQ(halo_left, 0u);
  EXPECT_EQ(psfs::countAbove(out, 127), psfs::countAbove(truth, 127));
  EXPECT_GT(psfs::countAbove(hull, 127), psfs::countAbove(truth, 127) * 3 / 2) << "the test's hull is no phantom";
}

TEST(ModelPrior, SureEvidenceOutsideTheModelNeedsToBeSurerTheFartherOut) {
  const BodyParts parts = person();
  psfs::ProbabilityVolume v = test::drawnVolume(parts);
  std::fill(v.data.begin(), v.data.end(), 0);
  // Single voxels at known distances outside the model, p = 254/255 (logit 5.5): with the
  // defaults (offset -5 mm, falloff 5 mm) it stays occupied up to 5.5 * 5 - 5 = 22.5 mm out.
  std::vector<std::pair<size_t, double>> probes;
  for (size_t i = 0; i < v.data.size(); ++i) {
    const double d = distanceToModel(parts, v.grid.centre(i));
    if (d > 0.0 && d < 0.10 && i % 7 == 0) probes.emplace_back(i, d), v.data[i] = 254;
  }
  ASSERT_GT(probes.size(), 500u);
  psfs::ProbabilityVolume out;
  const ModelPriorParams prm;
  applyModelPrior(v, parts, prm, &out);
  for (const auto& [i, d] : probes) {
    const double l = std::log(254.0 / 1.0) - (d - prm.offset) / prm.falloff;
    EXPECT_NEAR(out.data[i], 255.0 / (1.0 + std::exp(-l)), 0.51) << d;
    if (d < 0.020) {
      EXPECT_GT(out.data[i], 127) << d;
    }
    if (d > 0.025) {
      EXPECT_LE(out.data[i], 127) << d;
    }
    if (d > 0.06) {
      EXPECT_EQ(out.data[i], 0) << d;  // beyond the reach of the byte
    }
  }
}

double distanceToSolids(const std::vector<TruncatedQuadric>& solids, const Vector3d& p) {
  double d = INFINITY;
  for (const TruncatedQuadric& q : solids) d = std::min(d, signedDistance(q, p));
  return d;
}

TEST(ModelPrior, TheNeckAndTheFingerTipsTheModelLacksAreKept) {
  const BodyProfile profile;
  const BodyFrames f = personFrames();
  const BodyParts parts = buildParts(profile, f);
  ModelPriorParams none;
  none.neck_radius = 0;
  none.hand_reach = 0;
  const std::vector<TruncatedQuadric> bare = priorSolids(profile, f, none);
  ASSERT_EQ(bare.size(), parts.size());  // the tracked parts as they are
  for (size_t k = 0; k < parts.size(); ++k) {
    EXPECT_TRUE(bare[k].frame.isApprox(parts[k].frame, 1e-12)) << k;
    EXPECT_LT((bare[k].semi - parts[k].semi).norm(), 1e-12) << k;
    EXPECT_EQ(bare[k].length, parts[k].length) << k;
  }
  const ModelPriorParams prm;  // neck 5.5 cm, hands reaching 6 cm further
  const std::vector<TruncatedQuadric> solids = priorSolids(profile, f, prm);
  ASSERT_EQ(solids.size(), parts.size() + 3);  // two reaching hands and a neck beside the parts
  // The solids only add: no point is farther from them than from the parts.
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  for (int n = 0; n < 3000; ++n) {
    const Vector3d p = f.chest.translation() + Vector3d(u(rng), u(rng) + 0.2, u(rng));
    EXPECT_LE(distanceToSolids(solids, p), distanceToModel(parts, p) + 1e-12) << p.transpose();
  }
  // 1.5 cm above the neck pivot lies between the chest's top (2.5 cm below the pivot) and the
  // head's bottom (3 cm above): outside every part, 5.5 cm deep in the neck (on its axis, 6.5 cm
  // above its bottom at the shoulders' height).
  const Vector3d neck = f.head * Vector3d(0, 0, 0.015);
  EXPECT_GT(distanceToModel(parts, neck), 0.0);
  EXPECT_NEAR(distanceToSolids(solids, neck), -prm.neck_radius, 1e-9);
  // Finger tips 15 cm past the wrist along the forearm: 3 cm beyond the tracked hand's end
  // (wrist + 5 + 7 cm), 3 cm inside the reaching one (wrist + 18 cm).
  for (int i = 0; i < 2; ++i) {
    const Vector3d tip = f.forearm[i] * Vector3d(0, profile.forearm + 0.15, 0);
    EXPECT_NEAR(distanceToModel(parts, tip), 0.03, 1e-9) << i;
    EXPECT_NEAR(distanceToSolids(solids, tip), -0.03, 1e-9) << i;
  }
  // A volume that holds a neck of 4.5 cm radius and finger tips 1.2 cm thick out to 16.5 cm
  // past the wrists, at p = 0.9: the model's parts alone cut them, the prior's solids keep
  // every voxel of them.
  psfs::ProbabilityVolume v = test::drawnVolume(parts);
  std::fill(v.data.begin(), v.data.end(), 0);
  const Eigen::Isometry3d to_head = f.head.inverse();
  std::array<Eigen::Isometry3d, 2> to_forearm = {f.forearm[0].inverse(), f.forearm[1].inverse()};
  std::vector<size_t> drawn;
  size_t finger_voxels = 0;
  for (size_t i = 0; i < v.data.size(); ++i) {
    const Vector3d c = v.grid.centre(i);
    const Vector3d h = to_head * c;
    bool in = h.head<2>().norm() < 0.045 && h.z() > -0.04 && h.z() < 0.03;
    bool finger = false;
    for (int k = 0; k < 2; ++k) {
      const Vector3d a = to_forearm[k] * c;
      finger |= Eigen::Vector2d(a.x(), a.z()).norm() < 0.012 && a.y() > profile.forearm + 0.12 &&
                a.y() < profile.forearm + 0.165;
    }
    if ((in || finger) && distanceToModel(parts, c) > 0.0) {
      v.data[i] = 230, drawn.push_back(i);
      finger_voxels += finger;
    }
  }
  ASSERT_GT(drawn.size(), 20u);
  ASSERT_GE(finger_voxels, 4u) << "the finger tips fall between the voxel centres";
  psfs::ProbabilityVolume cut, kept;
  applyModelPrior(v, parts, prm, &cut);
  applyModelPrior(v, solids, prm, &kept);
  size_t cut_left = 0;
  for (size_t i : drawn) {
    cut_left += cut.data[i] > 127;
    EXPECT_EQ(kept.data[i], 230) << "voxel " << i << ", " << distanceToSolids(solids, v.grid.centre(i)) << " m from the solids";
  }
  EXPECT_LT(cut_left, drawn.size() / 2);
  ModelPriorParams bad;
  bad.neck_radius = NAN;
  EXPECT_THROW(priorSolids(profile, f, bad), std::invalid_argument);
  bad.neck_radius = 0.05;
  bad.hand_reach = -0.01;
  EXPECT_THROW(priorSolids(profile, f, bad), std::invalid_argument);
  bad.hand_reach = INFINITY;
  EXPECT_THROW(priorSolids(profile, f, bad), std::invalid_argument);
}

TEST(ModelPrior, NeverRaisesAProbabilityAndRejectsBadParameters) {
  const BodyParts parts = person();
  psfs::ProbabilityVolume v = test::drawnVolume(parts);
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> byte(0, 255);
  for (uint8_t& x : v.data) x = static_cast<uint8_t>(byte(rng));
  psfs::ProbabilityVolume out;
  applyModelPrior(v, parts, ModelPriorParams(), &out);
  size_t lowered = 0;
  for (size_t i = 0; i < v.data.size(); ++i) {
    EXPECT_LE(out.data[i], v.data[i]);
    lowered += out.data[i] < v.data[i];
  }
  EXPECT_GT(lowered, v.data.size() / 2);  // most of the grid is far from the person
  ModelPriorParams bad;
  bad.falloff = 0;
  EXPECT_THROW(applyModelPrior(v, parts, bad, &out), std::invalid_argument);
  bad.falloff = 0.005;
  bad.offset = NAN;
  EXPECT_THROW(applyModelPrior(v, parts, bad, &out), std::invalid_argument);
  EXPECT_THROW(applyModelPrior(v, parts, ModelPriorParams(), &v), std::invalid_argument);
  EXPECT_THROW(applyModelPrior(v, parts, ModelPriorParams(), nullptr), std::invalid_argument);
  v.data.pop_back();  // a volume whose data does not fill its grid
  EXPECT_THROW(applyModelPrior(v, parts, ModelPriorParams(), &out), std::invalid_argument);
}

}  // namespace
}  // namespace body_tracking
