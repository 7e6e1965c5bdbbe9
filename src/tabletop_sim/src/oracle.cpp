#include "tabletop_sim/oracle.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace tabletop_sim {

using Eigen::Vector3d;

Oracle::Oracle(std::vector<Primitive> person, const Vector3d& head_centre,
               std::shared_ptr<const Scene> scene)
    : person_(std::move(person)), head_(head_centre), scene_(std::move(scene)) {
  spheres_.reserve(person_.size());
  for (const Primitive& p : person_) {
    Vector3d c;
    double r;
    p.boundingSphere(&c, &r);
    spheres_.emplace_back(c.x(), c.y(), c.z(), r * r);
  }
}

bool Oracle::insidePerson(const Vector3d& p) const {
  for (size_t i = 0; i < person_.size(); ++i)
    if ((p - spheres_[i].head<3>()).squaredNorm() <= spheres_[i].w() && person_[i].contains(p))
      return true;
  return false;
}

bool Oracle::insideSkin(const Vector3d& p) const {
  bool skin = false;
  for (size_t i = 0; i < person_.size(); ++i) {
    if ((p - spheres_[i].head<3>()).squaredNorm() > spheres_[i].w() || !person_[i].contains(p))
      continue;
    if (!isSkin(person_[i].material)) return false;
    skin = true;
  }
  return skin;
}

bool Oracle::insidePart(const Vector3d& p, BodyPart part) const {
  for (size_t i = 0; i < person_.size(); ++i)
    if (person_[i].part == part && person_[i].contains(p)) return true;
  return false;
}

void Oracle::sampleGrid(const Vector3d& origin, double voxel_size, const Eigen::Vector3i& dims,
                        std::vector<uint8_t>* person, std::vector<uint8_t>* skin,
                        int threads) const {
  const size_t n = size_t(std::max(0, dims.x())) * size_t(std::max(0, dims.y())) *
                   size_t(std::max(0, dims.z()));
  if (person) person->assign(n, 0);
  if (skin) skin->assign(n, 0);
  if (n == 0 || person_.empty() || !(voxel_size > 0)) return;
  // Voxel index range of the union of the bounding spheres.
  Vector3d lo = Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (const auto& s : spheres_) {
    const double r = std::sqrt(s.w());
    lo = lo.cwiseMin(s.head<3>() - Vector3d::Constant(r));
    hi = hi.cwiseMax(s.head<3>() + Vector3d::Constant(r));
  }
  Eigen::Vector3i a, b;
  for (int k = 0; k < 3; ++k) {
    a[k] = std::max(0, static_cast<int>(std::floor((lo[k] - origin[k]) / voxel_size)));
    b[k] = std::min(dims[k], static_cast<int>(std::ceil((hi[k] - origin[k]) / voxel_size)) + 1);
  }
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads > 0 ? threads : omp_get_max_threads())
  for (int z = a.z(); z < b.z(); ++z)
    for (int y = a.y(); y < b.y(); ++y)
      for (int x = a.x(); x < b.x(); ++x) {
        const Vector3d p = origin + voxel_size * Vector3d(x + 0.5, y + 0.5, z + 0.5);
        const size_t i = size_t(x) + size_t(dims.x()) * (size_t(y) + size_t(dims.y()) * size_t(z));
        if (person) (*person)[i] = insidePerson(p);
        if (skin) (*skin)[i] = insideSkin(p);
      }
}

Vector3d Oracle::handCentroid(Side side) const { return tabletop_sim::handCentroid(person_, side); }

bool Oracle::occluded(const tabletop_capture::CameraModel& camera, const Vector3d& p, BodyPart part) const {
  const Vector3d o = camera.center();
  const Vector3d v = p - o;
  const double dist = v.norm();
  if (dist <= 0.0) return false;
  const Vector3d d = v / dist;
  double best = std::numeric_limits<double>::infinity();
  int best_prim = -1;
  for (size_t i = 0; i < person_.size(); ++i) {
    double t;
    if (person_[i].intersect(o, d, &t) && t < best) {
      best = t;
      best_prim = static_cast<int>(i);
    }
  }
  if (scene_) {
    SceneHit hit;
    if (scene_->intersect(o, d, std::min(best, dist), &hit)) return true;  // static occluder
  }
  if (best_prim < 0 || best > dist) return false;
  return person_[best_prim].part != part;
}

}  // namespace tabletop_sim
