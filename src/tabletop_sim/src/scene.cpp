#include "tabletop_sim/scene.h"

#include <algorithm>
#include <cmath>

namespace tabletop_sim {

using Eigen::Vector3d;

namespace {

inline uint32_t hash3(int32_t x, int32_t y, int32_t z, uint32_t seed) {
  uint32_t h = seed * 0x9E3779B1u ^ static_cast<uint32_t>(x) * 0x85EBCA77u ^
               static_cast<uint32_t>(y) * 0xC2B2AE3Du ^ static_cast<uint32_t>(z) * 0x27D4EB2Fu;
  h ^= h >> 15;
  h *= 0x2C1B3C6Du;
  h ^= h >> 12;
  h *= 0x297A2D39u;
  h ^= h >> 15;
  return h;
}
inline double unitHash(int32_t x, int32_t y, int32_t z, uint32_t seed) {
  return hash3(x, y, z, seed) * (1.0 / 4294967296.0);
}
inline double smooth(double t) { return t * t * (3.0 - 2.0 * t); }
inline Vector3d mix(const Vector3d& a, const Vector3d& b, double t) { return a + t * (b - a); }

}  // namespace

double valueNoise(double x, double y, double z, uint32_t seed) {
  const double fx = std::floor(x), fy = std::floor(y), fz = std::floor(z);
  const int32_t ix = static_cast<int32_t>(fx), iy = static_cast<int32_t>(fy),
                iz = static_cast<int32_t>(fz);
  const double tx = smooth(x - fx), ty = smooth(y - fy), tz = smooth(z - fz);
  double c[2];
  for (int k = 0; k < 2; ++k) {
    const double a = unitHash(ix, iy, iz + k, seed), b = unitHash(ix + 1, iy, iz + k, seed);
    const double cc = unitHash(ix, iy + 1, iz + k, seed),
                 d = unitHash(ix + 1, iy + 1, iz + k, seed);
    c[k] = (a + tx * (b - a)) + ty * ((cc + tx * (d - cc)) - (a + tx * (b - a)));
  }
  return c[0] + tz * (c[1] - c[0]);
}

double fbm(double x, double y, double z, uint32_t seed, int octaves) {
  double sum = 0, amp = 0.5, norm = 0;
  for (int o = 0; o < octaves; ++o) {
    sum += amp * valueNoise(x, y, z, seed + 101u * o);
    norm += amp;
    x *= 2.03;
    y *= 2.03;
    z *= 2.03;
    amp *= 0.5;
  }
  return sum / norm;
}

Scene::Scene(const DirectionalLight& light) : light_(light) { light_.to_light.normalize(); }

bool Scene::intersect(const Vector3d& o, const Vector3d& d, double t_max, SceneHit* hit,
                      bool shadow_casters_only) const {
  double best = t_max;
  int best_obj = -1;
  Vector3d best_n = Vector3d::UnitZ();
  for (size_t i = 0; i < objects_.size(); ++i) {
    const SceneObject& ob = objects_[i];
    if (shadow_casters_only && !ob.casts_shadow) continue;
    const Vector3d& lo = ob.box.min();
    const Vector3d& hi = ob.box.max();
    // Slab test on the bounds (exact for boxes, a cull for cylinders).
    double t0 = 0.0, t1 = best;
    int axis = -1;
    bool miss = false;
    for (int a = 0; a < 3; ++a) {
      if (std::abs(d[a]) < 1e-12) {
        if (o[a] < lo[a] || o[a] > hi[a]) {
          miss = true;
          break;
        }
        continue;
      }
      const double inv = 1.0 / d[a];
      double ta = (lo[a] - o[a]) * inv, tb = (hi[a] - o[a]) * inv;
      if (ta > tb) std::swap(ta, tb);
      if (ta > t0) {
        t0 = ta;
        axis = a;
      }
      t1 = std::min(t1, tb);
      if (t0 > t1) {
        miss = true;
        break;
      }
    }
    if (miss || axis < 0) continue;  // axis < 0: origin inside the bounds (not in our scene)
    if (ob.shape == SceneObject::Shape::BOX) {
      best = t0;
      best_obj = static_cast<int>(i);
      best_n = Vector3d::Zero();
      best_n[axis] = d[axis] > 0 ? -1.0 : 1.0;
      continue;
    }
    // Vertical cylinder: side, then caps (the slab entry on z is a cap hit if inside radius).
    const double cx = 0.5 * (lo.x() + hi.x()), cy = 0.5 * (lo.y() + hi.y());
    const double r = 0.5 * (hi.x() - lo.x());
    const Vector3d pe = o + t0 * d;
    if (axis == 2 && (pe.x() - cx) * (pe.x() - cx) + (pe.y() - cy) * (pe.y() - cy) <= r * r) {
      best = t0;
      best_obj = static_cast<int>(i);
      best_n = Vector3d(0, 0, d.z() > 0 ? -1.0 : 1.0);
      continue;
    }
    const double ox = o.x() - cx, oy = o.y() - cy;
    const double a = d.x() * d.x() + d.y() * d.y();
    const double b = ox * d.x() + oy * d.y();
    const double c = ox * ox + oy * oy - r * r;
    const double h = b * b - a * c;
    if (a <= 0 || h < 0) continue;
    const double t = (-b - std::sqrt(h)) / a;
    if (t < t0 - 1e-9 || t > t1) continue;
    best = t;
    best_obj = static_cast<int>(i);
    best_n = Vector3d(ox + t * d.x(), oy + t * d.y(), 0).normalized();
  }
  if (best_obj < 0) return false;
  hit->t = best;
  hit->object = best_obj;
  hit->normal = best_n;
  return true;
}

bool Scene::isDeskTop(const SceneHit& hit, const Vector3d& p) const {
  return hit.object >= 0 && objects_[hit.object].desk && hit.normal.z() > 0.5 &&
         std::abs(p.z()) < 1e-6;
}

Vector3d Scene::albedo(const SceneHit& hit, const Vector3d& p) const {
  const SceneObject& ob = objects_[hit.object];
  // 2-D coordinates on the face: the two axes other than the normal's dominant one.
  const Vector3d an = hit.normal.cwiseAbs();
  double u, v;
  if (an.z() >= an.x() && an.z() >= an.y()) {
    u = p.x();
    v = p.y();
  } else if (an.x() >= an.y()) {
    u = p.y();
    v = p.z();
  } else {
    u = p.x();
    v = p.z();
  }
  if (ob.shape == SceneObject::Shape::CYLINDER && an.z() < 0.5) {
    const Vector3d c = ob.box.center();
    u = std::atan2(p.y() - c.y(), p.x() - c.x()) * 0.5 * (ob.box.max().x() - ob.box.min().x());
    v = p.z();
  }
  const uint32_t seed = ob.seed;
  const double s = ob.scale;
  switch (ob.texture) {
    case Texture::SOLID:
      return ob.colour * (0.94 + 0.12 * fbm(p.x() * 12, p.y() * 12, p.z() * 12, seed));
    case Texture::PAINT:
      return ob.colour * (0.9 + 0.2 * fbm(p.x() * 3, p.y() * 3, p.z() * 3, seed, 4));
    case Texture::CARPET: {
      const double fine = valueNoise(p.x() * 400, p.y() * 400, 0.0, seed);
      const double coarse = fbm(p.x() * 2, p.y() * 2, 0.0, seed + 7, 3);
      return ob.colour * (0.7 + 0.35 * fine + 0.3 * coarse);
    }
    case Texture::WOOD: {
      // Grain along x: distorted stripes plus fine fibres.
      const double warp = 2.5 * fbm(u * 1.5, v * 6.0, 0.0, seed, 3);
      const double ring = 0.5 + 0.5 * std::sin((v / s + warp) * 2.0 * M_PI);
      const double fibre = valueNoise(u * 60.0, v * 900.0, 0.0, seed + 3);
      return mix(ob.colour, ob.colour2, std::pow(ring, 3.0)) * (0.9 + 0.2 * fibre);
    }
    case Texture::STRIPES: {
      const double w = 0.3 * fbm(u * 4, v * 4, 0, seed);
      const bool band = std::fmod(std::abs(u + v * 0.4) / s + w + 100.0, 1.0) < 0.5;
      return (band ? ob.colour : ob.colour2) * (0.93 + 0.14 * fbm(u * 20, v * 20, 0, seed + 1));
    }
    case Texture::BLOBS: {
      const double n = fbm(u / s, v / s, 0.0, seed, 4);
      return mix(ob.colour, ob.colour2, std::clamp((n - 0.45) * 6.0, 0.0, 1.0)) *
             (0.93 + 0.14 * valueNoise(u * 40, v * 40, 0, seed + 2));
    }
    case Texture::CHECKER: {
      const int cu = static_cast<int>(std::floor(u / s)), cv = static_cast<int>(std::floor(v / s));
      return (((cu + cv) & 1) ? ob.colour : ob.colour2) *
             (0.93 + 0.14 * valueNoise(u * 30, v * 30, 0, seed));
    }
    case Texture::SCREEN: {
      if (hit.normal.y() > -0.5) return ob.colour2;  // bezel and back
      const double mu = u - ob.box.min().x(), mv = v - ob.box.min().z();
      const double w = ob.box.max().x() - ob.box.min().x();
      const double h = ob.box.max().z() - ob.box.min().z();
      if (mu < 0.015 || mu > w - 0.015 || mv < 0.015 || mv > h - 0.015) return ob.colour2;
      // Desktop with a few application windows (grid cells chosen by hash).
      const int cu = static_cast<int>(mu / 0.09), cv = static_cast<int>(mv / 0.07);
      const double hu = unitHash(cu, cv, 0, seed);
      if (hu < 0.35) {
        const double fv = std::fmod(mv, 0.07);
        if (fv > 0.058) return Vector3d(0.25, 0.35, 0.6);  // title bar
        const double line = std::fmod(mv * 120.0, 1.0) < 0.3 && std::fmod(mu, 0.09) < 0.06;
        return line ? Vector3d(0.3, 0.3, 0.3) : Vector3d(0.85, 0.85, 0.82);
      }
      return mix(ob.colour, Vector3d(0.1, 0.35, 0.4), fbm(mu * 6, mv * 6, 0, seed));
    }
    case Texture::BOOKS: {
      // Shelf boards every `scale` metres; books of hashed colour/height between them.
      const double lv = v - ob.box.min().z();
      const int shelf = static_cast<int>(std::floor(lv / s));
      const double sv = lv - shelf * s;
      if (sv < 0.025) return ob.colour2 * (0.9 + 0.2 * valueNoise(u * 50, v * 200, 0, seed));
      const double bw = 0.032;
      const int cell = static_cast<int>(std::floor((u + 10.0) / bw));
      const double fu = (u + 10.0) / bw - cell;
      const double hh = unitHash(cell, shelf, 1, seed);
      const double height = 0.14 + 0.16 * hh;
      if (sv - 0.025 > std::min(height, s - 0.04) || fu < 0.06 || hh > 0.93)
        return Vector3d(0.09, 0.07, 0.06);  // gap between books, back panel
      static const Vector3d palette[10] = {
          {0.62, 0.12, 0.10}, {0.12, 0.35, 0.18}, {0.30, 0.38, 0.56},  // red, green, shirt blue
          {0.80, 0.58, 0.46}, {0.85, 0.80, 0.65}, {0.20, 0.20, 0.22},  // skin tan, cream, black
          {0.75, 0.62, 0.15}, {0.45, 0.25, 0.45}, {0.70, 0.45, 0.30},  // mustard, purple, tan
          {0.28, 0.36, 0.52}};                                         // another blue
      const Vector3d c = palette[hash3(cell, shelf, 2, seed) % 10];
      const double title = (sv > 0.06 && sv < 0.075 && fu > 0.25 && fu < 0.75) ? 0.6 : 1.0;
      return c * title * (0.9 + 0.2 * valueNoise(u * 80, v * 20, 0, seed + 5));
    }
  }
  return ob.colour;
}

Vector3d Scene::shade(const SceneHit& hit, const Vector3d& p, Vector3d* direct) const {
  const Vector3d a = albedo(hit, p);
  const double ndotl = hit.normal.dot(light_.to_light);
  double lit = 0.0;
  if (ndotl > 0.0) {
    SceneHit blocker;
    if (!intersect(p + 1e-6 * hit.normal, light_.to_light, 100.0, &blocker, true)) lit = ndotl;
  }
  const Vector3d d = a * (light_.diffuse * lit);
  if (direct) *direct = d;
  return a * light_.ambient + d;
}

Scene Scene::office(const DirectionalLight& light) {
  Scene s(light);
  uint32_t seed = 1;
  bool shell = true;  // the first objects (floor, ceiling, walls) cast no shadow
  auto box = [&](Vector3d lo, Vector3d hi, Texture tex, Vector3d c1,
                 Vector3d c2 = Vector3d(0, 0, 0), double scale = 0.1, bool desk = false) {
    SceneObject o;
    o.casts_shadow = !shell;
    o.shape = SceneObject::Shape::BOX;
    o.box = Eigen::AlignedBox3d(lo, hi);
    o.texture = tex;
    o.colour = c1;
    o.colour2 = c2;
    o.scale = scale;
    o.seed = seed++;
    o.desk = desk;
    s.add(o);
  };
  auto cylinder = [&](double x, double y, double r, double z0, double z1, Texture tex, Vector3d c1,
                      Vector3d c2 = Vector3d(0, 0, 0), double scale = 0.1) {
    SceneObject o;
    o.shape = SceneObject::Shape::CYLINDER;
    o.box = Eigen::AlignedBox3d(Vector3d(x - r, y - r, z0), Vector3d(x + r, y + r, z1));
    o.texture = tex;
    o.colour = c1;
    o.colour2 = c2;
    o.scale = scale;
    o.seed = seed++;
    s.add(o);
  };
  const Vector3d skin_like(0.80, 0.58, 0.46), shirt_like(0.30, 0.38, 0.56);
  const Vector3d wall(0.78, 0.76, 0.70), dark_wood(0.30, 0.20, 0.12);
  const double F = -0.75;  // floor

  // Room: floor, ceiling, four walls (x in [-1.9, 1.9], y in [-1.8, 1.8]).
  box({-2.0, -1.9, F - 0.05}, {2.0, 1.9, F}, Texture::CARPET, {0.36, 0.36, 0.40});
  box({-2.0, -1.9, 1.8}, {2.0, 1.9, 1.85}, Texture::PAINT, {0.9, 0.9, 0.88});
  box({-2.0, 1.8, F}, {2.0, 1.85, 1.8}, Texture::PAINT, wall);
  box({-2.0, -1.85, F}, {2.0, -1.8, 1.8}, Texture::PAINT, {0.74, 0.76, 0.72});
  box({-1.95, -1.9, F}, {-1.9, 1.9, 1.8}, Texture::PAINT, {0.80, 0.74, 0.64});
  box({1.9, -1.9, F}, {1.95, 1.9, 1.8}, Texture::PAINT, wall);
  shell = false;

  // Front wall (behind the monitor).
  box({-1.5, 1.45, F}, {-0.7, 1.8, 1.1}, Texture::BOOKS, {0, 0, 0}, dark_wood, 0.36);
  box({0.1, 1.79, 0.2}, {0.7, 1.8, 0.9}, Texture::STRIPES, {0.85, 0.55, 0.20}, {0.2, 0.2, 0.25},
      0.08);
  box({0.9, 1.79, 0.0}, {1.4, 1.8, 0.6}, Texture::BLOBS, skin_like, {0.72, 0.50, 0.40}, 0.15);
  box({-0.5, 1.78, 0.3}, {0.0, 1.8, 1.2}, Texture::SOLID, {0.92, 0.92, 0.92});
  box({1.3, 1.3, F}, {1.8, 1.8, 0.3}, Texture::SOLID, {0.55, 0.56, 0.58});
  box({1.35, 1.35, 0.3}, {1.6, 1.7, 0.55}, Texture::CHECKER, {0.15, 0.4, 0.2}, {0.8, 0.8, 0.2},
      0.05);

  // Back wall (behind the user).
  box({0.4, -1.8, F}, {1.3, -1.45, 1.0}, Texture::BOOKS, {0, 0, 0}, {0.55, 0.40, 0.25}, 0.34);
  box({-1.2, -1.8, 0.1}, {-0.5, -1.79, 0.8}, Texture::BLOBS, shirt_like, {0.75, 0.75, 0.80}, 0.12);
  box({-0.35, -1.8, F}, {0.25, -1.78, 1.3}, Texture::WOOD, {0.45, 0.30, 0.18}, {0.35, 0.22, 0.12},
      0.05);
  cylinder(-1.5, -1.45, 0.15, F, -0.4, Texture::SOLID, {0.70, 0.42, 0.30});
  cylinder(-1.5, -1.45, 0.25, -0.4, 0.35, Texture::BLOBS, {0.15, 0.40, 0.12}, {0.35, 0.55, 0.2},
           0.06);

  // Left wall.
  box({-1.9, -0.6, 0.1}, {-1.89, 0.1, 0.7}, Texture::CHECKER, {0.85, 0.2, 0.2}, {0.9, 0.9, 0.85},
      0.07);
  box({-1.9, 0.3, F}, {-1.5, 1.2, 0.05}, Texture::WOOD, {0.60, 0.45, 0.30}, {0.45, 0.32, 0.20},
      0.04);
  box({-1.85, 0.35, 0.05}, {-1.65, 1.0, 0.33}, Texture::BOOKS, {0, 0, 0}, {0.3, 0.2, 0.1}, 0.5);
  box({-1.9, -1.4, 0.2}, {-1.89, -0.9, 0.9}, Texture::STRIPES, skin_like, {0.6, 0.35, 0.25}, 0.1);

  // Right wall.
  box({1.55, -0.8, F}, {1.9, 0.2, 1.1}, Texture::BOOKS, {0, 0, 0}, dark_wood, 0.36);
  box({1.89, 0.5, 0.1}, {1.9, 1.1, 0.8}, Texture::BLOBS, {0.8, 0.5, 0.15}, {0.25, 0.3, 0.55}, 0.1);
  box({1.8, -1.5, -0.6}, {1.9, -1.0, -0.1}, Texture::STRIPES, {0.9, 0.9, 0.9}, {0.6, 0.6, 0.6},
      0.03);

  // Desk: top surface at z = 0, legs, modesty panel.
  const DeskTop& d = s.desk_;
  box({d.x_min, d.y_min, -0.03}, {d.x_max, d.y_max, 0.0}, Texture::WOOD, {0.58, 0.40, 0.24},
      {0.46, 0.30, 0.17}, 0.045, true);
  for (double x : {d.x_min, d.x_max - 0.04})
    for (double y : {d.y_min + 0.02, d.y_max - 0.06})
      box({x, y, F}, {x + 0.04, y + 0.04, -0.03}, Texture::SOLID, {0.25, 0.25, 0.27});
  box({d.x_min + 0.05, d.y_max - 0.05, -0.45}, {d.x_max - 0.05, d.y_max - 0.03, -0.03},
      Texture::WOOD, {0.50, 0.34, 0.20}, {0.42, 0.28, 0.16}, 0.05);

  // On the desk, away from the hands' paths: monitor, mug, books, pen holder, paper.
  box({-0.12, 0.42, 0.0}, {0.12, 0.58, 0.015}, Texture::SOLID, {0.12, 0.12, 0.13});
  box({-0.03, 0.53, 0.015}, {0.03, 0.56, 0.12}, Texture::SOLID, {0.12, 0.12, 0.13});
  box({-0.30, 0.48, 0.09}, {0.30, 0.52, 0.40}, Texture::SCREEN, {0.10, 0.18, 0.40},
      {0.08, 0.08, 0.09});
  cylinder(0.62, 0.32, 0.042, 0.0, 0.10, Texture::SOLID, {0.75, 0.15, 0.12});
  cylinder(0.45, 0.48, 0.035, 0.0, 0.11, Texture::SOLID, {0.15, 0.15, 0.18});
  box({-0.66, 0.30, 0.0}, {-0.44, 0.52, 0.03}, Texture::SOLID, shirt_like);
  box({-0.64, 0.31, 0.03}, {-0.46, 0.50, 0.055}, Texture::SOLID, {0.85, 0.80, 0.65});
  box({-0.65, 0.32, 0.055}, {-0.47, 0.49, 0.08}, Texture::SOLID, {0.60, 0.12, 0.10});
  box({0.22, 0.26, 0.0}, {0.43, 0.55, 0.001}, Texture::SOLID, {0.90, 0.90, 0.88});

  // Chair behind the user (seat under the pelvis, backrest behind the back).
  box({-0.24, -0.72, -0.33}, {0.24, -0.28, -0.28}, Texture::SOLID, {0.18, 0.18, 0.20});
  box({-0.22, -0.71, -0.25}, {0.22, -0.66, 0.22}, Texture::SOLID, {0.18, 0.18, 0.20});
  cylinder(0.0, -0.5, 0.025, -0.72, -0.33, Texture::SOLID, {0.3, 0.3, 0.32});
  cylinder(0.0, -0.5, 0.3, F, -0.72, Texture::SOLID, {0.15, 0.15, 0.16});
  return s;
}

}  // namespace tabletop_sim
