// Ray tests for the renderer's inner loops: a person primitive specialised to rays from one
// fixed origin (a camera centre), so each pixel costs a few multiply-adds. Private to
// src/sim (not installed).
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Core>

#include "tabletop_sim/primitives.h"

namespace tabletop_sim {
namespace detail {

using Eigen::Vector3d;

struct Rect {  // inclusive pixel bounds
  int x0 = 0, y0 = 0, x1 = -1, y1 = -1;
  bool empty() const { return x1 < x0 || y1 < y0; }
  void unite(const Rect& o) {
    if (o.empty()) return;
    if (empty()) {
      *this = o;
      return;
    }
    x0 = std::min(x0, o.x0);
    y0 = std::min(y0, o.y0);
    x1 = std::max(x1, o.x1);
    y1 = std::max(y1, o.y1);
  }
};

// A person primitive prepared for rays from one camera centre: everything that depends only
// on the origin is folded into constants, leaving a few multiply-adds per pixel.
struct CamPrim {
  int prim = 0;
  Primitive::Type type = Primitive::Type::SPHERE;
  bool generic = false;  // camera inside the bounding sphere: use Primitive::intersect
  float t_near = 0;      // no hit can be nearer than this (bounding sphere distance)
  Rect r;
  double c[14];
};

// Fills cp's constants (and generic/t_near) for rays starting at `o`.
inline void setRayOrigin(const Primitive& p, const Vector3d& o, CamPrim* cp) {
  Vector3d bc;
  double br;
  p.boundingSphere(&bc, &br);
  cp->generic = (o - bc).norm() <= br * 1.001;
  cp->t_near = static_cast<float>(std::max(0.0, (o - bc).norm() - br) * (1.0 - 1e-6));
  switch (p.type) {
    case Primitive::Type::SPHERE: {
      const Vector3d oc = o - p.p0;
      cp->c[0] = oc.x();
      cp->c[1] = oc.y();
      cp->c[2] = oc.z();
      cp->c[3] = oc.squaredNorm() - p.radius * p.radius;
      break;
    }
    case Primitive::Type::ELLIPSOID: {
      const Eigen::Matrix3d m = p.semi_axes.cwiseInverse().asDiagonal() * p.axes.transpose();
      const Vector3d ol = m * (o - p.p0);
      for (int r = 0; r < 3; ++r)
        for (int col = 0; col < 3; ++col) cp->c[3 * r + col] = m(r, col);
      cp->c[9] = ol.x();
      cp->c[10] = ol.y();
      cp->c[11] = ol.z();
      cp->c[12] = ol.squaredNorm() - 1.0;
      break;
    }
    case Primitive::Type::CAPSULE: {
      const Vector3d ba = p.p1 - p.p0, oa = o - p.p0, ob = o - p.p1;
      const double r2 = p.radius * p.radius;
      const double baba = ba.squaredNorm(), baoa = ba.dot(oa);
      for (int i = 0; i < 3; ++i) {
        cp->c[i] = ba[i];
        cp->c[3 + i] = oa[i];
        cp->c[6 + i] = ob[i];
      }
      cp->c[9] = baba;
      cp->c[10] = baoa;
      cp->c[11] = baba * oa.squaredNorm() - baoa * baoa - r2 * baba;
      cp->c[12] = oa.squaredNorm() - r2;
      cp->c[13] = ob.squaredNorm() - r2;
      if (baba <= 1e-18) cp->generic = true;
      break;
    }
  }
}

inline bool hitSphere(const CamPrim& p, double dx, double dy, double dz, double* t) {
  const double b = p.c[0] * dx + p.c[1] * dy + p.c[2] * dz;
  const double h = b * b - p.c[3];
  if (h < 0.0) return false;
  const double tt = -b - std::sqrt(h);
  if (tt <= 0.0) return false;
  *t = tt;
  return true;
}

inline bool hitEllipsoid(const CamPrim& p, double dx, double dy, double dz, double* t) {
  const double* m = p.c;
  const double lx = m[0] * dx + m[1] * dy + m[2] * dz;
  const double ly = m[3] * dx + m[4] * dy + m[5] * dz;
  const double lz = m[6] * dx + m[7] * dy + m[8] * dz;
  const double a = lx * lx + ly * ly + lz * lz;
  const double b = m[9] * lx + m[10] * ly + m[11] * lz;
  const double h = b * b - a * m[12];
  if (h < 0.0) return false;
  const double tt = (-b - std::sqrt(h)) / a;
  if (tt <= 0.0) return false;
  *t = tt;
  return true;
}

// Ray-capsule for an origin outside the capsule (after Inigo Quilez).
inline bool hitCapsule(const CamPrim& p, double dx, double dy, double dz, double* t) {
  const double* c = p.c;
  const double bard = c[0] * dx + c[1] * dy + c[2] * dz;
  const double rdoa = c[3] * dx + c[4] * dy + c[5] * dz;
  const double baba = c[9], baoa = c[10];
  const double a = baba - bard * bard;
  const double b = baba * rdoa - baoa * bard;
  const double h = b * b - a * c[11];
  if (h < 0.0) return false;  // misses the infinite cylinder, hence the capsule
  if (a > 1e-12 * baba) {
    const double tt = (-b - std::sqrt(h)) / a;
    const double y = baoa + tt * bard;
    if (y > 0.0 && y < baba) {
      if (tt <= 0.0) return false;
      *t = tt;
      return true;
    }
    // Hits an end cap: the sphere on the side the cylinder hit fell.
    const bool at_a = y <= 0.0;
    const double bb = at_a ? rdoa : c[6] * dx + c[7] * dy + c[8] * dz;
    const double hh = bb * bb - (at_a ? c[12] : c[13]);
    if (hh <= 0.0) return false;
    const double ts = -bb - std::sqrt(hh);
    if (ts <= 0.0) return false;
    *t = ts;
    return true;
  }
  // Ray parallel to the axis: nearest of the two end spheres.
  double best = std::numeric_limits<double>::infinity();
  for (int e = 0; e < 2; ++e) {
    const double bb = e == 0 ? rdoa : c[6] * dx + c[7] * dy + c[8] * dz;
    const double hh = bb * bb - (e == 0 ? c[12] : c[13]);
    if (hh <= 0.0) continue;
    const double ts = -bb - std::sqrt(hh);
    if (ts > 0.0) best = std::min(best, ts);
  }
  if (!std::isfinite(best)) return false;
  *t = best;
  return true;
}

inline bool hitPrim(const CamPrim& p, const Primitive& prim, const Vector3d& o, double dx,
                    double dy, double dz, double* t) {
  if (p.generic) return prim.intersect(o, Vector3d(dx, dy, dz), t);
  switch (p.type) {
    case Primitive::Type::SPHERE:
      return hitSphere(p, dx, dy, dz, t);
    case Primitive::Type::ELLIPSOID:
      return hitEllipsoid(p, dx, dy, dz, t);
    default:
      return hitCapsule(p, dx, dy, dz, t);
  }
}

// Outward unit normal at origin + t*d, from the per-camera constants (cheaper than
// Primitive::normal, which re-derives them).
inline Vector3d normalAt(const CamPrim& p, const Primitive& prim, const Vector3d& o,
                         const Vector3d& d, double t) {
  const double* c = p.c;
  if (p.generic) return prim.normal(o + t * d);
  switch (p.type) {
    case Primitive::Type::SPHERE:
      return Vector3d(c[0] + t * d.x(), c[1] + t * d.y(), c[2] + t * d.z()).normalized();
    case Primitive::Type::ELLIPSOID: {
      // Unit-sphere point q = ol + t M d; the gradient is M^T q.
      const double lx = c[9] + t * (c[0] * d.x() + c[1] * d.y() + c[2] * d.z());
      const double ly = c[10] + t * (c[3] * d.x() + c[4] * d.y() + c[5] * d.z());
      const double lz = c[11] + t * (c[6] * d.x() + c[7] * d.y() + c[8] * d.z());
      return Vector3d(c[0] * lx + c[3] * ly + c[6] * lz, c[1] * lx + c[4] * ly + c[7] * lz,
                      c[2] * lx + c[5] * ly + c[8] * lz)
          .normalized();
    }
    default: {
      const Vector3d ba(c[0], c[1], c[2]);
      const Vector3d pa = Vector3d(c[3], c[4], c[5]) + t * d;
      const double hh = std::clamp(pa.dot(ba) / c[9], 0.0, 1.0);
      return (pa - hh * ba).normalized();
    }
  }
}

}  // namespace detail
}  // namespace tabletop_sim
