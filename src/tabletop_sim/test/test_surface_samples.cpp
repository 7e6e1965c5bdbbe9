// Samples of the true visible skin surface (the reference of the hand-mesh accuracy tool): on the
// surface, uniform in area at the requested density (and better spread than i.i.d. points),
// hidden parts (overlaps, sleeves, the desk, outside the box) left out, deterministic; and on the
// simulated person's hands, every sample on the boundary of the union of its primitives.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>
#include <stdexcept>
#include <vector>

#include "tabletop_sim/body_model.h"
#include "tabletop_sim/motion_script.h"
#include "tabletop_sim/oracle.h"
#include "tabletop_sim/surface_samples.h"

namespace {

using Eigen::AlignedBox3d;
using Eigen::Vector3d;
using tabletop_sim::BodyModel;
using tabletop_sim::BodyPart;
using tabletop_sim::BodyPose;
using tabletop_sim::Material;
using tabletop_sim::MotionScript;
using tabletop_sim::Oracle;
using tabletop_sim::Primitive;
using tabletop_sim::sampleSkinSurface;
using tabletop_sim::Side;
using tabletop_sim::SurfaceSampleOptions;
using tabletop_sim::SurfaceSamples;

constexpr double kSpacing = 0.001;
// Float storage of world coordinates: ~3e-8 m of rounding at 0.5 m from the origin.
constexpr double kFloatTol = 2e-7;

const AlignedBox3d kEverything(Vector3d::Constant(-2.0), Vector3d::Constant(2.0));

SurfaceSampleOptions options(bool above_desk = false, uint32_t seed = 1) {
  SurfaceSampleOptions o;
  o.spacing = kSpacing;
  o.above_desk = above_desk;
  o.seed = seed;
  return o;
}

Primitive skinSphere(const Vector3d& c, double r) {
  return Primitive::sphere(c, r, Material::SKIN, BodyPart::RIGHT_HAND);
}

// Area of sphere (radius r) outside another sphere (radius R) whose centre is d away.
double sphereAreaOutside(double r, double R, double d) {
  const double h = (R * R - (d - r) * (d - r)) / (2.0 * d);  // height of the hidden cap
  return 4.0 * M_PI * r * r - 2.0 * M_PI * r * std::clamp(h, 0.0, 2.0 * r);
}

TEST(SurfaceSamples, SphereSamplesLieOnItWithRadialNormals) {
  const Vector3d c(0.21, -0.27, 0.05);
  const double r = 0.03;
  const SurfaceSamples s = sampleSkinSurface({skinSphere(c, r)}, kEverything, options());
  const double area = 4.0 * M_PI * r * r;
  ASSERT_EQ(s.points.size(), s.normals.size());
  EXPECT_NEAR(double(s.points.size()), area / (kSpacing * kSpacing), 0.03 * area / 1e-6);
  EXPECT_NEAR(s.area, area, 0.01 * area);
  for (size_t i = 0; i < s.points.size(); ++i) {
    const Vector3d p = s.points[i].cast<double>(), n = s.normals[i].cast<double>();
    ASSERT_NEAR((p - c).norm(), r, kFloatTol);
    ASSERT_NEAR(n.norm(), 1.0, 1e-6);
    ASSERT_GT(n.dot((p - c).normalized()), 1.0 - 1e-6);
  }
}

TEST(SurfaceSamples, DensityIsCalibratedAndBetterSpreadThanRandom) {
  // The blue-noise constants of surface_samples.cpp: density 1/spacing^2 within 2 %, and the
  // distance from a random surface point to the nearest sample (what inflates the accuracy
  // tool's mesh -> truth figure) well below that of i.i.d. points (0.50 / 0.98 spacing).
  const Vector3d c(0.1, 0.2, 0.3);
  for (double r : {0.008, 0.05}) {  // a finger, a big sphere
    double count = 0.0;
    std::vector<double> d;
    for (uint32_t seed = 1; seed <= 3; ++seed) {
      const SurfaceSamples s =
          sampleSkinSurface({skinSphere(c, r)}, kEverything, options(false, seed));
      count += double(s.points.size()) / 3.0;
      std::mt19937 g(seed);
      std::normal_distribution<double> n;
      for (int k = 0; k < 3000; ++k) {
        const Vector3d u = Vector3d(n(g), n(g), n(g)).normalized();
        const Eigen::Vector3f q = (c + r * u).cast<float>();
        float best = INFINITY;
        for (const auto& p : s.points) best = std::min(best, (p - q).squaredNorm());
        d.push_back(std::sqrt(double(best)) / kSpacing);
      }
    }
    std::sort(d.begin(), d.end());
    double mean = 0.0;
    for (double x : d) mean += x;
    mean /= double(d.size());
    const double expected = 4.0 * M_PI * r * r / (kSpacing * kSpacing);
    std::printf(
        "r = %.0f mm: %.0f samples (area / spacing^2 = %.0f); nearest sample from a "
        "surface point: mean %.3f, p95 %.3f, max %.3f spacing\n",
        1e3 * r, count, expected, mean, d[size_t(0.95 * double(d.size() - 1))], d.back());
    EXPECT_NEAR(count, expected, 0.02 * expected);
    EXPECT_LT(mean, 0.43);
    EXPECT_LT(d[size_t(0.95 * double(d.size() - 1))], 0.72);
    EXPECT_LT(d.back(), 1.3);
  }
}

TEST(SurfaceSamples, OverlappingSpheresKeepOnlyTheUnionBoundary) {
  const Vector3d c1(0.0, 0.0, 0.1), c2(0.03, 0.01, 0.1);
  const double r1 = 0.025, r2 = 0.02, d = (c2 - c1).norm();
  const SurfaceSamples s =
      sampleSkinSurface({skinSphere(c1, r1), skinSphere(c2, r2)}, kEverything, options());
  size_t on1 = 0;
  for (const auto& pf : s.points) {
    const Vector3d p = pf.cast<double>();
    const double d1 = (p - c1).norm(), d2 = (p - c2).norm();
    ASSERT_GE(d1, r1 - kFloatTol);  // strictly inside neither
    ASSERT_GE(d2, r2 - kFloatTol);
    ASSERT_TRUE(std::abs(d1 - r1) < kFloatTol || std::abs(d2 - r2) < kFloatTol);
    on1 += std::abs(d1 - r1) < kFloatTol;
  }
  const double a1 = sphereAreaOutside(r1, r2, d), a2 = sphereAreaOutside(r2, r1, d);
  EXPECT_NEAR(s.area, a1 + a2, 0.01 * (a1 + a2));
  EXPECT_NEAR(double(s.points.size()), (a1 + a2) / 1e-6, 0.03 * (a1 + a2) / 1e-6);
  EXPECT_NEAR(double(on1) / double(s.points.size()), a1 / (a1 + a2), 0.02);
}

TEST(SurfaceSamples, SleeveHidesTheSkinItCovers) {
  // Skin capsule along x from 0 to 10 cm (r 2 cm); a sleeve (r 2.5 cm) over x in [-5, 5] cm.
  // Visible skin: the cylinder beyond x = 5 + sqrt(2.5^2 - 2^2) = 6.5 cm plus the far end cap.
  const std::vector<Primitive> person = {
      Primitive::capsule({0, 0, 0.1}, {0.1, 0, 0.1}, 0.02, Material::SKIN, BodyPart::RIGHT_FOREARM),
      Primitive::capsule({-0.05, 0, 0.1}, {0.05, 0, 0.1}, 0.025, Material::SLEEVE,
                         BodyPart::RIGHT_FOREARM)};
  const SurfaceSamples s = sampleSkinSurface(person, kEverything, options());
  const double visible = 2.0 * M_PI * 0.02 * 0.035 + 2.0 * M_PI * 0.02 * 0.02;
  EXPECT_NEAR(s.area, visible, 0.01 * visible);
  EXPECT_NEAR(double(s.points.size()), visible / 1e-6, 0.03 * visible / 1e-6);
  for (const auto& pf : s.points) {
    const Vector3d p = pf.cast<double>();
    ASSERT_GE(p.x(), 0.065 - kFloatTol);  // nothing under the sleeve
    ASSERT_FALSE(person[1].contains(p - 1e-6 * person[1].normal(p)));
  }
}

TEST(SurfaceSamples, SkinSolidOptionsCloseTheSurface) {
  // The capsule and sleeve above, the box cutting the skin at x = 9 cm. With both options the
  // samples are the closed boundary of (skin solid) n (box): the visible cylinder x in
  // [6.5, 9] cm, the sleeve's end-sphere cap inside the skin (height 1 cm) and the disc cut at
  // x = 9 cm; and the divergence theorem gives its volume back.
  const std::vector<Primitive> person = {
      Primitive::capsule({0, 0, 0.1}, {0.1, 0, 0.1}, 0.02, Material::SKIN, BodyPart::RIGHT_FOREARM),
      Primitive::capsule({-0.05, 0, 0.1}, {0.05, 0, 0.1}, 0.025, Material::SLEEVE,
                         BodyPart::RIGHT_FOREARM)};
  const AlignedBox3d box(Vector3d(-1, -1, -1), Vector3d(0.09, 1, 1));
  SurfaceSampleOptions o = options();
  const double visible = 2.0 * M_PI * 0.02 * 0.025, cuff = 2.0 * M_PI * 0.025 * 0.01,
               cut = M_PI * 0.02 * 0.02;
  EXPECT_NEAR(sampleSkinSurface(person, box, o).area, visible, 0.01 * visible);
  o.clothing_interface = true;
  EXPECT_NEAR(sampleSkinSurface(person, box, o).area, visible + cuff, 0.01 * (visible + cuff));
  o.box_faces = true;
  const SurfaceSamples s = sampleSkinSurface(person, box, o);
  const double total = visible + cuff + cut;
  EXPECT_NEAR(s.area, total, 0.01 * total);
  EXPECT_NEAR(double(s.points.size()), total / 1e-6, 0.03 * total / 1e-6);
  const Vector3d cuff_centre(0.05, 0, 0.1);
  double flux = 0.0;
  size_t n_cuff = 0, n_cut = 0;
  for (size_t i = 0; i < s.points.size(); ++i) {
    const Vector3d p = s.points[i].cast<double>(), n = s.normals[i].cast<double>();
    flux += (p - cuff_centre).dot(n);
    if (std::abs((p - cuff_centre).norm() - 0.025) < kFloatTol) {  // on the cuff: into it
      ++n_cuff;
      ASSERT_LT(n.dot((p - cuff_centre).normalized()), -1.0 + 1e-6);
    } else if (std::abs(p.x() - 0.09) < kFloatTol) {  // on the cut: out of the box
      ++n_cut;
      ASSERT_GT(n.x(), 1.0 - 1e-6);
      ASSERT_LE(std::hypot(p.y(), p.z() - 0.1), 0.02 + kFloatTol);
    }
  }
  EXPECT_NEAR(double(n_cuff) * 1e-6, cuff, 0.05 * cuff);
  EXPECT_NEAR(double(n_cut) * 1e-6, cut, 0.05 * cut);
  // Volume of the solid on a 0.25 mm grid vs (1/3) sum (p - o) . n dA.
  double volume = 0.0;
  const double h = 0.00025;
  for (double x = 0.04 + h / 2; x < 0.09; x += h)
    for (double y = -0.02 + h / 2; y < 0.02; y += h)
      for (double z = 0.08 + h / 2; z < 0.12; z += h) {
        const Vector3d p(x, y, z);
        volume += person[0].contains(p) && !person[1].contains(p) ? h * h * h : 0.0;
      }
  const double from_samples = flux * (s.area / double(s.points.size())) / 3.0;
  std::printf(
      "skin solid in the box: volume %.4g m^3 (grid), %.4g m^3 (divergence of the "
      "samples)\n",
      volume, from_samples);
  EXPECT_NEAR(from_samples, volume, 0.02 * volume);
}

TEST(SurfaceSamples, BoxAndDeskClip) {
  const Vector3d c(0.1, -0.2, 0.01);
  const double r = 0.03;
  const std::vector<Primitive> person = {skinSphere(c, r)};
  // Half the sphere (x <= centre) in the box.
  const AlignedBox3d half(Vector3d(-1, -1, -1), Vector3d(c.x(), 1, 1));
  const SurfaceSamples h = sampleSkinSurface(person, half, options());
  EXPECT_NEAR(h.area, 2.0 * M_PI * r * r, 0.015 * 2.0 * M_PI * r * r);
  for (const auto& p : h.points) ASSERT_LE(p.x(), c.x() + kFloatTol);
  // The desk (z = 0) cuts a cap of height r - 1 cm off the bottom.
  const SurfaceSamples all = sampleSkinSurface(person, kEverything, options(false));
  const SurfaceSamples desk = sampleSkinSurface(person, kEverything, options(true));
  const double above = 2.0 * M_PI * r * (r + c.z());
  EXPECT_NEAR(all.area, 4.0 * M_PI * r * r, 0.01 * 4.0 * M_PI * r * r);
  EXPECT_NEAR(desk.area, above, 0.01 * above);
  size_t below = 0;
  for (const auto& p : all.points) below += p.z() < 0.0f;
  EXPECT_GT(below, 0u);
  for (const auto& p : desk.points) ASSERT_GE(p.z(), 0.0f);
  // A box entirely below the desk, an empty box, a box missing the person: nothing.
  EXPECT_TRUE(sampleSkinSurface(person, AlignedBox3d(Vector3d(-1, -1, -1), Vector3d(1, 1, -0.001)),
                                options(true))
                  .points.empty());
  EXPECT_TRUE(sampleSkinSurface(person, AlignedBox3d(), options()).points.empty());
  EXPECT_TRUE(sampleSkinSurface(person, AlignedBox3d(Vector3d::Constant(1), Vector3d::Constant(2)),
                                options())
                  .points.empty());
  EXPECT_TRUE(sampleSkinSurface({}, kEverything, options()).points.empty());
}

TEST(SurfaceSamples, NonSkinIsNotSampled) {
  const std::vector<Primitive> person = {
      Primitive::sphere({0, 0, 0.1}, 0.03, Material::SHIRT, BodyPart::TORSO)};
  EXPECT_TRUE(sampleSkinSurface(person, kEverything, options()).points.empty());
}

TEST(SurfaceSamples, EllipsoidIsUniformInArea) {
  // A flat ellipsoid like the palm (41 x 48 x 15.5 mm): the area per octant is the same by
  // symmetry, and the top/bottom faces (|normal.z| > 0.9) are most of it; compare sample counts
  // per region with the area, from a fine numerical integration over the parametrisation.
  Eigen::Matrix3d R = Eigen::AngleAxisd(0.7, Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  const Vector3d semi(0.041, 0.048, 0.0155), c(0.0, -0.2, 0.1);
  const Primitive e = Primitive::ellipsoid(c, R, semi, Material::SKIN, BodyPart::RIGHT_HAND);
  const SurfaceSamples s = sampleSkinSurface({e}, kEverything, options());
  // Numerical area (total and |n_local.z| > 0.9) over theta, phi.
  double total = 0.0, flat = 0.0;
  const int nt = 2000, np = 2000;
  for (int i = 0; i < nt; ++i)
    for (int j = 0; j < np; ++j) {
      const double th = M_PI * (i + 0.5) / nt, ph = 2.0 * M_PI * (j + 0.5) / np;
      const Vector3d u(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th));
      const Vector3d w(semi[1] * semi[2], semi[0] * semi[2], semi[0] * semi[1]);
      const double da = w.cwiseProduct(u).norm() * std::sin(th) * (M_PI / nt) * (2 * M_PI / np);
      total += da;
      if (std::abs(u.cwiseQuotient(semi).normalized().z()) > 0.9) flat += da;
    }
  size_t nflat = 0;
  for (size_t i = 0; i < s.points.size(); ++i) {
    const Vector3d p = s.points[i].cast<double>(), n = s.normals[i].cast<double>();
    const Vector3d l = (R.transpose() * (p - c)).cwiseQuotient(semi);
    ASSERT_NEAR(l.norm(), 1.0, 1e-5);
    ASSERT_GT(n.dot(e.normal(p)), 1.0 - 1e-6);
    nflat += std::abs((R.transpose() * n).z()) > 0.9;
  }
  std::printf(
      "ellipsoid: area %.6f m^2 (numerical %.6f), %zu samples, flat share %.4f "
      "(area share %.4f)\n",
      s.area, total, s.points.size(), double(nflat) / s.points.size(), flat / total);
  EXPECT_NEAR(s.area, total, 0.01 * total);
  EXPECT_NEAR(double(s.points.size()), total / 1e-6, 0.03 * total / 1e-6);
  EXPECT_NEAR(double(nflat) / double(s.points.size()), flat / total, 0.01);
}

TEST(SurfaceSamples, DeterministicPerSeed) {
  const std::vector<Primitive> person = BodyModel().build(BodyModel::restPose());
  const Vector3d h = tabletop_sim::handCentroid(person, Side::LEFT);
  const AlignedBox3d box(h - Vector3d::Constant(0.15), h + Vector3d::Constant(0.15));
  const SurfaceSamples a = sampleSkinSurface(person, box, options(true, 7));
  const SurfaceSamples b = sampleSkinSurface(person, box, options(true, 7));
  const SurfaceSamples c = sampleSkinSurface(person, box, options(true, 8));
  ASSERT_FALSE(a.points.empty());
  EXPECT_EQ(a.points, b.points);
  EXPECT_EQ(a.normals, b.normals);
  EXPECT_NE(a.points, c.points);
  EXPECT_NEAR(double(c.points.size()), double(a.points.size()), 0.02 * double(a.points.size()));
}

TEST(SurfaceSamples, RejectsBadSpacing) {
  const std::vector<Primitive> person = {skinSphere(Vector3d::Zero(), 0.1)};
  for (double sp : {0.0, -0.001, double(NAN), 1e-8}) {
    SurfaceSampleOptions o;
    o.spacing = sp;
    EXPECT_THROW(sampleSkinSurface(person, kEverything, o), std::invalid_argument) << sp;
  }
}

// Every sample of a hand box on the boundary of the union of the person's primitives.
void checkHandBox(const std::vector<Primitive>& person, const Vector3d& head, Side side,
                  const char* what) {
  const Vector3d h = tabletop_sim::handCentroid(person, side);
  ASSERT_TRUE(h.allFinite());
  const AlignedBox3d box(h - Vector3d::Constant(0.15), h + Vector3d::Constant(0.15));
  const auto t0 = std::chrono::steady_clock::now();
  const SurfaceSamples s = sampleSkinSurface(person, box, options(true));
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  const Oracle oracle(person, head, nullptr);
  const BodyPart hand = side == Side::LEFT ? BodyPart::LEFT_HAND : BodyPart::RIGHT_HAND;
  size_t on_hand = 0, outward_blocked = 0, inward_not_skin = 0;
  for (size_t i = 0; i < s.points.size(); ++i) {
    const Vector3d p = s.points[i].cast<double>(), n = s.normals[i].cast<double>();
    ASSERT_TRUE(box.contains(p));
    ASSERT_GE(p.z(), 0.0);
    // On the surface of a skin primitive whose normal it carries; not strictly inside any
    // primitive (where one contains it, 1 um outward along that one's normal leaves it).
    int on = -1;
    for (size_t j = 0; j < person.size(); ++j) {
      const Primitive& q = person[j];
      const Vector3d qn = q.normal(p);
      ASSERT_FALSE(q.contains(p + 1e-6 * qn))
          << what << ": sample " << i << " strictly inside primitive " << j;
      if (isSkin(q.material) && q.contains(p - 1e-6 * qn) && qn.dot(n) > 1.0 - 1e-5) on = int(j);
    }
    ASSERT_GE(on, 0) << what << ": sample " << i << " is on no skin primitive";
    on_hand += person[on].part == hand;
    // Half a millimetre in: inside the person; out: outside, except at concave creases (where
    // two primitives meet, the outward step can enter the neighbour).
    ASSERT_TRUE(oracle.insidePerson(p - 0.0005 * n)) << what << ": sample " << i;
    outward_blocked += oracle.insidePerson(p + 0.0005 * n);
    inward_not_skin += !oracle.insideSkin(p - 0.0005 * n);
  }
  const double hand_area = double(on_hand) * kSpacing * kSpacing;
  std::printf(
      "%s: %zu samples in %.1f ms; visible skin in the box %.4f m^2, of which the hand "
      "%.4f m^2; outward step blocked (creases) %.2f %%, inward step not skin (cuff) "
      "%.2f %%\n",
      what, s.points.size(), ms, s.area, hand_area,
      100.0 * double(outward_blocked) / double(s.points.size()),
      100.0 * double(inward_not_skin) / double(s.points.size()));
  EXPECT_GT(hand_area, 0.02);
  EXPECT_LT(hand_area, 0.06);
  EXPECT_LT(double(outward_blocked), 0.05 * double(s.points.size()));
  EXPECT_LT(double(inward_not_skin), 0.02 * double(s.points.size()));
}

TEST(SurfaceSamples, RestingHandsAreOnTheUnionBoundary) {
  const BodyModel model;
  const BodyPose pose = BodyModel::restPose();
  const std::vector<Primitive> person = model.build(pose);
  checkHandBox(person, model.headCentre(pose), Side::RIGHT, "rest, right hand");
  checkHandBox(person, model.headCentre(pose), Side::LEFT, "rest, left hand");
}

TEST(SurfaceSamples, SkinSolidOptionsCloseAHandBox) {
  // With both options the samples bound the oracle's skin solid cut by the box (hand, wrist,
  // the cuff's inner face, the cut through the forearm): the divergence theorem must give back
  // the volume the oracle's skin grid counts.
  const BodyModel model;
  const BodyPose pose = BodyModel::restPose();
  const std::vector<Primitive> person = model.build(pose);
  const Vector3d h = tabletop_sim::handCentroid(person, Side::RIGHT);
  const AlignedBox3d box(h - Vector3d::Constant(0.15), h + Vector3d::Constant(0.15));
  SurfaceSampleOptions o = options(true);
  o.clothing_interface = o.box_faces = true;
  const SurfaceSamples s = sampleSkinSurface(person, box, o);
  double flux = 0.0;
  for (size_t i = 0; i < s.points.size(); ++i)
    flux += (s.points[i].cast<double>() - h).dot(s.normals[i].cast<double>());
  const double from_samples = flux * (s.area / double(s.points.size())) / 3.0;
  const Oracle oracle(person, model.headCentre(pose), nullptr);
  const double voxel = 0.001;
  const Vector3d lo(box.min().x(), box.min().y(), std::max(0.0, box.min().z()));
  const Eigen::Vector3i dims = ((box.max() - lo) / voxel).array().round().cast<int>();
  std::vector<uint8_t> skin;
  oracle.sampleGrid(lo, voxel, dims, nullptr, &skin);
  double volume = 0.0;
  for (uint8_t v : skin) volume += v;
  volume *= voxel * voxel * voxel;
  std::printf(
      "rest, right hand box, skin solid: %zu samples, area %.4f m^2, volume %.4g m^3 "
      "(oracle grid), %.4g m^3 (divergence of the samples)\n",
      s.points.size(), s.area, volume, from_samples);
  EXPECT_NEAR(from_samples, volume, 0.02 * volume);
}

TEST(SurfaceSamples, ReachingHandsAreOnTheUnionBoundary) {
  // The right hand's half of reach_targets: open hand, fist and pointing shapes.
  const BodyModel model;
  const MotionScript script = MotionScript::create("reach_targets", model);
  for (double f : {0.6, 0.7, 0.8, 0.9}) {
    const BodyPose pose = script.poseAt(f * script.duration());
    char what[64];
    std::snprintf(what, sizeof(what), "reach_targets t = %.1f s, right hand",
                  f * script.duration());
    checkHandBox(model.build(pose), model.headCentre(pose), Side::RIGHT, what);
  }
}

}  // namespace
