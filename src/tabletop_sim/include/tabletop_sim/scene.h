// Static environment of the simulated rig: an office with a wooden desk (top surface at z = 0),
// a monitor and clutter on it, a chair, floor and walls covered in shelves, books and posters.
// Boxes and vertical cylinders with procedural textures; ray cast once per pixel by the
// renderer, so it may be as cluttered as realism asks. Some surfaces are deliberately close to
// the shirt colour and to skin tones (wood, a beige poster, blue books): the reconstruction
// must cope with camouflage.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace tabletop_sim {

// Sun-like light plus ambient; a surface of albedo a with normal n shows
// a * (ambient + diffuse * max(0, n . to_light)) (grey levels = 255 * that).
struct DirectionalLight {
  // Towards the light: from above, in front of the user (+y) and to their left (-x).
  Eigen::Vector3d to_light = Eigen::Vector3d(-0.35, 0.45, 1.0).normalized();
  double ambient = 0.3;
  double diffuse = 0.7;
};

enum class Texture : uint8_t { SOLID, WOOD, CARPET, PAINT, STRIPES, BLOBS, CHECKER, SCREEN, BOOKS };

struct SceneObject {
  enum class Shape : uint8_t { BOX, CYLINDER } shape = Shape::BOX;
  Eigen::AlignedBox3d box;  // BOX: the box; CYLINDER: its bounds (vertical axis, circular)
  Texture texture = Texture::SOLID;
  Eigen::Vector3d colour = Eigen::Vector3d::Constant(0.5);   // albedo in [0, 1]
  Eigen::Vector3d colour2 = Eigen::Vector3d::Constant(0.5);  // second colour of patterns
  double scale = 0.1;                                        // pattern period (m)
  uint32_t seed = 0;
  bool desk = false;         // its top face is the desk surface (receives the person's shadow)
  bool casts_shadow = true;  // false for the room shell (the light is inside the room)
};

struct SceneHit {
  double t = 0;
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  int object = -1;
};

// The desk top rectangle at z = 0 (world), where the person's shadow is drawn.
struct DeskTop {
  double x_min = -0.8, x_max = 0.8, y_min = -0.35, y_max = 0.6;
};

class Scene {
 public:
  explicit Scene(const DirectionalLight& light = DirectionalLight());
  // The default cluttered office.
  static Scene office(const DirectionalLight& light = DirectionalLight());

  void add(const SceneObject& object) { objects_.push_back(object); }
  const std::vector<SceneObject>& objects() const { return objects_; }
  const DirectionalLight& light() const { return light_; }
  const DeskTop& desk() const { return desk_; }

  // Nearest hit with 0 < t < t_max along origin + t*dir (dir unit).
  bool intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double t_max,
                 SceneHit* hit, bool shadow_casters_only = false) const;
  // True if the hit is on the desk top (the person's shadow may fall there).
  bool isDeskTop(const SceneHit& hit, const Eigen::Vector3d& p) const;
  Eigen::Vector3d albedo(const SceneHit& hit, const Eigen::Vector3d& p) const;
  // Lit colour in [0, 1] including static shadows; *direct gets the part the direct light
  // contributes (what a shadow cast on this point removes).
  Eigen::Vector3d shade(const SceneHit& hit, const Eigen::Vector3d& p,
                        Eigen::Vector3d* direct = nullptr) const;

 private:
  DirectionalLight light_;
  DeskTop desk_;
  std::vector<SceneObject> objects_;
};

// Smooth value noise in [0, 1] (deterministic), used by scene and person textures.
double valueNoise(double x, double y, double z, uint32_t seed);
double fbm(double x, double y, double z, uint32_t seed, int octaves = 3);

}  // namespace tabletop_sim
