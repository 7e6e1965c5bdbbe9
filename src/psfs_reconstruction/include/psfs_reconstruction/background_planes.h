// The parameter planes of a per-pixel background model (background_model.h) as plain pointers:
// what the classifier's row loops, the GPU pixel stage and its host emulation read and write.
// No OpenCV or CUDA types, so the header is usable from g++ and nvcc alike.
#pragma once

#include <array>

namespace psfs {

// Read-only view of the planes, row-major, width*height floats each.
struct BackgroundPlanes {
  const float* mean_r = nullptr;
  const float* mean_g = nullptr;
  const float* mean_intensity = nullptr;
  // 1 / (sigma * sqrt(2)): (dr * scale_r)^2 + (dg * scale_g)^2 is half the squared
  // Mahalanobis distance, and scale_r * scale_g / pi is the density's normaliser
  // 1 / (2 pi sigma_r sigma_g), so no log/sqrt is needed per pixel at classification time.
  const float* scale_r = nullptr;
  const float* scale_g = nullptr;
  const float* var_intensity = nullptr;  // variance of I (8-bit levels squared)
  // Variances of r and g (rg units squared): only the selective update reads them.
  const float* var_r = nullptr;
  const float* var_g = nullptr;
};

// The same planes, writable (the selective update).
struct MutableBackgroundPlanes {
  float* mean_r = nullptr;
  float* mean_g = nullptr;
  float* mean_intensity = nullptr;
  float* scale_r = nullptr;
  float* scale_g = nullptr;
  float* var_intensity = nullptr;
  float* var_r = nullptr;
  float* var_g = nullptr;
};

// The eight planes in one fixed order (BackgroundPlanes or MutableBackgroundPlanes), for code
// that treats them alike: copies to and from the GPU, filling a view from the model.
template <class Planes>
auto planeList(const Planes& p) {
  return std::array<decltype(p.mean_r), 8>{p.mean_r,  p.mean_g,        p.mean_intensity, p.scale_r,
                                           p.scale_g, p.var_intensity, p.var_r,          p.var_g};
}

}  // namespace psfs
