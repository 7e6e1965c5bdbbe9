// One class's view evidence in GPU memory (issue 20): the same arrays as ViewEvidence holds on
// the host (view_evidence.h: terms with the guard pixel, pairs with the kQuadPad border), so the
// GPU pixel stage writes what the GPU volume kernels read, and a host ViewEvidence can be
// uploaded as is. Plain pointers, no CUDA types: the struct is usable from any C++ file.
#pragma once

#include <cstdint>
#include <vector>

namespace psfs {

struct GpuViewEvidence {
  const int16_t* terms = nullptr;   // device: width * height + 1 entries (+ levels, see ViewEvidence)
  const uint16_t* pairs = nullptr;  // device: multi-projection only (else nullptr)
  int width = 0, height = 0;
  int quad_stride = 0;              // width + 2 * ViewEvidence::kQuadPad
  bool has_inactive_pixels = false;
};

// All views of one class, in the cameras' order.
using GpuEvidence = std::vector<GpuViewEvidence>;

}  // namespace psfs
