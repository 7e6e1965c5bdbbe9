#include "body_tracking/arm_length.h"

#include <algorithm>
#include <vector>

#include "body_tracking/arm_ik.h"
#include "body_tracking/body_parts.h"
#include "body_tracking/kinematics.h"
#include "scored_parts.h"

namespace body_tracking {

namespace {

using Eigen::Vector3d;

// Where a re-posed arm may put its hand besides the found one: the tracked hand slid along the
// forearm (m), so the vote does not hang on the found hand alone (on short sleeves a model arm
// too short cuts the hand's skin behind the true wrist and the forearm's skin pulls it back).
constexpr double kSlides[] = {-0.04, -0.02, 0.0, 0.02, 0.04};
constexpr double kMargin = 0.12;  // m around the tracked arm's box: what a longer arm could reach
// The hand's neighbourhood is left out (m around the found hand): the model's hand ellipsoid
// ends 12 cm beyond the wrist, an open hand's fingers 17-19 cm, so covering the fingers read
// the arms ~8 % long (generated people, 10 scenarios; 5 % with the hand left out).
constexpr double kHandClearance = 0.10;

// The arm's parts are consecutive in Part: upper arm, forearm, hand.
int firstArmPart(Side side) {
  return static_cast<int>(side == Side::LEFT ? Part::LEFT_UPPER_ARM : Part::RIGHT_UPPER_ARM);
}

bool holds(const TruncatedQuadric& q, const Vector3d& c) { return q.bounds.contains(c) && q.contains(c); }

struct Voxel {
  Vector3d centre;
  float p;
};

// The arm's neighbourhood: voxels within kMargin of the tracked arm's parts' box, away from the
// hand, that the trunk and the other arm (as tracked) do not hold, with their occupancy
// 2p - 1 clipped at 0: the pSfS halo (p just above 0.5 around the body) would read as arm and
// make longer arms win (soft p: factors 0.06-0.11 long on generated people).
std::vector<Voxel> armRegion(const VolumeObservation& obs, const BodyParts& tracked, Side side,
                             const Vector3d& hand) {
  const int first = firstArmPart(side);
  Eigen::AlignedBox3d box;
  for (int k = first; k < first + 3; ++k) box.extend(tracked[k].bounds);
  box.min().array() -= kMargin;
  box.max().array() += kMargin;
  std::vector<const TruncatedQuadric*> others;
  for (int k = 0; k < kNumParts; ++k)
    if (k < first || k >= first + 3) others.push_back(&tracked[k]);
  const psfs::VoxelGrid& g = obs.grid();
  const std::vector<float>& body = obs.bodyLikelihood();
  std::vector<Voxel> out;
  Eigen::Vector3i lo, hi;  // the voxels around the box, not the whole grid
  if (!g.voxelRange(box.min(), box.max(), &lo, &hi)) return out;
  for (int z = lo.z(); z <= hi.z(); ++z)
    for (int y = lo.y(); y <= hi.y(); ++y)
      for (int x = lo.x(); x <= hi.x(); ++x) {
        const Vector3d c = g.centre(x, y, z);
        if (!box.contains(c) || (c - hand).norm() < kHandClearance) continue;
        bool held = false;
        for (const TruncatedQuadric* q : others) held = held || holds(*q, c);
        if (!held) out.push_back({c, std::max(0.0f, 2.0f * body[g.index(x, y, z)] - 1.0f)});
      }
  return out;
}

// How well an arm's upper arm and forearm match the region's occupancy: the F1 measure with soft
// counts, 2 TP / (inside + occupied). The filter's observation (a mean inside each part) does
// not see an arm too short: the shortened parts still lie inside the arm, and shorter arms won
// (generated people: 1.08 -> 0.90); the occupied voxels they leave uncovered do.
double armF1(const std::vector<Voxel>& region, double occupied, const BodyParts& parts, Side side) {
  const int first = firstArmPart(side);
  const TruncatedQuadric &upper = parts[first], &fore = parts[first + 1];
  double tp = 0, inside = 0;
  for (const Voxel& v : region)
    if (holds(upper, v.centre) || holds(fore, v.centre)) {
      tp += v.p;
      inside += 1;
    }
  return inside + occupied > 0 ? 2.0 * tp / (inside + occupied) : 0.0;
}

}  // namespace

ArmLength::ArmLength(const ArmLengthParams& params)
    : params_((params.validate(), params)), ladder_(params_) {}

BodyProfile ArmLength::scaled(const BodyProfile& base, double factor) {
  BodyProfile p = base;
  p.upper_arm *= factor;
  p.forearm *= factor;
  return p;
}

void ArmLength::add(const VolumeObservation& obs, const BodyProfile& base, const BodyState& state,
                    const RefinedHands& hands) {
  if (!refining() || (!hands.from_skin[0] && !hands.from_skin[1])) return;
  const BodyProfile in_use = scaled(base, factor());
  const BodyFrames tracked = forwardKinematics(in_use, state);
  const BodyParts tracked_parts = buildParts(in_use, tracked);
  bool voted = false;
  for (Side side : {Side::LEFT, Side::RIGHT}) {
    const int i = static_cast<int>(side);
    if (!hands.from_skin[i]) continue;  // no hand found: the arm may be out of sight
    const std::vector<Voxel> region = armRegion(obs, tracked_parts, side, hands.position[i]);
    double occupied = 0;
    for (const Voxel& v : region) occupied += v.p;
    std::vector<Vector3d> targets{hands.position[i]};
    const Vector3d along = (tracked.hand[i] - tracked.elbow[i]).normalized();
    for (double d : kSlides) targets.push_back(tracked.hand[i] + d * along);
    for (size_t k = 0; k < ladder_.factors().size(); ++k) {
      const BodyProfile p = scaled(base, ladder_.factors()[k]);
      double best = 0;
      for (const Vector3d& t : targets) {
        BodyState s = state;
        solveArmIk(p, side, t, tracked.elbow[i], &s);
        limits_.enforce(&s, armDof(side, 0), 5);
        BodyParts parts;
        if (buildScoredParts(p, s, 1 + i, &parts)) continue;  // self-colliding
        best = std::max(best, armF1(region, occupied, parts, side));
      }
      ladder_.add(k, best);
      voted = voted || best > 0;  // an arm all of whose poses collide or miss says nothing
    }
  }
  if (voted) ladder_.endFrame();
}

}  // namespace body_tracking
