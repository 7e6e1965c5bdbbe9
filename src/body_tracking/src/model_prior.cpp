#include "body_tracking/model_prior.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

namespace body_tracking {

std::vector<TruncatedQuadric> priorSolids(const BodyProfile& profile, const BodyFrames& frames,
                                          const ModelPriorParams& params) {
  if (!(params.neck_radius >= 0 && params.neck_radius < 1) || !(params.hand_reach >= 0 && params.hand_reach < 1))
    throw std::invalid_argument("priorSolids: neck_radius and hand_reach must be in [0, 1) m");
  const BodyParts parts = buildParts(profile, frames);
  std::vector<TruncatedQuadric> solids(parts.begin(), parts.end());
  if (params.hand_reach > 0) {
    // Beside the tracked hand (not instead: a longer ellipsoid is narrower near the wrist), from
    // its wrist end to hand_reach beyond its far end, as wide across as it is along x.
    for (Side s : {Side::LEFT, Side::RIGHT}) {
      const TruncatedQuadric& hand = parts[static_cast<int>(handPart(s))];
      const double half = 0.5 * params.hand_reach;
      solids.push_back(TruncatedQuadric::ellipsoid(
          hand.frame * Eigen::Translation3d(0, half, 0),
          Eigen::Vector3d(hand.semi.x(), hand.semi.y() + half, hand.semi.x())));
    }
  }
  if (params.neck_radius > 0) {
    // The head frame's origin is the neck pivot, its z the head's axis; the cylinder's axis is
    // its local y (a quarter turn about x puts it on z), from the shoulders' height (inside
    // the chest) to the head's centre height (inside the head).
    const double below = profile.neck_height - profile.shoulder_height;
    const Eigen::Isometry3d start = frames.head * Eigen::Translation3d(0, 0, -below) *
                                    Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitX());
    solids.push_back(TruncatedQuadric::cylinder(start, below + profile.head_centre_height,
                                                params.neck_radius, params.neck_radius));
  }
  return solids;
}

void applyModelPrior(const psfs::ProbabilityVolume& body, const BodyParts& parts,
                     const ModelPriorParams& params, psfs::ProbabilityVolume* out) {
  applyModelPrior(body, std::vector<TruncatedQuadric>(parts.begin(), parts.end()), params, out);
}

void applyModelPrior(const psfs::ProbabilityVolume& body, const std::vector<TruncatedQuadric>& solids,
                     const ModelPriorParams& params, psfs::ProbabilityVolume* out) {
  if (!out || out == &body) throw std::invalid_argument("applyModelPrior: out must be another volume");
  if (!std::isfinite(params.offset) || !std::isfinite(params.falloff) || !(params.falloff > 0))
    throw std::invalid_argument("applyModelPrior: offset must be finite and falloff > 0");
  const psfs::VoxelGrid& g = body.grid;
  if (body.data.size() != g.numVoxels())
    throw std::invalid_argument("applyModelPrior: the volume's data does not fill its grid");
  out->grid = g;
  out->data.assign(body.data.size(), 0);
  // Beyond this distance even byte 255 (p = 254.5/255) maps below 0.5/255:
  // logit(254.5/255) + logit(1 - 0.5/255) = 2 ln(509) units of log-odds. Not below 0: the
  // elliptic parts' ray distance can read deeper than the true one inside.
  const double reach = std::max(0.0, params.offset + 2.0 * std::log(509.0) * params.falloff);
  // Nearest part's distance per voxel, part by part within its box grown by `reach` (a trunk's
  // box is ~13 000 voxels at 16 mm, a hand's ~2 000: far fewer than the grid's).
  std::vector<float> dist(body.data.size(), std::numeric_limits<float>::infinity());
  for (const TruncatedQuadric& part : solids) {
    Eigen::Vector3i lo, hi;  // none for a part off the grid or with non-finite bounds
    const Eigen::Vector3d grow = Eigen::Vector3d::Constant(reach);
    if (!g.voxelRange(part.bounds.min() - grow, part.bounds.max() + grow, &lo, &hi)) continue;
    const Eigen::Isometry3d to_local = part.frame.inverse();
    for (int z = lo.z(); z <= hi.z(); ++z)
      for (int y = lo.y(); y <= hi.y(); ++y)
        for (int x = lo.x(); x <= hi.x(); ++x) {
          const size_t i = g.index(x, y, z);
          dist[i] = std::min(dist[i], float(localSignedDistance(part, to_local * g.centre(x, y, z))));
        }
  }
  for (size_t i = 0; i < body.data.size(); ++i) {
    const uint8_t v = body.data[i];
    const double penalty = (double(dist[i]) - params.offset) / params.falloff;  // +inf: no part near
    if (!(penalty > 0)) {
      out->data[i] = v;
      continue;
    }
    if (v == 0 || std::isinf(penalty)) continue;  // stays 0
    const double pv = std::min(double(v), 254.5) / 255.0;
    const double l = std::log(pv / (1.0 - pv)) - penalty;
    out->data[i] = static_cast<uint8_t>(std::lround(255.0 / (1.0 + std::exp(-l))));
  }
}

}  // namespace body_tracking
