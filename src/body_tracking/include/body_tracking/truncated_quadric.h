// A body part's solid: a quadric surface v^T Q v = 0 (v homogeneous, world frame) cut by up to
// two clipping planes (thesis 3.3, 5.2.2). Two shapes cover the model: elliptic cylinders
// truncated at both ends (trunk, limbs) and ellipsoids (head, hands). Q is scaled so that
// v^T Q v is -1 on the axis (cylinder) or at the centre (ellipsoid) and 0 on the surface; the
// observation weights voxels by 1 + v^T Q v (0 on the bone, 1 at the surface, thesis 5.2.3).
#pragma once

#include <array>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace body_tracking {

struct TruncatedQuadric {
  enum class Shape { CYLINDER, ELLIPSOID };

  Shape shape = Shape::ELLIPSOID;
  // Local frame: the ellipsoid's centre, or the cylinder's axis start, with the cylinder's axis
  // along local +y from 0 to `length`. semi = half extents along local x, y, z (a cylinder's
  // y entry is length / 2, its x and z the cross-section's half axes).
  Eigen::Isometry3d frame = Eigen::Isometry3d::Identity();
  Eigen::Vector3d semi = Eigen::Vector3d::Ones();
  double length = 0.0;  // cylinders only

  Eigen::Matrix4d Q = Eigen::Matrix4d::Identity();        // world homogeneous
  std::array<Eigen::Vector4d, 2> planes;                  // inside where planes[i].dot(v) >= 0
  int num_planes = 0;
  Eigen::AlignedBox3d bounds;                             // tight axis-aligned box (world)

  static TruncatedQuadric cylinder(const Eigen::Isometry3d& frame, double length, double half_x,
                                   double half_z);
  static TruncatedQuadric ellipsoid(const Eigen::Isometry3d& frame, const Eigen::Vector3d& semi);

  double algebraic(const Eigen::Vector3d& p) const {
    const Eigen::Vector4d v(p.x(), p.y(), p.z(), 1.0);
    return v.dot(Q * v);
  }
  bool withinPlanes(const Eigen::Vector3d& p) const {
    const Eigen::Vector4d v(p.x(), p.y(), p.z(), 1.0);
    for (int i = 0; i < num_planes; ++i)
      if (planes[i].dot(v) < 0) return false;
    return true;
  }
  bool contains(const Eigen::Vector3d& p) const { return algebraic(p) <= 0 && withinPlanes(p); }
  double volume() const;
  // Centre of the solid (world): the ellipsoid's centre, the cylinder's mid-axis point.
  Eigen::Vector3d centre() const;
};

// Approximate signed distance (m) from p to the part's surface, negative inside: exact on
// circular cylinders and spheres, along the ray from the axis or centre on elliptic ones (never
// shorter than the true distance outside); a cylinder's end caps count by their planes.
double signedDistance(const TruncatedQuadric& part, const Eigen::Vector3d& p);
// The same for q in the part's local frame (part.frame.inverse() * p): loops over many points
// transform once.
double localSignedDistance(const TruncatedQuadric& part, const Eigen::Vector3d& q);

}  // namespace body_tracking
