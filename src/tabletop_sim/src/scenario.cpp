#include "tabletop_sim/scenario.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <initializer_list>
#include <stdexcept>

#include "tabletop_capture/default_rig.h"
#include "tabletop_sim/renderer.h"

namespace tabletop_sim {

using Eigen::Vector3d;

namespace {

// SplitMix64: the same stream on every platform (std:: distributions are not portable).
class Random {
 public:
  explicit Random(uint64_t seed) : state_(seed * 0x2545F4914F6CDD1DULL + 0x9E3779B97F4A7C15ULL) {}
  uint64_t next() {
    uint64_t z = (state_ += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
  }
  double uniform(double lo = 0.0, double hi = 1.0) {
    return lo + (hi - lo) * static_cast<double>(next() >> 11) * (1.0 / 9007199254740992.0);
  }
  int integer(int lo, int hi) {  // inclusive
    return lo + static_cast<int>(next() % static_cast<uint64_t>(hi - lo + 1));
  }
  bool chance(double p) { return uniform() < p; }
  // Index drawn with the given weights.
  int pick(std::initializer_list<double> weights) {
    double total = 0;
    for (double w : weights) total += w;
    double u = uniform(0.0, total);
    int i = 0;
    for (double w : weights) {
      if (u < w) return i;
      u -= w;
      ++i;
    }
    return i - 1;
  }

 private:
  uint64_t state_;
};

Vector3d hsv(double h, double s, double v) {  // h in [0, 1)
  const double c = v * s, hh = 6.0 * (h - std::floor(h));
  const double x = c * (1.0 - std::abs(std::fmod(hh, 2.0) - 1.0));
  Vector3d rgb;
  if (hh < 1) rgb = {c, x, 0};
  else if (hh < 2) rgb = {x, c, 0};
  else if (hh < 3) rgb = {0, c, x};
  else if (hh < 4) rgb = {0, x, c};
  else if (hh < 5) rgb = {x, 0, c};
  else rgb = {c, 0, x};
  return rgb + Vector3d::Constant(v - c);
}

Vector3d clamp01(const Vector3d& v) { return v.cwiseMax(0.0).cwiseMin(1.0); }

const Eigen::AlignedBox3d kWorkspace(Vector3d(-0.5, -0.5, 0.0), Vector3d(0.5, 0.5, 0.75));

tabletop_capture::RigDescription randomRig(Random& r, int n, int width, int height) {
  tabletop_capture::RigDescription rig;
  rig.name = "tabletop_sim";
  rig.world_frame = "world";
  const double scale = width / 320.0;
  // Azimuths spread over the 270 degrees in front of and beside the user (none straight
  // behind: the back would hide the hands), each jittered within its share.
  const double span = 270.0, first = -45.0;
  for (int i = 0; i < n; ++i) {
    const double az =
        (first + span * (i + 0.5 + r.uniform(-0.35, 0.35)) / n) * M_PI / 180.0;
    const double radius = r.uniform(1.25, 1.6), h = r.uniform(0.95, 1.55);
    const Vector3d c(radius * std::cos(az), -0.05 + radius * std::sin(az), h);
    const Vector3d target(r.uniform(-0.08, 0.08), r.uniform(-0.15, 0.05), r.uniform(0.15, 0.35));
    tabletop_capture::CameraModel cam;
    cam.name = "cam" + std::to_string(i);
    cam.frame_id = cam.name + "_optical_frame";
    cam.width = width;
    cam.height = height;
    cam.cx = (width - 1) / 2.0 + r.uniform(-2.0, 2.0) * scale;
    cam.cy = (height - 1) / 2.0 + r.uniform(-2.0, 2.0) * scale;
    cam.distortion = {{r.uniform(-0.2, -0.04), r.uniform(0.0, 0.06), r.uniform(-6e-4, 6e-4),
                       r.uniform(-6e-4, 6e-4), 0.0}};
    cam.world_T_camera = tabletop_capture::lookAt(c, target);
    // Zoomed to the workspace with a random margin: some cameras frame it tightly, some loosely.
    const double f = tabletop_capture::focalToFit(cam, kWorkspace, r.uniform(4.0, 0.08 * width));
    cam.fx = f;
    cam.fy = f * 1.002;
    rig.cameras.push_back(cam);
  }
  return rig;
}

SceneObject deskObject(Random& r, const Vector3d& colour, double max_height) {
  SceneObject o;
  const double x = r.uniform(-0.72, 0.72), y = r.uniform(0.2, 0.55);
  double hx = r.uniform(0.02, 0.09), hy = r.uniform(0.02, 0.07);
  const double z1 = r.uniform(0.02, max_height);
  o.shape = r.chance(0.5) ? SceneObject::Shape::BOX : SceneObject::Shape::CYLINDER;
  if (o.shape == SceneObject::Shape::CYLINDER) hy = hx;
  o.box = Eigen::AlignedBox3d(Vector3d(x - hx, y - hy, 0.0), Vector3d(x + hx, y + hy, z1));
  o.texture = r.chance(0.6) ? Texture::SOLID : (r.chance(0.5) ? Texture::STRIPES : Texture::BLOBS);
  o.colour = colour;
  o.colour2 = clamp01(colour * r.uniform(0.5, 0.9));
  o.scale = r.uniform(0.02, 0.08);
  o.seed = static_cast<uint32_t>(r.next());
  return o;
}

std::string fmt(const char* f, double a) {
  char b[64];
  std::snprintf(b, sizeof(b), f, a);
  return b;
}

std::string rgb(const Vector3d& c) {
  char b[64];
  std::snprintf(b, sizeof(b), "(%.2f %.2f %.2f)", c.x(), c.y(), c.z());
  return b;
}

}  // namespace

std::array<Vector3d, kNumMaterials> defaultAlbedo() { return defaultMaterialAlbedos(); }

Vector3d fitzpatrickSkin(double type) {
  // Linear albedos, type I to VI; type III is the default person's.
  static const Vector3d table[6] = {{0.86, 0.69, 0.61}, {0.83, 0.63, 0.53}, {0.80, 0.58, 0.46},
                                    {0.63, 0.43, 0.31}, {0.43, 0.28, 0.19}, {0.25, 0.16, 0.11}};
  const double t = std::clamp(type, 1.0, 6.0) - 1.0;
  const int i = std::min(4, static_cast<int>(t));
  return table[i] + (t - i) * (table[i + 1] - table[i]);
}

Scenario defaultScenario() {
  Scenario s;
  s.albedo = defaultAlbedo();
  return s;
}

Scenario randomScenario(uint64_t seed) {
  Random r(seed);
  Scenario s = defaultScenario();
  s.name = "random-" + std::to_string(seed);
  s.seed = seed;

  // Person.
  using M = Material;
  auto& a = s.albedo;
  const double skin_type = r.uniform(1.0, 6.0);
  a[static_cast<int>(M::SKIN)] = fitzpatrickSkin(skin_type);
  BodyOptions& b = s.body;
  b.size = r.uniform(0.88, 1.12);
  b.arm_length = r.uniform(0.94, 1.06);
  b.girth = r.uniform(0.85, 1.3);
  b.hand_size = r.uniform(0.85, 1.15);
  b.sleeves = static_cast<Sleeves>(r.pick({0.4, 0.2, 0.2, 0.2}));  // LONG ROLLED SHORT CUFF
  b.cuff_cover = r.uniform(0.15, 0.5);
  b.hair = static_cast<Hair>(r.pick({0.6, 0.25, 0.15}));
  static const Vector3d hair_colours[6] = {{0.05, 0.04, 0.04}, {0.20, 0.13, 0.08},
                                           {0.35, 0.24, 0.14}, {0.75, 0.62, 0.38},
                                           {0.62, 0.62, 0.60}, {0.50, 0.20, 0.08}};
  a[static_cast<int>(M::HAIR)] = hair_colours[r.integer(0, 5)];
  Vector3d shirt;
  switch (r.pick({0.55, 0.15, 0.15, 0.15})) {
    case 0: shirt = hsv(r.uniform(), r.uniform(0.15, 0.6), r.uniform(0.2, 0.7)); break;
    case 1: shirt = hsv(r.uniform(), r.uniform(0.0, 0.3), r.uniform(0.04, 0.12)); break;  // dark
    case 2: shirt = clamp01(fitzpatrickSkin(r.uniform(1.0, 6.0)) * r.uniform(0.9, 1.1)); break;
    default: {  // like the room: desk wood, wall paint or carpet
      static const Vector3d room[3] = {{0.58, 0.40, 0.24}, {0.78, 0.76, 0.70}, {0.36, 0.36, 0.40}};
      shirt = clamp01(room[r.integer(0, 2)] * r.uniform(0.9, 1.1));
    }
  }
  a[static_cast<int>(M::SHIRT)] = a[static_cast<int>(M::SLEEVE)] = shirt;
  a[static_cast<int>(M::TROUSERS)] = hsv(r.uniform(), r.uniform(0.0, 0.5), r.uniform(0.08, 0.4));

  // Light.
  LightingScript& l = s.lighting;
  const double az = r.uniform(0.0, 2.0 * M_PI), el = r.uniform(35.0, 80.0) * M_PI / 180.0;
  l.light.to_light = Vector3d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
  l.light.ambient = r.uniform(0.2, 0.42);
  l.light.diffuse = r.uniform(0.9, 1.05) - l.light.ambient;
  l.intensity = r.uniform(0.8, 1.2);
  l.tint = colourTemperatureTint(r.uniform(3000.0, 6500.0));
  if (r.chance(0.5)) {
    l.flicker_amplitude = r.uniform(0.01, 0.05);
    l.flicker_beat_hz = r.uniform(0.1, 1.5);
    l.flicker_phase = r.uniform(0.0, 2.0 * M_PI);
  }
  l.drift_per_minute = r.uniform(-0.1, 0.1);
  if (r.chance(0.25)) {
    l.sudden_time = r.uniform(3.0, 10.0);
    l.sudden_gain = r.chance(0.5) ? r.uniform(1.15, 1.4) : r.uniform(0.75, 0.87);
  }

  // Cameras.
  const int n = r.integer(4, 8);
  static const int sizes[4][2] = {{320, 240}, {400, 300}, {480, 360}, {640, 480}};
  const int k = r.pick({0.45, 0.2, 0.2, 0.15});
  s.rig = randomRig(r, n, sizes[k][0], sizes[k][1]);
  s.noise_sigma = r.uniform(1.0, 4.0);
  CameraEffects& e = s.effects;
  e.vignetting = r.uniform(0.0, 0.35);
  if (r.chance(0.5)) e.blur_sigma = r.uniform(0.3, 1.0);
  if (r.chance(0.4)) e.jpeg_quality = r.integer(60, 90);
  e.bayer = r.chance(0.3);
  // White balance set for the room's light, as an installer does, with a residual error.
  for (int c = 0; c < n; ++c)
    e.white_balance.push_back(
        l.tint.cwiseInverse().cwiseProduct(Vector3d(r.uniform(0.93, 1.07), 1.0, r.uniform(0.93, 1.07))));
  e.exposure_steps.resize(n);
  for (int c = 0; c < n; ++c) {
    if (!r.chance(0.3)) continue;
    double t = r.uniform(2.0, 7.0);
    for (int j = r.integer(1, 2); j > 0; --j, t += r.uniform(2.0, 6.0))
      e.exposure_steps[c].emplace_back(t, r.uniform(0.85, 1.15));
  }

  // Room: clutter on the far half of the desk (the hands' paths stay free), perhaps a
  // skin-coloured object, perhaps a tall object in front of the torso.
  for (int i = r.integer(2, 8); i > 0; --i)
    s.extra_objects.push_back(deskObject(r, hsv(r.uniform(), r.uniform(0.1, 0.8), r.uniform(0.1, 0.9)), 0.2));
  if (r.chance(0.5))
    s.extra_objects.push_back(deskObject(r, clamp01(fitzpatrickSkin(r.uniform(1.0, 6.0))), 0.15));
  if (r.chance(0.3)) {
    SceneObject o;
    const double x = r.uniform(-0.3, 0.3), hw = r.uniform(0.08, 0.15);
    const double y = r.uniform(0.25, 0.4);
    o.box = Eigen::AlignedBox3d(Vector3d(x - hw, y - 0.04, 0.0), Vector3d(x + hw, y + 0.04, r.uniform(0.25, 0.42)));
    o.texture = Texture::SOLID;
    o.colour = hsv(r.uniform(), r.uniform(0.0, 0.4), r.uniform(0.1, 0.6));
    o.seed = static_cast<uint32_t>(r.next());
    s.extra_objects.push_back(o);
  }
  return s;
}

const std::vector<std::string>& scenarioPresets() {
  static const std::vector<std::string> names = {
      "dark_skin", "pale_skin", "skin_sleeves", "cuffs",    "short_sleeves", "four_cameras",
      "vga",       "lights_on", "flicker",      "clutter",  "occluder",      "low_light"};
  return names;
}

Scenario scenarioByName(const std::string& name) {
  if (name == "default") return defaultScenario();
  const std::string prefix = "random-";
  if (name.compare(0, prefix.size(), prefix) == 0 && name.size() > prefix.size() &&
      name.find_first_not_of("0123456789", prefix.size()) == std::string::npos &&
      name.size() - prefix.size() <= 19)
    return randomScenario(std::stoull(name.substr(prefix.size())));
  Scenario s = defaultScenario();
  s.name = name;
  using M = Material;
  auto& a = s.albedo;
  if (name == "dark_skin") {
    a[static_cast<int>(M::SKIN)] = fitzpatrickSkin(6.0);
  } else if (name == "pale_skin") {
    a[static_cast<int>(M::SKIN)] = fitzpatrickSkin(1.0);
  } else if (name == "skin_sleeves") {
    a[static_cast<int>(M::SHIRT)] = a[static_cast<int>(M::SLEEVE)] = Vector3d(0.78, 0.60, 0.50);
  } else if (name == "cuffs") {
    s.body.sleeves = Sleeves::CUFF;
    s.body.cuff_cover = 0.4;
  } else if (name == "short_sleeves") {
    s.body.sleeves = Sleeves::SHORT;
  } else if (name == "four_cameras") {
    tabletop_capture::DefaultRigOptions o;
    o.num_cameras = 4;
    s.rig = tabletop_capture::makeDefaultRig(o);
  } else if (name == "vga") {
    tabletop_capture::DefaultRigOptions o;
    o.width = 640;
    o.height = 480;
    s.rig = tabletop_capture::makeDefaultRig(o);
  } else if (name == "lights_on") {
    s.lighting.sudden_time = 2.5;  // after the background (1 s) and a few person frames
    s.lighting.sudden_gain = 1.4;
  } else if (name == "flicker") {
    s.lighting.flicker_amplitude = 0.05;
    s.lighting.flicker_beat_hz = 0.8;
    s.lighting.drift_per_minute = 0.1;
  } else if (name == "clutter") {
    Random r(7);
    for (int i = 0; i < 10; ++i)
      s.extra_objects.push_back(deskObject(r, hsv(r.uniform(), r.uniform(0.1, 0.8), r.uniform(0.1, 0.9)), 0.2));
    for (int i = 0; i < 3; ++i)
      s.extra_objects.push_back(deskObject(r, fitzpatrickSkin(1.0 + 2.0 * i), 0.15));
  } else if (name == "occluder") {
    SceneObject o;
    o.box = Eigen::AlignedBox3d(Vector3d(-0.15, 0.28, 0.0), Vector3d(0.15, 0.36, 0.38));
    o.colour = Vector3d(0.3, 0.3, 0.32);
    s.extra_objects.push_back(o);
  } else if (name == "low_light") {
    s.lighting.intensity = 0.45;
    s.noise_sigma = 4.0;
  } else {
    std::string valid = "default, random-<seed>";
    for (const std::string& p : scenarioPresets()) valid += ", " + p;
    throw std::invalid_argument("unknown scenario '" + name + "' (valid: " + valid + ")");
  }
  return s;
}

std::string Scenario::describe() const {
  using M = Material;
  std::string d = name + (seed ? " (seed " + std::to_string(seed) + ")" : std::string()) + "\n";
  d += "  person: skin " + rgb(albedo[static_cast<int>(M::SKIN)]) + ", shirt " +
       rgb(albedo[static_cast<int>(M::SHIRT)]) + ", hair " + hairName(body.hair) + " " +
       rgb(albedo[static_cast<int>(M::HAIR)]) + ", sleeves " + sleevesName(body.effectiveSleeves());
  if (body.effectiveSleeves() == Sleeves::CUFF) d += fmt(" over %.0f %% of the palm", 100 * body.cuff_cover);
  d += fmt(", size %.2f", body.size) + fmt(", arms %.2f", body.arm_length) +
       fmt(", girth %.2f", body.girth) + fmt(", hands %.2f\n", body.hand_size);
  const LightingScript& l = lighting;
  d += "  light: intensity" + fmt(" %.2f", l.intensity) + ", tint " + rgb(l.tint) +
       fmt(", ambient %.2f", l.light.ambient) + fmt(", elevation %.0f deg",
                                                   std::asin(l.light.to_light.normalized().z()) * 180 / M_PI);
  if (l.flicker_amplitude > 0)
    d += fmt(", flicker %.0f %%", 100 * l.flicker_amplitude) + fmt(" at %.2f Hz", l.flicker_beat_hz);
  if (l.drift_per_minute != 0) d += fmt(", drift %+.0f %%/min", 100 * l.drift_per_minute);
  if (l.sudden_time >= 0) d += fmt(", x%.2f", l.sudden_gain) + fmt(" at %.1f s", l.sudden_time);
  d += "\n";
  const int n = rig.cameras.empty() ? 8 : static_cast<int>(rig.cameras.size());
  const int w = rig.cameras.empty() ? 320 : rig.cameras[0].width;
  const int h = rig.cameras.empty() ? 240 : rig.cameras[0].height;
  int steps = 0;
  for (const auto& c : effects.exposure_steps) steps += static_cast<int>(c.size());
  d += "  cameras: " + std::to_string(n) + " x " + std::to_string(w) + "x" + std::to_string(h) +
       (rig.cameras.empty() ? " (default ring)" : "") + fmt(", noise %.1f", noise_sigma);
  if (effects.vignetting > 0) d += fmt(", vignetting %.2f", effects.vignetting);
  if (effects.blur_sigma > 0) d += fmt(", blur %.1f px", effects.blur_sigma);
  if (effects.jpeg_quality > 0) d += ", jpeg q" + std::to_string(effects.jpeg_quality);
  if (effects.bayer) d += ", bayer";
  if (steps) d += ", " + std::to_string(steps) + " exposure steps";
  if (!effects.white_balance.empty())
    d += ", white balance leaves " + rgb(lighting.tint.cwiseProduct(effects.white_balance[0]));
  d += "\n  scene: office + " + std::to_string(extra_objects.size()) + " objects\n";
  return d;
}

}  // namespace tabletop_sim
