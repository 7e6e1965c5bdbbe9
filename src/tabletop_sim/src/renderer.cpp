#include "tabletop_sim/renderer.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <mutex>
#include <stdexcept>

#include <omp.h>

#include "desk_shadow.h"
#include "tabletop_sim/camera_effects.h"
#include "ray_kernels.h"

namespace tabletop_sim {

using Eigen::Vector3d;
using namespace detail;  // ray kernels and the desk shadow (private headers)

Eigen::Vector3d materialAlbedo(Material m) {
  switch (m) {
    case Material::SKIN:
      return {0.80, 0.58, 0.46};
    case Material::SHIRT:
      return {0.30, 0.38, 0.56};
    case Material::SLEEVE:
      return {0.30, 0.38, 0.56};
    case Material::HAIR:
      return {0.20, 0.13, 0.08};
    case Material::TROUSERS:
      return {0.16, 0.16, 0.20};
    case Material::SHOES:
      return {0.08, 0.07, 0.07};
    case Material::EYE:
      return {0.12, 0.08, 0.07};
  }
  return {0.5, 0.5, 0.5};
}

std::array<Eigen::Vector3d, kNumMaterials> defaultMaterialAlbedos() {
  std::array<Eigen::Vector3d, kNumMaterials> a;
  for (int m = 0; m < kNumMaterials; ++m) a[m] = materialAlbedo(static_cast<Material>(m));
  return a;
}

namespace {

constexpr int kNoiseBits = 10;
constexpr uint32_t kNoiseMask = (1u << kNoiseBits) - 1;

// SplitMix64: the stateless mixer keys each (seed, frame, camera, row); the sequential
// generator then walks the row (rows are always shaded whole, left to right, by one thread).
inline uint64_t splitmix64(uint64_t x) {
  x += 0x9E3779B97F4A7C15ULL;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31);
}
inline uint64_t nextRandom(uint64_t* state) {
  uint64_t z = (*state += 0x9E3779B97F4A7C15ULL);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

// Inverse of the standard normal CDF by bisection (used once, to fill the noise table).
double inverseNormalCdf(double p) {
  double lo = -10, hi = 10;
  for (int i = 0; i < 100; ++i) {
    const double mid = 0.5 * (lo + hi);
    (0.5 * std::erfc(-mid / std::sqrt(2.0)) < p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

inline uint8_t toU8(float v) {
  const int i = static_cast<int>(v + 0.5f);
  return static_cast<uint8_t>(i < 0 ? 0 : (i > 255 ? 255 : i));
}

struct CameraData {
  tabletop_capture::CameraModel cam;
  int w = 0, h = 0;
  std::vector<float> dir;          // unit world ray per pixel (x, y, z)
  cv::Mat bg, depth;               // CV_32FC3 grey levels, CV_32FC1 metres
  std::vector<uint8_t> desk;       // per pixel: 1 if it sees the directly lit desk top
  std::vector<float> desk_xy;      // per pixel: world x, y of the seen desk point
  std::vector<float> desk_direct;  // per pixel: grey levels a full shadow removes (R, G, B)
  cv::Mat vignetting;              // CV_32FC1 gain per pixel; empty = none
  double max_radius = 0;           // lens model valid (monotonic) up to this normalised radius
};

struct CamFrame {
  std::vector<CamPrim> prims;
  std::vector<int> slot;            // person primitive -> index in prims, -1 if culled
  std::vector<int8_t> look;         // person primitive -> colour class (material, sleeve = shirt)
  Rect all;                         // union of the primitives' rects
  Rect shadow;                      // where the person's shadow may darken the desk
  uint64_t key = 0;                 // noise key of this camera and frame
  float gain[3] = {1.0f, 1.0f, 1.0f};  // light and exposure gain of this camera and frame
  bool unit_gain = true;
  std::vector<int> row_x0, row_x1;  // per row of `all`: columns the primitives may cover
};

// Centre-ray z-buffer of a band of rows (plus a row of halo each side) over the columns of
// CamFrame::all: thread-local, so a band is depth-tested and shaded by one thread with no
// barrier in between.
struct DepthBand {
  int y0 = 0, y1 = -1, x0 = 0, x1 = -1;  // rows and columns held (inclusive)
  std::vector<int16_t> ids;
  std::vector<float> zs;
  size_t at(int x, int y) const { return static_cast<size_t>(y - y0) * (x1 - x0 + 1) + (x - x0); }
  int idAt(int x, int y) const {
    return (x < x0 || x > x1 || y < y0 || y > y1) ? -1 : ids[at(x, y)];
  }
};

// Per-call working memory, pooled so steady-state rendering allocates nothing.
struct FrameScratch {
  ShadowMap sm;
  std::vector<CamFrame> cams;
  std::vector<std::pair<int, int>> bands;  // (camera, first row)
};

constexpr int kBandRows = 8;

}  // namespace

struct Renderer::Impl {
  tabletop_capture::RigDescription rig;
  RenderOptions options;
  Scene scene;
  std::vector<CameraData> cams;
  float noise[1u << kNoiseBits];
  int threads = 1;
  mutable std::mutex pool_mutex;
  mutable std::vector<std::unique_ptr<FrameScratch>> pool;

  Impl(const tabletop_capture::RigDescription& r, const RenderOptions& o, const Scene& s)
      : rig(r), options(o), scene(s) {}

  void precompute();
  void prepareCamera(int c, const std::vector<Primitive>& person, bool cull, const ShadowMap& sm,
                     CamFrame* f) const;
  void depthRow(int c, int y, const std::vector<Primitive>& person, const CamFrame& f,
                DepthBand* band) const;
  void shadeRow(int c, int y, const CamFrame& f, const DepthBand& band,
                const std::vector<Primitive>& person, const ShadowMap& sm, bool masks,
                RenderOutput* out) const;
  void renderBand(int c, int y0, const CamFrame& f, const std::vector<Primitive>& person,
                  const ShadowMap& sm, bool masks, RenderOutput* out) const;
  void shadePerson(const Primitive& p, const Vector3d& pt, const Vector3d& n, const Vector3d& dir,
                   float* rgb) const;
  void renderAll(const std::vector<Primitive>& person, uint64_t frame, bool masks, bool cull,
                 RenderOutput* out, const std::vector<Eigen::Vector3f>* gains) const;
};

void Renderer::Impl::precompute() {
  const double sigma = options.noise_sigma;
  for (uint32_t k = 0; k <= kNoiseMask; ++k)
    noise[k] = static_cast<float>(sigma * inverseNormalCdf((k + 0.5) / (kNoiseMask + 1.0)));
  cams.resize(rig.cameras.size());
  for (size_t c = 0; c < cams.size(); ++c) {
    CameraData& d = cams[c];
    d.cam = rig.cameras[c];
    d.w = d.cam.width;
    d.h = d.cam.height;
    const size_t n = static_cast<size_t>(d.w) * d.h;
    d.dir.resize(3 * n);
    d.bg.create(d.h, d.w, CV_32FC3);
    d.depth.create(d.h, d.w, CV_32FC1);
    d.desk.assign(n, 0);
    d.desk_xy.assign(2 * n, 0.0f);
    d.desk_direct.assign(3 * n, 0.0f);
    if (options.vignetting > 0.0) d.vignetting = vignettingGain(d.w, d.h, options.vignetting);
    // Radius (normalised image plane) up to which the radial distortion is monotonic:
    // projected bounds are trusted only inside it.
    const auto& k = d.cam.distortion;
    d.max_radius = std::numeric_limits<double>::infinity();
    for (double r = 0.0; r < 10.0; r += 1e-3) {
      const double r2 = r * r;
      if (1.0 + r2 * (3 * k[0] + r2 * (5 * k[1] + r2 * 7 * k[4])) < 0.05) {
        d.max_radius = r;
        break;
      }
    }
  }
  // Rays and the static scene, once (cameras never move).
  int total = 0;
  for (const auto& d : cams) total += d.h;
#pragma omp parallel for schedule(dynamic, 4) num_threads(threads)
  for (int item = 0; item < total; ++item) {
    int c = 0, y = item;
    while (y >= cams[c].h) y -= cams[c++].h;
    CameraData& d = cams[c];
    const Vector3d o = d.cam.center();
    for (int x = 0; x < d.w; ++x) {
      const size_t i = static_cast<size_t>(y) * d.w + x;
      const Vector3d r = d.cam.rayWorld(Eigen::Vector2d(x, y));
      for (int k = 0; k < 3; ++k) d.dir[3 * i + k] = static_cast<float>(r[k]);
      const Vector3d dir(d.dir[3 * i], d.dir[3 * i + 1], d.dir[3 * i + 2]);
      SceneHit hit;
      float* bg = d.bg.ptr<float>(y) + 3 * x;
      if (!scene.intersect(o, dir, 1e3, &hit)) {
        bg[0] = bg[1] = bg[2] = 0.0f;
        d.depth.at<float>(y, x) = std::numeric_limits<float>::infinity();
        continue;
      }
      const Vector3d p = o + hit.t * dir;
      Vector3d direct;
      const Vector3d col = 255.0 * scene.shade(hit, p, &direct);
      for (int k = 0; k < 3; ++k) bg[k] = static_cast<float>(col[k]);
      d.depth.at<float>(y, x) = static_cast<float>(hit.t);
      if (scene.isDeskTop(hit, p) && direct.maxCoeff() > 0.0) {
        d.desk[i] = 1;
        d.desk_xy[2 * i] = static_cast<float>(p.x());
        d.desk_xy[2 * i + 1] = static_cast<float>(p.y());
        for (int k = 0; k < 3; ++k)
          d.desk_direct[3 * i + k] = static_cast<float>(255.0 * direct[k]);
      }
    }
  }
}

void Renderer::Impl::prepareCamera(int c, const std::vector<Primitive>& person, bool cull,
                                   const ShadowMap& sm, CamFrame* f) const {
  const CameraData& d = cams[c];
  const Vector3d o = d.cam.center();
  const Eigen::Matrix3d rcw = d.cam.world_T_camera.linear().transpose();
  const int pad = options.bounds_padding;
  const Rect whole{0, 0, d.w - 1, d.h - 1};
  // Bounds of a set of world points (a box's corners) in the image: nothing if all are behind
  // the camera; the whole image if some are, or if a point lies where the lens model is no
  // longer monotonic (the projection could fold).
  auto project = [&](const Vector3d* pts, int n, int padding) {
    double u0 = 1e18, v0 = 1e18, u1 = -1e18, v1 = -1e18;
    int behind = 0;
    for (int k = 0; k < n; ++k) behind += (rcw * (pts[k] - o)).z() < 1e-3;
    if (behind == n) return Rect();
    if (behind > 0) return whole;
    for (int k = 0; k < n; ++k) {
      const Vector3d pc = rcw * (pts[k] - o);
      if (std::hypot(pc.x() / pc.z(), pc.y() / pc.z()) > d.max_radius) return whole;
      Eigen::Vector2d px;
      d.cam.projectCamera(pc, &px);
      u0 = std::min(u0, px.x());
      u1 = std::max(u1, px.x());
      v0 = std::min(v0, px.y());
      v1 = std::max(v1, px.y());
    }
    Rect r;
    r.x0 = std::max(0, static_cast<int>(std::floor(u0)) - padding);
    r.y0 = std::max(0, static_cast<int>(std::floor(v0)) - padding);
    r.x1 = std::min(d.w - 1, static_cast<int>(std::ceil(u1)) + padding);
    r.y1 = std::min(d.h - 1, static_cast<int>(std::ceil(v1)) + padding);
    return r;
  };
  f->prims.clear();
  for (size_t k = 0; k < person.size(); ++k) {
    const Primitive& p = person[k];
    CamPrim cp;
    cp.prim = static_cast<int>(k);
    cp.type = p.type;
    if (cull) {
      const Eigen::AlignedBox3d b = p.bounds();
      Vector3d corners[8];
      for (int i = 0; i < 8; ++i)
        corners[i] = b.corner(static_cast<Eigen::AlignedBox3d::CornerType>(i));
      cp.r = project(corners, 8, pad);
    } else {
      cp.r = whole;
    }
    if (cp.r.empty()) continue;
    setRayOrigin(p, o, &cp);
    f->prims.push_back(cp);
  }
  // Front to back, so the z-buffer test below skips what nearer surfaces already hide.
  std::stable_sort(f->prims.begin(), f->prims.end(),
                   [](const CamPrim& a, const CamPrim& b) { return a.t_near < b.t_near; });
  f->shadow = Rect();
  if (sm.active) {
    // The shadow sub-grid's rectangle on the desk plane, sampled 5x5 (distortion bends edges).
    Vector3d pts[25];
    const double x0 = sm.x_min + sm.tx0 * sm.texel, y0 = sm.y_min + sm.ty0 * sm.texel;
    const double x1 = x0 + sm.nx * sm.texel, y1 = y0 + sm.ny * sm.texel;
    for (int a = 0; a < 5; ++a)
      for (int b = 0; b < 5; ++b)
        pts[5 * a + b] = Vector3d(x0 + (x1 - x0) * a / 4.0, y0 + (y1 - y0) * b / 4.0, 0.0);
    f->shadow = project(pts, 25, 3);
  }
}

// Pass 1: nearest person primitive along each pixel-centre ray, inside the culled bounds.
void Renderer::Impl::depthRow(int c, int y, const std::vector<Primitive>& person, const CamFrame& f,
                              DepthBand* band) const {
  const CameraData& d = cams[c];
  const float* depth = d.depth.ptr<float>(y);
  const float* dirs = d.dir.data() + static_cast<size_t>(y) * d.w * 3;
  const size_t row = band->at(band->x0, y);
  int16_t* ids = band->ids.data() + row - band->x0;  // indexed by x
  float* zbuf = band->zs.data() + row - band->x0;
  for (int x = band->x0; x <= band->x1; ++x) {
    zbuf[x] = depth[x];
    ids[x] = -1;
  }
  const Vector3d o = d.cam.center();
  for (const CamPrim& p : f.prims) {
    if (y < p.r.y0 || y > p.r.y1) continue;
    const Primitive& prim = person[p.prim];
    for (int x = p.r.x0; x <= p.r.x1; ++x) {
      if (zbuf[x] <= p.t_near) continue;  // hidden by the scene or a nearer primitive
      double t;
      if (hitPrim(p, prim, o, dirs[3 * x], dirs[3 * x + 1], dirs[3 * x + 2], &t) && t < zbuf[x]) {
        zbuf[x] = static_cast<float>(t);
        ids[x] = static_cast<int16_t>(p.prim);
      }
    }
  }
}

// A band of kBandRows rows: depth pass over the rows it needs (its own and one halo row each
// side), then shading.
void Renderer::Impl::renderBand(int c, int y0, const CamFrame& f,
                                const std::vector<Primitive>& person, const ShadowMap& sm,
                                bool masks, RenderOutput* out) const {
  thread_local DepthBand band;
  const int y1 = std::min(cams[c].h, y0 + kBandRows) - 1;
  band.y0 = 0;
  band.y1 = -1;
  if (!f.all.empty()) {
    band.y0 = std::max(f.all.y0, y0 - 1);
    band.y1 = std::min(f.all.y1, y1 + 1);
    band.x0 = f.all.x0;
    band.x1 = f.all.x1;
    if (band.y1 >= band.y0) {
      const size_t size = static_cast<size_t>(band.y1 - band.y0 + 1) * (band.x1 - band.x0 + 1);
      if (band.ids.size() < size) {
        band.ids.resize(size);
        band.zs.resize(size);
      }
      for (int y = band.y0; y <= band.y1; ++y) depthRow(c, y, person, f, &band);
    }
  }
  for (int y = y0; y <= y1; ++y) shadeRow(c, y, f, band, person, sm, masks, out);
}

void Renderer::Impl::shadePerson(const Primitive& p, const Vector3d& pt, const Vector3d& normal,
                                 const Vector3d& dir, float* rgb) const {
  const Vector3d n = normal.dot(dir) > 0 ? Vector3d(-normal) : normal;  // grazing: face camera
  Vector3d a = options.albedo[static_cast<int>(p.material)];
  if (p.material != Material::SKIN && p.material != Material::EYE) {
    // Fabric/hair texture that sticks to the primitive (its local frame).
    const Vector3d q = p.type == Primitive::Type::ELLIPSOID
                           ? Vector3d(p.axes.transpose() * (pt - p.p0))
                           : Vector3d(pt - p.p0);
    const double freq = p.material == Material::HAIR ? 90.0 : 45.0;
    const double amp = p.material == Material::HAIR ? 0.35 : 0.14;
    a *= 1.0 - amp * 0.5 + amp * valueNoise(q.x() * freq, q.y() * freq, q.z() * freq, 7u);
  }
  const DirectionalLight& l = scene.light();
  const double shade = 255.0 * (l.ambient + l.diffuse * std::max(0.0, n.dot(l.to_light)));
  for (int k = 0; k < 3; ++k) rgb[k] = static_cast<float>(a[k] * shade);
}

// Pass 2: colour, masks and noise. Pixels whose 3x3 neighbourhood sees more than one surface
// (silhouette and part edges) get 4 more rays at (+-1/4, +-1/4) pixel and average the five
// samples, as a real pixel integrates its footprint; their masks are set if any sample sees
// the person (or skin), so silhouettes are conservative: every point of the person projects
// into a pixel marked 255.
void Renderer::Impl::shadeRow(int c, int y, const CamFrame& f, const DepthBand& band,
                              const std::vector<Primitive>& person, const ShadowMap& sm, bool masks,
                              RenderOutput* out) const {
  const CameraData& d = cams[c];
  const int w = d.w, h = d.h;
  const float* bg = d.bg.ptr<float>(y);
  const float* depth = d.depth.ptr<float>(y);
  const float* dirs = d.dir.data() + static_cast<size_t>(y) * w * 3;
  const size_t row_base = static_cast<size_t>(y) * w;
  const uint8_t* desk = d.desk.data() + row_base;
  uint8_t* dst = out->images[c].ptr<uint8_t>(y);
  uint8_t* pm = masks ? out->person_masks[c].ptr<uint8_t>(y) : nullptr;
  uint8_t* sk = masks ? out->skin_masks[c].ptr<uint8_t>(y) : nullptr;
  uint64_t rng = splitmix64(f.key ^ (static_cast<uint64_t>(y) * 0xD1B54A32D192ED03ULL));
  const bool shadow_row = !f.shadow.empty() && y >= f.shadow.y0 && y <= f.shadow.y1;
  const int sx0 = shadow_row ? f.shadow.x0 : w, sx1 = shadow_row ? f.shadow.x1 : -1;

  const float* vig = d.vignetting.empty() ? nullptr : d.vignetting.ptr<float>(y);
  const bool plain = f.unit_gain && !vig;
  auto emit = [&](int x, const float* col) {
    const uint64_t z = nextRandom(&rng);
    if (plain) {
      dst[3 * x] = toU8(col[0] + noise[z & kNoiseMask]);
      dst[3 * x + 1] = toU8(col[1] + noise[(z >> kNoiseBits) & kNoiseMask]);
      dst[3 * x + 2] = toU8(col[2] + noise[(z >> (2 * kNoiseBits)) & kNoiseMask]);
      return;
    }
    const float v = vig ? vig[x] : 1.0f;
    dst[3 * x] = toU8(col[0] * f.gain[0] * v + noise[z & kNoiseMask]);
    dst[3 * x + 1] = toU8(col[1] * f.gain[1] * v + noise[(z >> kNoiseBits) & kNoiseMask]);
    dst[3 * x + 2] = toU8(col[2] * f.gain[2] * v + noise[(z >> (2 * kNoiseBits)) & kNoiseMask]);
  };
  auto background = [&](int x, float* col) {
    col[0] = bg[3 * x];
    col[1] = bg[3 * x + 1];
    col[2] = bg[3 * x + 2];
    if (x >= sx0 && x <= sx1 && desk[x]) {
      const size_t di = row_base + x;
      const float s = sm.sample(d.desk_xy[2 * di], d.desk_xy[2 * di + 1]);
      for (int k = 0; k < 3; ++k) col[k] -= s * d.desk_direct[3 * di + k];
    }
  };
  // Static pixels: background (+ shadow) + noise.
  auto staticSpan = [&](int x0, int x1) {
    for (int x = x0; x < x1; ++x) {
      float col[3];
      background(x, col);
      emit(x, col);
    }
    if (pm && x1 > x0) {
      std::fill(pm + x0, pm + x1, 0);
      std::fill(sk + x0, sk + x1, 0);
    }
  };

  if (f.all.empty() || y < f.all.y0 - 1 || y > f.all.y1 + 1) {
    staticSpan(0, w);
    return;
  }
  // Columns any primitive may cover in rows y-1..y+1, widened by the 3x3 neighbourhood.
  int lo = w, hi = -1;
  for (int yy = std::max(f.all.y0, y - 1); yy <= std::min(f.all.y1, y + 1); ++yy) {
    lo = std::min(lo, f.row_x0[yy - f.all.y0]);
    hi = std::max(hi, f.row_x1[yy - f.all.y0]);
  }
  if (hi < lo) {
    staticSpan(0, w);
    return;
  }
  const int a = std::max(0, lo - 1), b = std::min(w - 1, hi + 1);
  staticSpan(0, a);

  // Ids of rows y-1, y, y+1 over [a-1, b+1], clamped at the image border (outside pixels
  // repeat the edge, so they never make a rim); colmax = the largest id in each column.
  const int n = b - a + 3;
  thread_local std::vector<int16_t> nb;
  nb.resize(4 * static_cast<size_t>(n));
  for (int r = 0; r < 3; ++r) {
    const int yy = std::clamp(y - 1 + r, 0, h - 1);
    int16_t* dstrow = &nb[r * n];
    for (int i = 0; i < n; ++i)
      dstrow[i] = static_cast<int16_t>(band.idAt(std::clamp(a - 1 + i, 0, w - 1), yy));
  }
  int16_t* colmax = &nb[3 * n];
  for (int i = 0; i < n; ++i) colmax[i] = std::max(nb[i], std::max(nb[n + i], nb[2 * n + i]));
  const Vector3d o = d.cam.center();
  auto dirAt = [&](int xx, int yy) {
    xx = std::clamp(xx, 0, w - 1);
    yy = std::clamp(yy, 0, h - 1);
    const float* q = d.dir.data() + (static_cast<size_t>(yy) * w + xx) * 3;
    return Vector3d(q[0], q[1], q[2]);
  };
  for (int x = a; x <= b; ++x) {
    const int16_t* cm = colmax + (x - a);
    if (cm[0] < 0 && cm[1] < 0 && cm[2] < 0) {  // no person anywhere in the 3x3
      float col[3];
      background(x, col);
      emit(x, col);
      if (pm) pm[x] = sk[x] = 0;
      continue;
    }
    const int16_t* r0 = &nb[x - a];
    const int16_t* r1 = r0 + n;
    const int16_t* r2 = r1 + n;
    const int id = r1[1];
    // A rim is where the look changes: person/background or a different material (internal
    // joins of same-coloured primitives are not anti-aliased; they look the same).
    auto cls = [&](int i) { return i < 0 ? -1 : f.look[i]; };
    const int k = cls(id);
    const bool rim = cls(r0[0]) != k || cls(r0[1]) != k || cls(r0[2]) != k || cls(r1[0]) != k ||
                     cls(r1[2]) != k || cls(r2[0]) != k || cls(r2[1]) != k || cls(r2[2]) != k;
    float col[3];
    background(x, col);
    if (!rim && id < 0) {
      emit(x, col);
      if (pm) pm[x] = sk[x] = 0;
      continue;
    }
    const Vector3d dir(dirs[3 * x], dirs[3 * x + 1], dirs[3 * x + 2]);
    float centre[3] = {col[0], col[1], col[2]};
    bool is_person = false, is_skin = false;
    if (id >= 0) {
      const Primitive& p = person[id];
      const double t = band.zs[band.at(x, y)];
      shadePerson(p, o + t * dir, normalAt(f.prims[f.slot[id]], p, o, dir, t), dir, centre);
      is_person = true;
      is_skin = p.material == Material::SKIN;
    }
    if (!rim) {
      emit(x, centre);
      if (pm) {
        pm[x] = 255;
        sk[x] = is_skin ? 255 : 0;
      }
      continue;
    }
    // Candidates: every primitive seen in the 3x3 neighbourhood.
    int cand[9], nc = 0;
    for (const int16_t* r : {r0, r1, r2})
      for (int k = 0; k < 3; ++k)
        if (r[k] >= 0 && std::find(cand, cand + nc, r[k]) == cand + nc) cand[nc++] = r[k];
    // Sub-pixel ray directions from central differences of the exact per-pixel rays (the lens
    // map is smooth: the error is ~1e-7 rad).
    const Vector3d ddx = (dirAt(x + 1, y) - dirAt(x - 1, y)) * ((x > 0 && x < w - 1) ? 0.5 : 1.0);
    const Vector3d ddy = (dirAt(x, y + 1) - dirAt(x, y - 1)) * ((y > 0 && y < h - 1) ? 0.5 : 1.0);
    float sum[3] = {centre[0], centre[1], centre[2]};
    for (int s = 0; s < 4; ++s) {
      const double ox = (s & 1) ? 0.25 : -0.25, oy = (s & 2) ? 0.25 : -0.25;
      const Vector3d sd = (dir + ox * ddx + oy * ddy).normalized();
      double best = depth[x];
      int best_id = -1;
      for (int k = 0; k < nc; ++k) {
        double t;
        const int slot = f.slot[cand[k]];
        if (hitPrim(f.prims[slot], person[cand[k]], o, sd.x(), sd.y(), sd.z(), &t) && t < best) {
          best = t;
          best_id = cand[k];
        }
      }
      float sc[3] = {col[0], col[1], col[2]};
      if (best_id >= 0) {
        shadePerson(person[best_id], o + best * sd,
                    normalAt(f.prims[f.slot[best_id]], person[best_id], o, sd, best), sd, sc);
        is_person = true;
        is_skin |= person[best_id].material == Material::SKIN;
      }
      for (int k = 0; k < 3; ++k) sum[k] += sc[k];
    }
    for (int k = 0; k < 3; ++k) sum[k] *= 0.2f;
    emit(x, sum);
    if (pm) {
      pm[x] = is_person ? 255 : 0;
      sk[x] = is_skin ? 255 : 0;
    }
  }
  staticSpan(b + 1, w);
}

void Renderer::Impl::renderAll(const std::vector<Primitive>& person, uint64_t frame, bool masks,
                               bool cull, RenderOutput* out,
                               const std::vector<Eigen::Vector3f>* gains) const {
  if (person.size() > 32000) throw std::invalid_argument("Renderer: too many primitives");
  const int n = static_cast<int>(cams.size());
  if (gains && static_cast<int>(gains->size()) != n)
    throw std::invalid_argument("Renderer: one gain per camera expected");
  out->images.resize(n);
  out->person_masks.resize(masks ? n : 0);
  out->skin_masks.resize(masks ? n : 0);
  for (int c = 0; c < n; ++c) {
    out->images[c].create(cams[c].h, cams[c].w, CV_8UC3);
    if (masks) {
      out->person_masks[c].create(cams[c].h, cams[c].w, CV_8UC1);
      out->skin_masks[c].create(cams[c].h, cams[c].w, CV_8UC1);
    }
  }
  std::unique_ptr<FrameScratch> scratch;
  {
    std::lock_guard<std::mutex> lock(pool_mutex);
    if (!pool.empty()) {
      scratch = std::move(pool.back());
      pool.pop_back();
    }
  }
  if (!scratch) scratch.reset(new FrameScratch);
  FrameScratch& fs = *scratch;
  if (options.shadows)
    planDeskShadow(person, scene, options.shadow_texel, &fs.sm);
  else
    fs.sm.active = false;
  fs.cams.resize(n);
  fs.bands.clear();
  for (int c = 0; c < n; ++c) {
    CamFrame& f = fs.cams[c];
    prepareCamera(c, person, cull, fs.sm, &f);
    f.all = Rect();
    f.slot.assign(person.size(), -1);
    f.look.resize(person.size());
    for (size_t k = 0; k < person.size(); ++k)
      f.look[k] = static_cast<int8_t>(person[k].material == Material::SLEEVE ? Material::SHIRT
                                                                             : person[k].material);
    for (size_t k = 0; k < f.prims.size(); ++k) {
      f.all.unite(f.prims[k].r);
      f.slot[f.prims[k].prim] = static_cast<int>(k);
    }
    if (!f.all.empty()) {
      const int rows = f.all.y1 - f.all.y0 + 1;
      f.row_x0.assign(rows, cams[c].w);
      f.row_x1.assign(rows, -1);
      for (const CamPrim& p : f.prims)
        for (int y = p.r.y0; y <= p.r.y1; ++y) {
          f.row_x0[y - f.all.y0] = std::min(f.row_x0[y - f.all.y0], p.r.x0);
          f.row_x1[y - f.all.y0] = std::max(f.row_x1[y - f.all.y0], p.r.x1);
        }
    }
    for (int y = 0; y < cams[c].h; y += kBandRows) fs.bands.emplace_back(c, y);
    f.key = splitmix64(splitmix64(splitmix64(options.seed) ^ frame) ^
                       (static_cast<uint64_t>(c) + 0x1234567ULL));
    f.unit_gain = true;
    for (int k = 0; k < 3; ++k) {
      f.gain[k] = gains ? (*gains)[c][k] : 1.0f;
      f.unit_gain = f.unit_gain && f.gain[k] == 1.0f;
    }
  }
  // Two barriers per frame: after the shared shadow map, and at the end. Bands are claimed
  // dynamically one at a time, so a thread that loses its core holds up little work.
  const int nb = static_cast<int>(fs.bands.size());
  const int shadow_rows = fs.sm.active ? fs.sm.ny : 0;
#pragma omp parallel num_threads(threads)
  {
#pragma omp for schedule(dynamic, 4)
    for (int j = 0; j < shadow_rows; ++j) fillDeskShadowRow(person, j, &fs.sm);
#pragma omp for schedule(dynamic, 1)
    for (int i = 0; i < nb; ++i)
      renderBand(fs.bands[i].first, fs.bands[i].second, fs.cams[fs.bands[i].first], person, fs.sm,
                 masks, out);
  }
  std::lock_guard<std::mutex> lock(pool_mutex);
  pool.push_back(std::move(scratch));
}

Renderer::Renderer(const tabletop_capture::RigDescription& rig, const RenderOptions& options, const Scene& scene)
    : impl_(new Impl(rig, options, scene)) {
  if (rig.cameras.empty()) throw std::invalid_argument("Renderer: the rig has no cameras");
  for (const tabletop_capture::CameraModel& c : rig.cameras)
    if (c.width < 1 || c.height < 1 || !(c.fx > 0) || !(c.fy > 0))
      throw std::invalid_argument("Renderer: camera '" + c.name +
                                  "' has a bad size or focal length");
  if (!(options.noise_sigma >= 0.0) || !std::isfinite(options.noise_sigma))
    throw std::invalid_argument("Renderer: noise_sigma must be a finite value >= 0");
  if (options.threads < 0) throw std::invalid_argument("Renderer: threads must be >= 0");
  if (!(options.vignetting >= 0.0 && options.vignetting < 1.0))
    throw std::invalid_argument("Renderer: vignetting must be in [0, 1)");
  for (const Eigen::Vector3d& a : options.albedo)
    if (!a.allFinite() || a.minCoeff() < 0.0 || a.maxCoeff() > 1.0)
      throw std::invalid_argument("Renderer: albedos must be in [0, 1]");
  if (options.bounds_padding < 0)
    throw std::invalid_argument("Renderer: bounds_padding must be >= 0");
  if (!(options.shadow_texel > 1e-4))
    throw std::invalid_argument("Renderer: shadow_texel must be > 0.1 mm");
  impl_->threads = options.threads > 0 ? options.threads : omp_get_max_threads();
  impl_->precompute();
}

Renderer::~Renderer() = default;

const tabletop_capture::RigDescription& Renderer::rig() const { return impl_->rig; }
const RenderOptions& Renderer::options() const { return impl_->options; }
const Scene& Renderer::scene() const { return impl_->scene; }
const cv::Mat& Renderer::backgroundColour(int c) const { return impl_->cams.at(c).bg; }
const cv::Mat& Renderer::backgroundDepth(int c) const { return impl_->cams.at(c).depth; }

void Renderer::render(const std::vector<Primitive>& person, uint64_t frame, bool masks,
                      RenderOutput* out, const std::vector<Eigen::Vector3f>* gains) const {
  impl_->renderAll(person, frame, masks, true, out, gains);
}

void Renderer::renderWithoutCulling(const std::vector<Primitive>& person, uint64_t frame,
                                    bool masks, RenderOutput* out) const {
  impl_->renderAll(person, frame, masks, false, out, nullptr);
}

}  // namespace tabletop_sim
