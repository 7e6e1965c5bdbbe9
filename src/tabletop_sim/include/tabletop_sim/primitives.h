// Solid primitives the simulated person is built from (sphere, capsule, oriented ellipsoid),
// with the ray, inside and normal queries the renderer and the occupancy oracle share, so the
// pictures and the ground truth describe exactly the same solid.
#pragma once

#include <cstdint>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace tabletop_sim {

// What a surface is made of; decides its colour. Only SKIN counts as skin in the ground truth.
enum class Material : uint8_t { SKIN, SHIRT, SLEEVE, HAIR, TROUSERS, SHOES, EYE };
constexpr int kNumMaterials = 7;
const char* materialName(Material m);
inline bool isSkin(Material m) { return m == Material::SKIN; }

// Which body part a primitive belongs to (ground truth labels, occlusion queries).
enum class BodyPart : uint8_t {
  TORSO,
  NECK,
  HEAD,
  LEFT_UPPER_ARM,
  LEFT_FOREARM,
  LEFT_HAND,
  RIGHT_UPPER_ARM,
  RIGHT_FOREARM,
  RIGHT_HAND,
  LEGS
};
constexpr int kNumBodyParts = 10;
const char* bodyPartName(BodyPart p);

struct Primitive {
  enum class Type : uint8_t { SPHERE, CAPSULE, ELLIPSOID };

  Type type = Type::SPHERE;
  Material material = Material::SKIN;
  BodyPart part = BodyPart::TORSO;
  Eigen::Vector3d p0 = Eigen::Vector3d::Zero();  // sphere/ellipsoid centre; capsule end A
  Eigen::Vector3d p1 = Eigen::Vector3d::Zero();  // capsule end B
  double radius = 0.0;                           // sphere, capsule
  // Ellipsoid: columns are the unit principal axes (world), semi_axes their half lengths.
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();
  Eigen::Vector3d semi_axes = Eigen::Vector3d::Zero();

  static Primitive sphere(const Eigen::Vector3d& centre, double radius, Material m, BodyPart p);
  static Primitive capsule(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double radius,
                           Material m, BodyPart p);
  static Primitive ellipsoid(const Eigen::Vector3d& centre, const Eigen::Matrix3d& axes,
                             const Eigen::Vector3d& semi_axes, Material m, BodyPart p);

  // Nearest t > 0 with origin + t*dir on the surface (dir need not be unit; t is in units of
  // |dir|). From inside, that is the exit point. False if the ray misses.
  bool intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double* t) const;
  // Closed solid: boundary points count as inside.
  bool contains(const Eigen::Vector3d& p) const;
  // Outward unit normal (gradient of the implicit function), meant for surface points.
  Eigen::Vector3d normal(const Eigen::Vector3d& p) const;
  void boundingSphere(Eigen::Vector3d* centre, double* radius) const;
  // Tight axis-aligned bounds (tighter than the bounding sphere's cube for capsules).
  Eigen::AlignedBox3d bounds() const;
  double volume() const;
  Eigen::Vector3d centroid() const;  // centre of mass of the primitive alone
};

}  // namespace tabletop_sim
