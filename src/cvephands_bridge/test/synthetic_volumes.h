// Synthetic probability volumes for the meshing tests and benchmarks: analytic shapes given as
// signed distance functions (negative inside), sampled at the voxel centres into bytes with a
// linear probability ramp p = clamp(0.5 - sd / width) across the surface, plus deterministic
// noise. The iso-surface p = iso of such a volume is the level set sd = width * (0.5 - iso)
// of the analytic shape, which is what the tests measure the mesh against.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <random>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "cvephands_bridge/mesh/probability_grid.h"

namespace cvephands_test {

using Sdf = std::function<double(const Eigen::Vector3d&)>;

struct TestVolume {
  Eigen::Vector3i dims = Eigen::Vector3i::Zero();
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  double voxel = 1.0;
  std::vector<uint8_t> data;

  cvephands::ProbabilityGridView view() const {
    cvephands::ProbabilityGridView v;
    v.data = data.empty() ? nullptr : data.data();
    v.dims = dims;
    v.origin = origin;
    v.voxel_size = voxel;
    return v;
  }
  size_t index(int x, int y, int z) const { return x + size_t(dims.x()) * (y + size_t(dims.y()) * z); }
  Eigen::Vector3d centre(int x, int y, int z) const {
    return origin + voxel * Eigen::Vector3d(x + 0.5, y + 0.5, z + 0.5);
  }
};

inline TestVolume constantVolume(const Eigen::Vector3i& dims, uint8_t value) {
  TestVolume v;
  v.dims = dims;
  v.data.assign(size_t(dims.x()) * dims.y() * dims.z(), value);
  return v;
}

// Uniform random bytes: every cell pattern occurs, the hardest input for crack-freeness.
inline TestVolume noiseVolume(const Eigen::Vector3i& dims, uint32_t seed) {
  TestVolume v = constantVolume(dims, 0);
  std::mt19937 rng(seed);
  for (auto& b : v.data) b = static_cast<uint8_t>(rng() & 0xff);
  return v;
}

// p = clamp(0.5 - sd / width) at every voxel centre, rounded to bytes; width in metres.
inline TestVolume sampleSdf(const Eigen::Vector3i& dims, const Eigen::Vector3d& origin,
                            double voxel, const Sdf& sd, double width) {
  TestVolume v = constantVolume(dims, 0);
  v.origin = origin;
  v.voxel = voxel;
  for (int z = 0; z < dims.z(); ++z)
    for (int y = 0; y < dims.y(); ++y)
      for (int x = 0; x < dims.x(); ++x) {
        const double p = std::clamp(0.5 - sd(v.centre(x, y, z)) / width, 0.0, 1.0);
        v.data[v.index(x, y, z)] = static_cast<uint8_t>(std::lround(255.0 * p));
      }
  return v;
}

// The level set of sd that the iso level (bytes) selects in a sampleSdf volume.
inline double isoDistance(double iso_byte, double width) { return width * (0.5 - iso_byte / 255.0); }

// ---- shapes (signed distances, negative inside) ----------------------------------------------
inline Sdf sphere(const Eigen::Vector3d& c, double r) {
  return [=](const Eigen::Vector3d& p) { return (p - c).norm() - r; };
}
// Ring of radius R around the z axis through c, tube radius r.
inline Sdf torus(const Eigen::Vector3d& c, double R, double r) {
  return [=](const Eigen::Vector3d& p) {
    const Eigen::Vector3d d = p - c;
    return std::hypot(std::hypot(d.x(), d.y()) - R, d.z()) - r;
  };
}
inline Sdf box(const Eigen::Vector3d& c, const Eigen::Vector3d& half) {
  return [=](const Eigen::Vector3d& p) {
    const Eigen::Vector3d d = (p - c).cwiseAbs() - half;
    return d.cwiseMax(0.0).norm() + std::min(d.maxCoeff(), 0.0);
  };
}
inline Sdf capsule(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double r) {
  return [=](const Eigen::Vector3d& p) {
    const Eigen::Vector3d ab = b - a;
    const double t = std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
    return (p - (a + t * ab)).norm() - r;
  };
}
// Not an exact distance (scaled implicit function), but smooth and exact on the surface.
inline Sdf ellipsoid(const Eigen::Vector3d& c, const Eigen::Vector3d& radii) {
  return [=](const Eigen::Vector3d& p) {
    return ((p - c).cwiseQuotient(radii).norm() - 1.0) * radii.minCoeff();
  };
}
inline Sdf unite(std::vector<Sdf> parts) {
  return [parts = std::move(parts)](const Eigen::Vector3d& p) {
    double d = 1e30;
    for (const auto& s : parts) d = std::min(d, s(p));
    return d;
  };
}

// Classifier-like noise: +-amplitude on every voxel, clamped to bytes (seeded, deterministic).
inline void addNoise(TestVolume* v, int amplitude, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> u(-amplitude, amplitude);
  for (auto& b : v->data) b = static_cast<uint8_t>(std::clamp(int(b) + u(rng), 0, 255));
}

// ---- the benchmark workload ------------------------------------------------------------------
// A hand in an 83^3 sub-volume of 3.6 mm voxels (30 cm cube, DESIGN.md section 4): palm
// ellipsoid, four fingers and a thumb as capsules, 2-voxel probability ramp, noise.
inline TestVolume handVolume(uint32_t seed, bool mirror = false) {
  const int n = 83;
  const double voxel = 0.30 / n;
  const Eigen::Vector3d c(0.15, 0.15, 0.15);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> jitter(-0.004, 0.004);
  const double s = mirror ? -1.0 : 1.0;
  std::vector<Sdf> parts = {ellipsoid(c, Eigen::Vector3d(0.042, 0.048, 0.014)),
                            capsule(c + Eigen::Vector3d(0, -0.04, 0), c + Eigen::Vector3d(0, -0.09, -0.01), 0.025)};  // wrist
  const double spread[4] = {-0.027, -0.009, 0.009, 0.027};
  const double length[4] = {0.070, 0.080, 0.075, 0.060};
  for (int f = 0; f < 4; ++f) {
    const Eigen::Vector3d base = c + Eigen::Vector3d(s * spread[f], 0.045, 0.0);
    const Eigen::Vector3d dir =
        Eigen::Vector3d(s * spread[f] * 0.6 + jitter(rng), 1.0, -0.25 + 10 * jitter(rng)).normalized();
    parts.push_back(capsule(base, base + length[f] * dir, 0.0085));
  }
  const Eigen::Vector3d thumb = c + Eigen::Vector3d(s * 0.04, -0.01, -0.005);
  parts.push_back(capsule(thumb, thumb + 0.06 * Eigen::Vector3d(s * 0.8, 0.55, -0.2).normalized(), 0.010));
  TestVolume v = sampleSdf(Eigen::Vector3i(n, n, n), Eigen::Vector3d::Zero(), voxel,
                           unite(parts), 2.0 * voxel);
  addNoise(&v, 20, seed + 1);
  return v;
}

// A seated person over the default workspace box (1.0 x 1.0 x 0.75 m, min (-0.5, -0.5, 0)):
// torso, head, upper arms, forearms, hands, 2-voxel ramp and noise. dims 128x128x96 (7.8 mm)
// or 256x256x192 (3.9 mm).
inline TestVolume personVolume(const Eigen::Vector3i& dims, uint32_t seed) {
  const double voxel = 1.0 / dims.x();
  using V = Eigen::Vector3d;
  const Sdf body = unite({ellipsoid(V(0, -0.35, 0.33), V(0.17, 0.11, 0.22)),   // torso
                          sphere(V(0, -0.36, 0.65), 0.095),                   // head
                          capsule(V(0, -0.36, 0.52), V(0, -0.36, 0.58), 0.05),  // neck
                          capsule(V(-0.19, -0.35, 0.48), V(-0.24, -0.25, 0.28), 0.045),  // arms
                          capsule(V(0.19, -0.35, 0.48), V(0.24, -0.25, 0.28), 0.045),
                          capsule(V(-0.24, -0.25, 0.28), V(-0.15, 0.02, 0.17), 0.037),  // forearms
                          capsule(V(0.24, -0.25, 0.28), V(0.18, 0.05, 0.22), 0.037),
                          ellipsoid(V(-0.14, 0.07, 0.16), V(0.045, 0.06, 0.018)),  // hands
                          ellipsoid(V(0.17, 0.10, 0.21), V(0.045, 0.06, 0.018))});
  TestVolume v = sampleSdf(dims, V(-0.5, -0.5, 0.0), voxel, body, 2.0 * voxel);
  addNoise(&v, 20, seed);
  return v;
}

}  // namespace cvephands_test
