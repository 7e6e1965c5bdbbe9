#include "hand_tracking/arm_geodesic.h"

#include <algorithm>
#include <cmath>
#include <queue>
#include <utility>
#include <vector>

namespace hand_tracking {
namespace {
constexpr double kRamp = 0.05;       // m of length over which a blob becomes fully an arm
constexpr double kEndSlice = 0.03;   // m: the voxels this near an end locate it
constexpr double kDirectionFrom = 0.06, kDirectionTo = 0.10;  // m: the arm's direction at an end
constexpr float kUnreached = std::numeric_limits<float>::infinity();
constexpr double kNoLimit = 1e9;  // m: walks within the blob need no reach

// The walkable voxels of a box of the grid (a list: skin is a few thousand of the grid's
// 200k voxels) and geodesic distances over their 26-neighbourhood.
class BlobWalk {
 public:
  BlobWalk(const psfs::ProbabilityVolume& v, uint8_t thr, const Eigen::Vector3i& lo,
           const Eigen::Vector3i& hi, const VoxelFilter& mine)
      : g_(v.grid) {
    const psfs::VoxelGrid& g = v.grid;
    slot_.assign(g.numVoxels(), -1);
    for (int z = lo.z(); z < hi.z(); ++z)
      for (int y = lo.y(); y < hi.y(); ++y) {
        const uint8_t* row = v.data.data() + g.index(0, y, z);
        for (int x = lo.x(); x < hi.x(); ++x) {
          if (row[x] <= thr) continue;
          const Eigen::Vector3d p = g.centre(x, y, z);
          if (mine && !mine(p)) continue;
          slot_[g.index(x, y, z)] = int32_t(voxel_.size());
          voxel_.emplace_back(x, y, z);
          centre_.push_back(p);
          weight_.push_back(row[x]);
        }
      }
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx)
          if (dx || dy || dz)
            steps_.push_back(
                {Eigen::Vector3i(dx, dy, dz),
                 float(g.voxel_size * std::sqrt(double(dx * dx + dy * dy + dz * dz)))});
  }
  size_t size() const { return voxel_.size(); }
  const Eigen::Vector3d& centre(size_t i) const { return centre_[i]; }
  double weight(size_t i) const { return weight_[i]; }
  // Dijkstra from voxel `from` up to `reach` (m); where `only` is given, only the voxels it
  // reached are walked.
  std::vector<float> distances(size_t from, double reach, const std::vector<float>* only) const {
    std::vector<float> d(voxel_.size(), kUnreached);
    using Item = std::pair<float, uint32_t>;
    std::priority_queue<Item, std::vector<Item>, std::greater<Item>> q;
    d[from] = 0.f;
    q.push({0.f, uint32_t(from)});
    while (!q.empty()) {
      const auto [dist, i] = q.top();
      q.pop();
      if (dist > d[i]) continue;
      for (const Step& s : steps_) {
        const Eigen::Vector3i n = voxel_[i] + s.offset;
        if ((n.array() < 0).any() || (n.array() >= g_.dims.array()).any()) continue;
        const int32_t j = slot_[g_.index(n.x(), n.y(), n.z())];
        if (j < 0 || (only && !std::isfinite((*only)[j]))) continue;
        const float nd = dist + s.cost;
        if (nd < d[j] && nd <= reach) {
          d[j] = nd;
          q.push({nd, uint32_t(j)});
        }
      }
    }
    return d;
  }

 private:
  struct Step {
    Eigen::Vector3i offset;
    float cost;
  };
  const psfs::VoxelGrid& g_;
  std::vector<int32_t> slot_;  // grid index -> walkable voxel, -1: none
  std::vector<Eigen::Vector3i> voxel_;
  std::vector<Eigen::Vector3d> centre_;
  std::vector<float> weight_;
  std::vector<Step> steps_;
};

// The reached voxel farthest from the walk's start (the start itself has distance 0).
size_t farthest(const std::vector<float>& d) {
  size_t best = 0;
  float best_d = -1.f;
  for (size_t i = 0; i < d.size(); ++i)
    if (std::isfinite(d[i]) && d[i] > best_d) best_d = d[i], best = i;
  return best;
}

// Weighted mean of the voxels whose distance along the skin lies in [from, to] (NaN: none).
Eigen::Vector3d meanInBand(const BlobWalk& w, const std::vector<float>& d, double from, double to) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  double mass = 0.0;
  for (size_t i = 0; i < d.size(); ++i)
    if (d[i] >= from && d[i] <= to) sum += w.weight(i) * w.centre(i), mass += w.weight(i);
  return mass > 0.0 ? Eigen::Vector3d(sum / mass) : Eigen::Vector3d::Constant(std::nan(""));
}
Eigen::Vector3d meanNear(const BlobWalk& w, const std::vector<float>& d, double upto) {
  return meanInBand(w, d, 0.0, upto);
}
// The arm's direction at an end (unit, outwards): from the voxels 6-10 cm in to the end.
Eigen::Vector3d outwards(const BlobWalk& w, const std::vector<float>& d,
                         const Eigen::Vector3d& end) {
  const Eigen::Vector3d inside = meanInBand(w, d, kDirectionFrom, kDirectionTo);
  if (!inside.allFinite()) return Eigen::Vector3d::Zero();
  const Eigen::Vector3d dir = end - inside;
  return dir.norm() > 1e-9 ? Eigen::Vector3d(dir.normalized()) : Eigen::Vector3d::Zero();
}
}  // namespace

ArmEnd armHandEnd(const psfs::ProbabilityVolume& skin, uint8_t threshold,
                  const Eigen::Vector3d& start, double start_radius, const VoxelFilter& filter,
                  const ArmWalkParams& params, const Eigen::Vector3d& head,
                  const ForeignBodyProbe& foreign, const Eigen::Vector3d* previous_hand_end) {
  ArmEnd out;
  const psfs::VoxelGrid& g = skin.grid;
  if (skin.data.size() != g.numVoxels() || !(g.voxel_size > 0.0) || !start.allFinite() ||
      !(params.reach > 0.0))
    return out;
  Eigen::Vector3i lo, hi;
  for (int a = 0; a < 3; ++a) {
    lo[a] = std::max(0, int(std::floor((start[a] - params.reach - g.origin[a]) / g.voxel_size)));
    hi[a] = std::min(g.dims[a],
                     int(std::ceil((start[a] + params.reach - g.origin[a]) / g.voxel_size)) + 1);
    if (hi[a] <= lo[a]) return out;
  }
  const BlobWalk walk(skin, threshold, lo, hi, filter);
  size_t seed = walk.size();
  double best_sq = start_radius * start_radius;
  for (size_t i = 0; i < walk.size(); ++i) {
    const double d_sq = (walk.centre(i) - start).squaredNorm();
    if (d_sq < best_sq || (d_sq == best_sq && seed == walk.size())) best_sq = d_sq, seed = i;
  }
  if (seed == walk.size()) return out;
  // The blob: what the walk reaches from the start. Its ends: the voxel farthest from the start,
  // and the one farthest from that.
  const std::vector<float> from_seed = walk.distances(seed, params.reach, nullptr);
  const size_t a = farthest(from_seed);
  const std::vector<float> from_a = walk.distances(a, kNoLimit, &from_seed);
  const size_t b = farthest(from_a);
  const double length = from_a[b];
  size_t count = 0;
  for (float d : from_seed) count += std::isfinite(d);
  out.length = length;
  out.cross_section = count * std::pow(g.voxel_size, 3) / std::max(length, g.voxel_size);
  if (length <= params.min_arm_length || length > params.max_length ||
      out.cross_section > params.max_cross_section)
    return out;
  const std::vector<float> from_b = walk.distances(b, kNoLimit, &from_seed);
  const Eigen::Vector3d end_a = meanNear(walk, from_a, kEndSlice);
  const Eigen::Vector3d end_b = meanNear(walk, from_b, kEndSlice);
  bool hand_is_a = (end_a - head).norm() > (end_b - head).norm();  // 4. away from the head
  if (previous_hand_end && previous_hand_end->allFinite()) {  // 3. where the hand was
    const double da = (end_a - *previous_hand_end).norm(), db = (end_b - *previous_hand_end).norm();
    if (std::min(da, db) < params.continuity_radius && std::abs(da - db) > params.continuity_margin)
      hand_is_a = da < db;
  }
  if (foreign) {  // 2. the sleeve goes on past the arm's root
    const double fa = foreign(end_a + params.beyond * outwards(walk, from_a, end_a));
    const double fb = foreign(end_b + params.beyond * outwards(walk, from_b, end_b));
    if (std::abs(fa - fb) > kForeignMargin) hand_is_a = fa < fb;
  }
  const double ahead = (end_a - end_b).dot(params.frontal);  // 1. the hands are in front
  if (std::abs(ahead) > params.frontal_margin) hand_is_a = ahead > 0.0;
  out.hand_end = hand_is_a ? end_a : end_b;
  out.other_end = hand_is_a ? end_b : end_a;
  out.centroid = meanNear(walk, hand_is_a ? from_a : from_b, params.hand_length);
  out.arm_weight = out.centroid.allFinite()
                       ? std::min(1.0, (length - params.min_arm_length) / kRamp)
                       : 0.0;
  return out;
}

}  // namespace hand_tracking
