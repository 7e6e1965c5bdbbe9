#include "tabletop_capture/sim/oracle.h"

#include <limits>

namespace tabletop_capture {
namespace sim {

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

Vector3d Oracle::handCentroid(Side side) const { return sim::handCentroid(person_, side); }

bool Oracle::occluded(const CameraModel& camera, const Vector3d& p, BodyPart part) const {
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

}  // namespace sim
}  // namespace tabletop_capture
