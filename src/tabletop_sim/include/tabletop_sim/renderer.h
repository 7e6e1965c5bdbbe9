// CPU ray-casting renderer of the simulated rig. Cameras are static, so everything that does
// not move is computed once per camera: the per-pixel world ray (from CameraModel::rayWorld,
// so lens distortion is exact), the lit background colour and depth, and where the directly
// lit desk top is seen. Per frame only the person is ray cast: each primitive is tested only
// at the pixels inside its screen-space bounds (its tight world box projected with full
// distortion, padded) and only where the z-buffer (initialised with the background depth) is
// farther than its bounding sphere. Silhouette and material edges get 4 extra sub-pixel rays
// (anti-aliasing, as a real pixel integrates its footprint). The person casts a shadow on the
// desk through a per-frame shadow map on the desk plane shared by all cameras. Lambert +
// ambient shading; Gaussian sensor noise from a counter-based RNG keyed by
// (seed, frame, camera, row): the same inputs give the same bytes whatever the thread count.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "tabletop_capture/rig_description.h"
#include "tabletop_sim/primitives.h"
#include "tabletop_sim/scene.h"

namespace tabletop_sim {

// Albedo (linear, [0, 1], R G B) of a person material in the default scenario; skin is what
// skin classifiers and the tests compare chromaticity against.
Eigen::Vector3d materialAlbedo(Material m);
std::array<Eigen::Vector3d, kNumMaterials> defaultMaterialAlbedos();

struct RenderOptions {
  double noise_sigma = 2.0;  // grey levels, per channel
  // The person's colours, indexed by Material (the scenario's skin tone, clothes, hair).
  std::array<Eigen::Vector3d, kNumMaterials> albedo = defaultMaterialAlbedos();
  double vignetting = 0.0;  // relative darkening at the image corners (camera_effects.h)
  uint64_t seed = 1;
  bool shadows = true;          // the person's shadow on the desk
  int threads = 0;              // OpenMP threads; 0 = OpenMP default
  int bounds_padding = 2;       // pixels added around each primitive's projected bounds
  double shadow_texel = 0.004;  // shadow-map texel (m); sampled bilinearly (soft edge)
};

// Masks are conservative at edges: 255 where any of the pixel's samples (its centre, plus
// 4 at +-1/4 pixel on edge pixels) sees the person (or skin). So every point of the person
// projects into a pixel marked 255, and a visual hull carved from the masks contains it.
struct RenderOutput {
  std::vector<cv::Mat> images;        // CV_8UC3, channel order R, G, B
  std::vector<cv::Mat> person_masks;  // CV_8UC1, 255 = person (only when masks requested)
  std::vector<cv::Mat> skin_masks;    // CV_8UC1, 255 = visible skin (only when requested)
};

class Renderer {
 public:
  // Throws std::invalid_argument for an empty rig, bad sizes or negative noise.
  Renderer(const tabletop_capture::RigDescription& rig, const RenderOptions& options = RenderOptions(),
           const Scene& scene = Scene::office());
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  const tabletop_capture::RigDescription& rig() const;
  const RenderOptions& options() const;
  const Scene& scene() const;

  // Renders all cameras. `frame` keys the noise. Reuses out's buffers when sizes match.
  // Safe to call concurrently (no shared mutable state). `gains` (optional, one per camera):
  // per-channel gain of everything the camera sees this frame (light changes, exposure),
  // applied before the noise.
  void render(const std::vector<Primitive>& person, uint64_t frame, bool masks,
              RenderOutput* out, const std::vector<Eigen::Vector3f>* gains = nullptr) const;
  // Same images, but every primitive is ray tested at every pixel: the no-culling baseline
  // for benchmarks and the exactness test of the culling.
  void renderWithoutCulling(const std::vector<Primitive>& person, uint64_t frame, bool masks,
                            RenderOutput* out) const;

  // Noise-free background of camera i: CV_32FC3 (R, G, B grey levels, 0..255) and CV_32FC1
  // distance along the pixel's unit ray to the first static surface (m).
  const cv::Mat& backgroundColour(int camera) const;
  const cv::Mat& backgroundDepth(int camera) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Bayer mosaic of an rgb8 image for a ROS encoding: bayer_rggb8, bayer_bggr8, bayer_gbrg8 or
// bayer_grbg8. The four letters give the colour kept at (row, col) = (0,0), (0,1), (1,0),
// (1,1), repeating every 2 pixels. Returns CV_8UC1. Throws std::invalid_argument otherwise.
cv::Mat mosaicBayer(const cv::Mat& rgb, const std::string& encoding);

}  // namespace tabletop_sim
