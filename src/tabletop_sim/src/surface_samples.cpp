#include "tabletop_sim/surface_samples.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>

namespace tabletop_sim {

namespace {

using Eigen::Vector3d;

// Candidates per spacing^2 before the blue-noise thinning, and the thinning's exclusion radius in
// units of spacing, calibrated together (test_surface_samples.cpp, DensityIsCalibrated) so the
// kept density is 1/spacing^2. More candidates saturate the packing better (smaller holes) but
// cost time linearly (10: p95 hole 0.67 instead of 0.68 spacing, twice the time).
constexpr double kOversample = 6.0;
constexpr double kDiskRadius = 0.716;

// 48 bytes each: ~5 GB. A hand box at 1 mm needs ~0.4 M.
constexpr double kMaxCandidates = 1e8;

// A point ON another primitive's surface (an exactly shared boundary) is not hidden by it.
constexpr double kStrictEps = 1e-10;  // m

// Uniform doubles and bounded integers from mt19937, written out so that the samples are the same
// with any standard library (std::uniform_real_distribution and std::shuffle are not portable).
class Rng {
 public:
  Rng(uint32_t seed, uint32_t stream) {
    std::seed_seq s{seed, stream, 0x5a3d1e7bu};
    g_.seed(s);
  }
  double uniform() {  // [0, 1), 53 bits
    const uint64_t a = g_() >> 5, b = g_() >> 6;
    return (double(a) * 67108864.0 + double(b)) * (1.0 / 9007199254740992.0);
  }
  uint64_t below(uint64_t n) {  // [0, n), n < 2^32; bias < n / 2^32, irrelevant here
    return (uint64_t(g_()) * n) >> 32;
  }

 private:
  std::mt19937 g_;
};

Vector3d uniformOnSphere(Rng& rng) {  // Archimedes: z uniform in [-1, 1]
  const double z = 1.0 - 2.0 * rng.uniform();
  const double phi = 2.0 * M_PI * rng.uniform();
  const double s = std::sqrt(std::max(0.0, 1.0 - z * z));
  return Vector3d(s * std::cos(phi), s * std::sin(phi), z);
}

Vector3d closestOnSegment(const Vector3d& p, const Vector3d& a, const Vector3d& b) {
  const Vector3d ba = b - a;
  const double l2 = ba.squaredNorm();
  const double s = l2 > 0.0 ? std::clamp((p - a).dot(ba) / l2, 0.0, 1.0) : 0.0;
  return a + s * ba;
}

// Primitive::contains() is closed; hiding needs the open interior.
bool strictlyInside(const Primitive& q, const Vector3d& p) {
  switch (q.type) {
    case Primitive::Type::SPHERE:
      return (p - q.p0).norm() < q.radius - kStrictEps;
    case Primitive::Type::CAPSULE:
      return (p - closestOnSegment(p, q.p0, q.p1)).norm() < q.radius - kStrictEps;
    case Primitive::Type::ELLIPSOID:
      // Algebraic distance; the tolerance only has to be tiny, not exact.
      return (q.axes.transpose() * (p - q.p0)).cwiseQuotient(q.semi_axes).norm() <
             1.0 - kStrictEps / q.semi_axes.maxCoeff();
  }
  return false;
}

struct Candidate {
  Vector3d p, n;
};

// Expected candidate count of one primitive at `density` per m^2 (for the size check).
double expectedCandidates(const Primitive& q, double density) {
  switch (q.type) {
    case Primitive::Type::SPHERE:
      return density * 4.0 * M_PI * q.radius * q.radius;
    case Primitive::Type::CAPSULE:
      return density *
             (2.0 * M_PI * q.radius * (q.p1 - q.p0).norm() + 4.0 * M_PI * q.radius * q.radius);
    case Primitive::Type::ELLIPSOID: {  // the tries (an upper bound)
      Vector3d s = q.semi_axes;
      std::sort(s.data(), s.data() + 3);
      return density * 4.0 * M_PI * s[1] * s[2];
    }
  }
  return 0.0;
}

// I.i.d. uniform points on q's surface at `density` per m^2 (area-proportional counts), passed to
// `emit(point, outward normal)`.
template <typename Emit>
void sampleSurface(const Primitive& q, double density, Rng& rng, Emit&& emit) {
  switch (q.type) {
    case Primitive::Type::SPHERE: {
      const long n = std::lround(density * 4.0 * M_PI * q.radius * q.radius);
      for (long k = 0; k < n; ++k) {
        const Vector3d d = uniformOnSphere(rng);
        emit(q.p0 + q.radius * d, d);
      }
      return;
    }
    case Primitive::Type::CAPSULE: {
      const Vector3d ab = q.p1 - q.p0;
      const double len = ab.norm();
      const double r = q.radius;
      // Cylinder side (developable: uniform in axial position and angle).
      if (len > 0.0) {
        const Vector3d w = ab / len;
        const Vector3d e1 = w.unitOrthogonal(), e2 = w.cross(e1);
        const long n = std::lround(density * 2.0 * M_PI * r * len);
        for (long k = 0; k < n; ++k) {
          const double s = len * rng.uniform();
          const double phi = 2.0 * M_PI * rng.uniform();
          const Vector3d d = std::cos(phi) * e1 + std::sin(phi) * e2;
          emit(q.p0 + s * w + r * d, d);
        }
      }
      // The two end caps make one sphere: each direction goes to the cap on its side.
      const long n = std::lround(density * 4.0 * M_PI * r * r);
      for (long k = 0; k < n; ++k) {
        const Vector3d d = uniformOnSphere(rng);
        emit((d.dot(ab) > 0.0 ? q.p1 : q.p0) + r * d, d);
      }
      return;
    }
    case Primitive::Type::ELLIPSOID: {
      // x = c + R S u for u on the unit sphere; the area element relative to the sphere's is
      // f(u) = s0 s1 s2 |S^-1 u| (|det A| |A^-T n| for the linear map A = R S). Accepting u with
      // probability f / max f makes the points uniform in area, and with
      // tries = density * 4 pi max f the expected count is density * area, exactly.
      const Vector3d& s = q.semi_axes;
      const Vector3d w(s[1] * s[2], s[0] * s[2], s[0] * s[1]);  // f(u) = |w .* u|
      const double fmax = w.maxCoeff();
      const long tries = std::lround(density * 4.0 * M_PI * fmax);
      for (long k = 0; k < tries; ++k) {
        const Vector3d u = uniformOnSphere(rng);
        const double f = w.cwiseProduct(u).norm();
        if (rng.uniform() * fmax >= f) continue;
        const Vector3d n = q.axes * u.cwiseQuotient(s);  // gradient direction, local S^-1 u
        emit(q.p0 + q.axes * s.cwiseProduct(u), n.normalized());
      }
      return;
    }
  }
}

// Open-addressing hash of grid cells -> head of a linked list of kept samples.
class CellTable {
 public:
  explicit CellTable(size_t expected) {
    size_t n = 16;
    while (n < 2 * expected) n <<= 1;
    keys_.assign(n, kEmpty);
    heads_.assign(n, -1);
    mask_ = n - 1;
  }
  static uint64_t key(int64_t x, int64_t y, int64_t z) {
    constexpr int64_t kOff = int64_t(1) << 20;  // 21 bits per axis: +-1e6 cells
    return (uint64_t(x + kOff) << 42) | (uint64_t(y + kOff) << 21) | uint64_t(z + kOff);
  }
  // Slot of `k`; inserted (head -1) if absent and `insert`, else SIZE_MAX when absent.
  size_t find(uint64_t k, bool insert) {
    size_t i = (k * 0x9E3779B97F4A7C15ull) >> 20 & mask_;
    while (true) {
      if (keys_[i] == k) return i;
      if (keys_[i] == kEmpty) {
        if (!insert) return SIZE_MAX;
        keys_[i] = k;
        return i;
      }
      i = (i + 1) & mask_;
    }
  }
  int32_t& head(size_t slot) { return heads_[slot]; }
  // Call before each insertion: keeps the load <= 1/2 (the table cannot fill up).
  void reserveOneMore() {
    if (2 * (++count_) <= keys_.size()) return;
    std::vector<uint64_t> keys = std::move(keys_);
    std::vector<int32_t> heads = std::move(heads_);
    keys_.assign(2 * keys.size(), kEmpty);
    heads_.assign(2 * keys.size(), -1);
    mask_ = keys_.size() - 1;
    for (size_t i = 0; i < keys.size(); ++i)
      if (keys[i] != kEmpty) heads_[find(keys[i], true)] = heads[i];
  }

 private:
  static constexpr uint64_t kEmpty = ~uint64_t(0);
  std::vector<uint64_t> keys_;
  std::vector<int32_t> heads_;
  size_t mask_ = 0;
  size_t count_ = 0;
};

}  // namespace

SurfaceSamples sampleSkinSurface(const std::vector<Primitive>& person,
                                 const Eigen::AlignedBox3d& box, const SurfaceSampleOptions& o) {
  if (!(o.spacing > 0.0) || !std::isfinite(o.spacing))
    throw std::invalid_argument("sampleSkinSurface: spacing must be > 0, got " +
                                std::to_string(o.spacing));
  SurfaceSamples out;
  if (box.isEmpty()) return out;
  Eigen::AlignedBox3d region = box;
  if (o.above_desk) {
    region.min().z() = std::max(region.min().z(), 0.0);
    if (region.isEmpty()) return out;
  }

  // Only primitives touching the region can emit or hide a sample in it.
  std::vector<int> near;
  for (size_t i = 0; i < person.size(); ++i)
    if (person[i].bounds().intersects(region)) near.push_back(int(i));

  const double density = kOversample / (o.spacing * o.spacing);
  auto strictlyInsideAny = [&](const Vector3d& p, int self, bool skin, bool clothing) {
    for (int j : near)
      if (j != self && (isSkin(person[j].material) ? skin : clothing) &&
          strictlyInside(person[j], p))
        return true;
    return false;
  };

  // Clothing that can touch skin (only its faces inside skin count) and, per face of the
  // region, the rectangles where skin primitives' bounds cross it (cut faces are sampled there).
  std::vector<int> clothing;
  if (o.clothing_interface)
    for (int j : near) {
      if (isSkin(person[j].material)) continue;
      const Eigen::AlignedBox3d b = person[j].bounds();
      for (int i : near)
        if (isSkin(person[i].material) && person[i].bounds().intersects(b)) {
          clothing.push_back(j);
          break;
        }
    }
  struct FaceRect {
    int axis;                  // the face's normal axis
    double sign;               // -1: the region's min face, +1: its max face
    double coord;              // plane coordinate
    Eigen::AlignedBox2d rect;  // in the other two axes, (axis + 1) % 3 then (axis + 2) % 3
    int face;                  // 0..5, rectangles of one face are consecutive
  };
  std::vector<FaceRect> rects;
  if (o.box_faces)
    for (int face = 0; face < 6; ++face) {
      const int a = face / 2, b = (a + 1) % 3, c = (a + 2) % 3;
      const double sign = face % 2 ? 1.0 : -1.0;
      const double x = face % 2 ? region.max()[a] : region.min()[a];
      const Eigen::AlignedBox2d whole(Eigen::Vector2d(region.min()[b], region.min()[c]),
                                      Eigen::Vector2d(region.max()[b], region.max()[c]));
      for (int i : near) {
        const Eigen::AlignedBox3d pb = person[i].bounds();
        if (!isSkin(person[i].material) || pb.min()[a] > x || pb.max()[a] < x) continue;
        const Eigen::AlignedBox2d r = whole.intersection(Eigen::AlignedBox2d(
            Eigen::Vector2d(pb.min()[b], pb.min()[c]), Eigen::Vector2d(pb.max()[b], pb.max()[c])));
        if (!r.isEmpty()) rects.push_back({a, sign, x, r, face});
      }
    }

  double expected = 0.0;
  for (int i : near)
    if (isSkin(person[i].material)) expected += expectedCandidates(person[i], density);
  for (int j : clothing) expected += expectedCandidates(person[j], density);
  for (const FaceRect& f : rects) expected += density * f.rect.volume();
  if (expected > kMaxCandidates)
    throw std::invalid_argument("sampleSkinSurface: spacing " + std::to_string(o.spacing) +
                                " m needs " + std::to_string(expected) + " candidates (limit " +
                                std::to_string(kMaxCandidates) + ")");

  // 1 + 2: candidates on each skin primitive, kept where visible.
  std::vector<Candidate> cand;
  for (int i : near) {
    const Primitive& q = person[i];
    if (!isSkin(q.material)) continue;
    Rng rng(o.seed, uint32_t(i));
    sampleSurface(q, density, rng, [&](const Vector3d& p, const Vector3d& n) {
      if (region.contains(p) && !strictlyInsideAny(p, i, true, true)) cand.push_back({p, n});
    });
  }
  // Options: the clothing's faces inside skin (normal into the clothing = out of the skin
  // solid), and the region's faces where they cut the skin solid.
  for (int j : clothing) {
    Rng rng(o.seed, uint32_t(j));
    sampleSurface(person[j], density, rng, [&](const Vector3d& p, const Vector3d& n) {
      if (region.contains(p) && strictlyInsideAny(p, j, true, false) &&
          !strictlyInsideAny(p, j, false, true))
        cand.push_back({p, -n});
    });
  }
  for (size_t k = 0; k < rects.size(); ++k) {
    const FaceRect& f = rects[k];
    const int b = (f.axis + 1) % 3, c = (f.axis + 2) % 3;
    Rng rng(o.seed, 0x80000000u + uint32_t(k));
    const long n = std::lround(density * f.rect.volume());
    for (long m = 0; m < n; ++m) {
      const Eigen::Vector2d uv =
          f.rect.min() + f.rect.sizes().cwiseProduct(Eigen::Vector2d(rng.uniform(), rng.uniform()));
      // Overlapping rectangles of one face: each point belongs to the first that holds it.
      bool earlier = false;
      for (size_t e = k; e-- > 0 && rects[e].face == f.face && !earlier;)
        earlier = rects[e].rect.contains(uv);
      if (earlier) continue;
      Vector3d p;
      p[f.axis] = f.coord;
      p[b] = uv.x();
      p[c] = uv.y();
      bool in_skin = false;
      for (int i : near)
        if (isSkin(person[i].material) && person[i].contains(p)) in_skin = true;
      if (!in_skin || strictlyInsideAny(p, -1, false, true)) continue;
      cand.push_back({p, f.sign * Vector3d::Unit(f.axis)});
    }
  }
  out.area = double(cand.size()) / density;
  if (cand.empty()) return out;

  // 3: random sequential adsorption in a shuffled order (Fisher-Yates).
  Rng shuffle_rng(o.seed, 0xffffffffu);
  for (size_t k = cand.size() - 1; k > 0; --k) std::swap(cand[k], cand[shuffle_rng.below(k + 1)]);
  const double r = kDiskRadius * o.spacing, r2 = r * r;
  const double cell = 2.0 * r;  // a ball of radius r spans at most 2 cells per axis
  CellTable table(cand.size() / 16 + 16);
  std::vector<int32_t> next;  // linked lists of kept samples per cell
  std::vector<const Candidate*> kept;
  kept.reserve(size_t(cand.size() / kOversample * 1.2));
  next.reserve(kept.capacity());
  for (const Candidate& c : cand) {
    const Eigen::Vector3d lo = ((c.p.array() - r) / cell).floor().matrix();
    const int64_t x0 = int64_t(lo.x()), y0 = int64_t(lo.y()), z0 = int64_t(lo.z());
    bool blocked = false;
    for (int dz = 0; dz < 2 && !blocked; ++dz)
      for (int dy = 0; dy < 2 && !blocked; ++dy)
        for (int dx = 0; dx < 2 && !blocked; ++dx) {
          const size_t slot = table.find(CellTable::key(x0 + dx, y0 + dy, z0 + dz), false);
          if (slot == SIZE_MAX) continue;
          for (int32_t k = table.head(slot); k >= 0; k = next[k])
            if ((kept[k]->p - c.p).squaredNorm() < r2 && kept[k]->n.dot(c.n) > 0.0) {
              blocked = true;
              break;
            }
        }
    if (blocked) continue;
    const Eigen::Vector3d ci = (c.p / cell).array().floor().matrix();
    const uint64_t key = CellTable::key(int64_t(ci.x()), int64_t(ci.y()), int64_t(ci.z()));
    size_t slot = table.find(key, false);
    if (slot == SIZE_MAX) {
      table.reserveOneMore();
      slot = table.find(key, true);
    }
    next.push_back(table.head(slot));
    table.head(slot) = int32_t(kept.size());
    kept.push_back(&c);
  }

  out.points.reserve(kept.size());
  out.normals.reserve(kept.size());
  for (const Candidate* c : kept) {
    out.points.push_back(c->p.cast<float>());
    out.normals.push_back(c->n.cast<float>());
  }
  return out;
}

}  // namespace tabletop_sim
