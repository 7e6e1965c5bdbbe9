#include "tabletop_sim/primitives.h"

#include <algorithm>
#include <cmath>

namespace tabletop_sim {

const char* materialName(Material m) {
  switch (m) {
    case Material::SKIN:
      return "skin";
    case Material::SHIRT:
      return "shirt";
    case Material::SLEEVE:
      return "sleeve";
    case Material::HAIR:
      return "hair";
    case Material::TROUSERS:
      return "trousers";
    case Material::SHOES:
      return "shoes";
    case Material::EYE:
      return "eye";
  }
  return "?";
}

const char* bodyPartName(BodyPart p) {
  switch (p) {
    case BodyPart::TORSO:
      return "torso";
    case BodyPart::NECK:
      return "neck";
    case BodyPart::HEAD:
      return "head";
    case BodyPart::LEFT_UPPER_ARM:
      return "left_upper_arm";
    case BodyPart::LEFT_FOREARM:
      return "left_forearm";
    case BodyPart::LEFT_HAND:
      return "left_hand";
    case BodyPart::RIGHT_UPPER_ARM:
      return "right_upper_arm";
    case BodyPart::RIGHT_FOREARM:
      return "right_forearm";
    case BodyPart::RIGHT_HAND:
      return "right_hand";
    case BodyPart::LEGS:
      return "legs";
  }
  return "?";
}

Primitive Primitive::sphere(const Eigen::Vector3d& c, double r, Material m, BodyPart p) {
  Primitive s;
  s.type = Type::SPHERE;
  s.p0 = c;
  s.radius = r;
  s.material = m;
  s.part = p;
  return s;
}

Primitive Primitive::capsule(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double r,
                             Material m, BodyPart p) {
  Primitive s;
  s.type = Type::CAPSULE;
  s.p0 = a;
  s.p1 = b;
  s.radius = r;
  s.material = m;
  s.part = p;
  return s;
}

Primitive Primitive::ellipsoid(const Eigen::Vector3d& c, const Eigen::Matrix3d& axes,
                               const Eigen::Vector3d& semi, Material m, BodyPart p) {
  Primitive s;
  s.type = Type::ELLIPSOID;
  s.p0 = c;
  s.axes = axes;
  s.semi_axes = semi;
  s.material = m;
  s.part = p;
  return s;
}

namespace {

// Roots of a t^2 + 2 b t + c = 0 (half-b form); false if none.
inline bool roots(double a, double b, double c, double* t0, double* t1) {
  const double h = b * b - a * c;
  if (h < 0.0 || a <= 0.0) return false;
  const double s = std::sqrt(h);
  *t0 = (-b - s) / a;
  *t1 = (-b + s) / a;
  return true;
}

// Nearest positive root; the far one when the origin is inside (c < 0).
inline bool nearestPositive(double a, double b, double c, double* t) {
  double t0, t1;
  if (!roots(a, b, c, &t0, &t1)) return false;
  if (t0 > 0.0) {
    *t = t0;
    return true;
  }
  if (t1 > 0.0) {
    *t = t1;
    return true;
  }
  return false;
}

}  // namespace

bool Primitive::intersect(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double* t) const {
  switch (type) {
    case Type::SPHERE: {
      const Eigen::Vector3d oc = o - p0;
      return nearestPositive(d.dot(d), oc.dot(d), oc.dot(oc) - radius * radius, t);
    }
    case Type::ELLIPSOID: {
      // Map to the unit sphere: q = S^-1 R^T (x - c).
      const Eigen::Vector3d inv = semi_axes.cwiseInverse();
      const Eigen::Vector3d ol = (axes.transpose() * (o - p0)).cwiseProduct(inv);
      const Eigen::Vector3d dl = (axes.transpose() * d).cwiseProduct(inv);
      return nearestPositive(dl.dot(dl), ol.dot(dl), ol.dot(ol) - 1.0, t);
    }
    case Type::CAPSULE: {
      // A capsule is convex: collect every surface crossing (cylinder side within the segment,
      // end spheres beyond it) and take the smallest positive one.
      const Eigen::Vector3d ba = p1 - p0, oa = o - p0;
      const double baba = ba.dot(ba);
      const double r2 = radius * radius;
      double best = INFINITY;
      auto consider = [&](double tc) {
        if (tc > 0.0 && tc < best) best = tc;
      };
      if (baba > 0.0) {
        const double bard = ba.dot(d), baoa = ba.dot(oa);
        const double a = baba * d.dot(d) - bard * bard;
        const double b = baba * oa.dot(d) - baoa * bard;
        const double c = baba * oa.dot(oa) - baoa * baoa - r2 * baba;
        double t0, t1;
        if (roots(a, b, c, &t0, &t1)) {
          for (double tc : {t0, t1}) {
            const double y = baoa + tc * bard;
            if (y >= 0.0 && y <= baba) consider(tc);
          }
        }
      }
      for (int e = 0; e < 2; ++e) {
        const Eigen::Vector3d& cen = e == 0 ? p0 : p1;
        const Eigen::Vector3d oc = o - cen;
        double t0, t1;
        if (!roots(d.dot(d), oc.dot(d), oc.dot(oc) - r2, &t0, &t1)) continue;
        for (double tc : {t0, t1}) {
          const double y = ba.dot(o + tc * d - p0);
          if ((e == 0 && y <= 0.0) || (e == 1 && y >= baba) || baba == 0.0) consider(tc);
        }
      }
      if (!std::isfinite(best)) return false;
      *t = best;
      return true;
    }
  }
  return false;
}

namespace {
inline Eigen::Vector3d closestOnSegment(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                        const Eigen::Vector3d& b) {
  const Eigen::Vector3d ba = b - a;
  const double l2 = ba.squaredNorm();
  const double s = l2 > 0.0 ? std::clamp((p - a).dot(ba) / l2, 0.0, 1.0) : 0.0;
  return a + s * ba;
}
}  // namespace

bool Primitive::contains(const Eigen::Vector3d& p) const {
  switch (type) {
    case Type::SPHERE:
      return (p - p0).squaredNorm() <= radius * radius;
    case Type::CAPSULE:
      return (p - closestOnSegment(p, p0, p1)).squaredNorm() <= radius * radius;
    case Type::ELLIPSOID:
      return (axes.transpose() * (p - p0)).cwiseQuotient(semi_axes).squaredNorm() <= 1.0;
  }
  return false;
}

Eigen::Vector3d Primitive::normal(const Eigen::Vector3d& p) const {
  switch (type) {
    case Type::SPHERE:
      return (p - p0).normalized();
    case Type::CAPSULE:
      return (p - closestOnSegment(p, p0, p1)).normalized();
    case Type::ELLIPSOID: {
      // Gradient of |S^-1 R^T (p - c)|^2 is 2 R S^-2 R^T (p - c).
      const Eigen::Vector3d l = axes.transpose() * (p - p0);
      return (axes * l.cwiseQuotient(semi_axes.cwiseProduct(semi_axes))).normalized();
    }
  }
  return Eigen::Vector3d::UnitZ();
}

void Primitive::boundingSphere(Eigen::Vector3d* c, double* r) const {
  switch (type) {
    case Type::SPHERE:
      *c = p0;
      *r = radius;
      return;
    case Type::CAPSULE:
      *c = 0.5 * (p0 + p1);
      *r = 0.5 * (p1 - p0).norm() + radius;
      return;
    case Type::ELLIPSOID:
      *c = p0;
      *r = semi_axes.maxCoeff();
      return;
  }
}

Eigen::AlignedBox3d Primitive::bounds() const {
  switch (type) {
    case Type::SPHERE: {
      const Eigen::Vector3d e = Eigen::Vector3d::Constant(radius);
      return Eigen::AlignedBox3d(p0 - e, p0 + e);
    }
    case Type::CAPSULE: {
      const Eigen::Vector3d e = Eigen::Vector3d::Constant(radius);
      return Eigen::AlignedBox3d(p0.cwiseMin(p1) - e, p0.cwiseMax(p1) + e);
    }
    case Type::ELLIPSOID: {
      // Half extent along world axis i: |row i of (R S)|.
      const Eigen::Matrix3d rs = axes * semi_axes.asDiagonal();
      const Eigen::Vector3d e = rs.rowwise().norm();
      return Eigen::AlignedBox3d(p0 - e, p0 + e);
    }
  }
  return Eigen::AlignedBox3d();
}

double Primitive::volume() const {
  switch (type) {
    case Type::SPHERE:
      return 4.0 / 3.0 * M_PI * radius * radius * radius;
    case Type::CAPSULE:
      return M_PI * radius * radius * ((p1 - p0).norm() + 4.0 / 3.0 * radius);
    case Type::ELLIPSOID:
      return 4.0 / 3.0 * M_PI * semi_axes.prod();
  }
  return 0.0;
}

Eigen::Vector3d Primitive::centroid() const {
  return type == Type::CAPSULE ? Eigen::Vector3d(0.5 * (p0 + p1)) : p0;
}

}  // namespace tabletop_sim
