#include "hand_tracking/head_model.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Dense>

namespace hand_tracking {
namespace {

void fail(const std::string& field, const std::string& why) {
  throw std::invalid_argument("HeadModelParams." + field + ": " + why);
}

// The body voxels of one z level inside the vertical cylinder (axis, radius): their area
// (m^2, each voxel weighted by its probability) and first moments in x and y.
struct Level {
  double area = 0.0, sx = 0.0, sy = 0.0;
};

Level levelAt(const psfs::ProbabilityVolume& v, int z, const Eigen::Vector2d& axis, double radius,
              uint8_t thr) {
  const psfs::VoxelGrid& g = v.grid;
  const double s = g.voxel_size;
  Level l;
  const int x0 = std::max(0, int(std::floor((axis.x() - radius - g.origin.x()) / s)));
  const int x1 = std::min(g.dims.x() - 1, int(std::floor((axis.x() + radius - g.origin.x()) / s)));
  const int y0 = std::max(0, int(std::floor((axis.y() - radius - g.origin.y()) / s)));
  const int y1 = std::min(g.dims.y() - 1, int(std::floor((axis.y() + radius - g.origin.y()) / s)));
  const double r2 = radius * radius;
  for (int y = y0; y <= y1; ++y) {
    const double wy = g.origin.y() + (y + 0.5) * s;
    const uint8_t* row = v.data.data() + g.index(0, y, z);
    for (int x = x0; x <= x1; ++x) {
      if (row[x] <= thr) continue;
      const double wx = g.origin.x() + (x + 0.5) * s;
      if ((wx - axis.x()) * (wx - axis.x()) + (wy - axis.y()) * (wy - axis.y()) > r2) continue;
      const double p = row[x] / 255.0;
      l.area += p;
      l.sx += p * wx;
      l.sy += p * wy;
    }
  }
  l.area *= s * s;
  l.sx *= s * s;
  l.sy *= s * s;
  return l;
}

}  // namespace

void HeadModelParams::validate() const {
  auto positive = [](double v, const char* f) {
    if (!(v > 0.0 && std::isfinite(v))) fail(f, "must be > 0");
  };
  positive(radius, "radius");
  positive(max_above, "max_above");
  positive(fit_depth, "fit_depth");
  positive(min_top_area, "min_top_area");
  if (!(threshold >= 0.0 && threshold < 1.0)) fail("threshold", "must lie in [0, 1)");
  if (iterations < 1) fail("iterations", "must be >= 1");
  positive(top_above_centre, "top_above_centre");
  if (!(vertex_weight >= 0.0 && vertex_weight <= 1.0)) fail("vertex_weight", "must lie in [0, 1]");
  if (!(face_weight >= 0.0 && face_weight <= 1.0)) fail("face_weight", "must lie in [0, 1]");
}

HeadFit fitHeadCentre(const psfs::ProbabilityVolume& body, const Eigen::Vector3d& face,
                      const HeadModelParams& p) {
  HeadFit fit;
  fit.centre = face;
  const psfs::VoxelGrid& g = body.grid;
  const double s = g.voxel_size;
  if (!(s > 0.0) || body.data.size() != g.numVoxels() || !face.allFinite()) return fit;
  const uint8_t thr = psfs::thresholdByte(p.threshold);
  auto levelOf = [&](double z) { return int(std::floor((z - g.origin.z()) / s)); };
  auto levelZ = [&](int k) { return g.origin.z() + (k + 0.5) * s; };

  // Levels searched for the top: from max_above over the face down to the face.
  const int k_hi = std::min(g.dims.z() - 1, levelOf(face.z() + p.max_above));
  const int k_lo = std::max(0, levelOf(face.z()));
  if (k_hi < k_lo) return fit;

  Eigen::Vector2d axis = face.head<2>();
  int top = -1;
  const int axis_levels = std::max(1, int(std::lround(0.12 / s)));  // the blob's upper 12 cm
  for (int it = 0; it < p.iterations; ++it) {
    // Upwards from the face to the first level without a head's worth of area: the top of
    // the blob the face belongs to (a hand raised above the head, past a gap, is not it).
    top = -1;
    for (int k = k_lo; k <= k_hi; ++k) {
      if (levelAt(body, k, axis, p.radius, thr).area < p.min_top_area) break;
      top = k;
    }
    if (top < 0) return fit;  // no head there
    // No end to it: a tall person's head leaves the workspace at its top (fitted from the
    // levels there are); any other column that does not end is no head.
    if (top == k_hi && k_hi != g.dims.z() - 1) return fit;
    double a = 0.0, sx = 0.0, sy = 0.0;
    for (int k = top; k > top - axis_levels && k >= 0; --k) {
      const Level l = levelAt(body, k, axis, p.radius, thr);
      a += l.area, sx += l.sx, sy += l.sy;
    }
    if (!(a > 0.0)) return fit;
    axis = Eigen::Vector2d(sx / a, sy / a);
  }

  // Least-squares parabola A(z) = c0 + c1 u + c2 u^2 in u = z - z_top (well conditioned).
  const double z_top = levelZ(top);
  const int depth_levels = std::max(3, int(std::lround(p.fit_depth / s)));
  Eigen::Matrix3d ata = Eigen::Matrix3d::Zero();
  Eigen::Vector3d atb = Eigen::Vector3d::Zero();
  std::vector<double> areas;  // from the top level down
  for (int k = top; k > top - depth_levels && k >= 0; --k) {
    const double u = levelZ(k) - z_top;
    const Eigen::Vector3d row(1.0, u, u * u);
    areas.push_back(levelAt(body, k, axis, p.radius, thr).area);
    ata += row * row.transpose();
    atb += row * areas.back();
  }
  const int n = int(areas.size());
  // The top to a fraction of a level: the top level's area against the one below (a level
  // that is half full holds the crown's upper half-voxel). Whole levels would move the
  // top-based estimate in 8 mm steps from frame to frame.
  const double a_below = n > 1 ? areas[1] : 0.0;
  const double fill = a_below > 0.0 ? std::clamp(areas[0] / a_below, 0.0, 1.0) : 1.0;
  fit.top = z_top - 0.5 * s + fill * s;
  fit.levels = n;
  fit.clipped = top == g.dims.z() - 1;
  if (n < 3) return fit;  // a blob at the grid's floor: no head
  // A widest level among the fitted ones: a concave profile whose vertex lies in their range.
  const Eigen::Vector3d c = ata.ldlt().solve(atb);
  if (c.allFinite() && c[2] < 0.0) {
    const double u_vertex = -c[1] / (2.0 * c[2]);
    const double u_min = levelZ(top - n + 1) - z_top;
    if (u_vertex <= 0.0 && u_vertex >= u_min) fit.vertex = z_top + u_vertex;
  }
  const double from_top = fit.top - p.top_above_centre;
  double z;
  if (fit.clipped) {
    // The top is the workspace's ceiling, not the head's: the vertex or nothing. (A bound from
    // the ceiling, centre >= ceiling - top_above_centre, was tried for random-21, whose head's
    // top is above the workspace: 58 -> 33 mm, but it flips on and off with the face estimate,
    // max 74 mm; see docs/benchmarks.md.)
    if (!std::isfinite(fit.vertex)) return fit;
    z = fit.vertex;
  } else if (std::isfinite(fit.vertex)) {
    // Two estimates whose errors come from different things (the hull's shape below the
    // head's widest level; the hair's and the hull's extent above the head).
    z = p.vertex_weight * fit.vertex + (1.0 - p.vertex_weight) * from_top;
  } else {
    z = from_top;
    fit.from_top = true;
  }
  const Eigen::Vector2d xy = (1.0 - p.face_weight) * axis + p.face_weight * face.head<2>();
  fit.centre = Eigen::Vector3d(xy.x(), xy.y(), z);
  fit.ok = true;

  return fit;
}

}  // namespace hand_tracking
