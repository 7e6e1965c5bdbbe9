// Normalised-rg chromaticity plus intensity (thesis 4.2.1): r = R/(R+G+B), g = G/(R+G+B),
// I = (R+G+B)/3. Chroma is (to first order) invariant to shading, which is why both the
// background and the skin models live in rg, and I is kept separately for the shadow test.
//
// Units: r, g in [0, 1] (r + g <= 1); I in 8-bit levels [0, 255].
// Densities over rg in this package are per unit rg area. The thesis' uniform alternative
// 1/256^2 per quantisation cell of a 256x256 rg grid is the same as density 1 per unit area,
// so p(c|.) in unit-area terms can be compared with 1 directly.
#pragma once

#include <cstdint>

namespace psfs {

struct NormalizedRgI {
  float r = 1.0f / 3.0f;
  float g = 1.0f / 3.0f;
  float intensity = 0.0f;  // (R+G+B)/3, 8-bit levels
};

// Black (0,0,0) has no chroma; it maps to the neutral grey point (1/3, 1/3) instead of a
// division by zero, so black pixels can never produce NaN downstream.
inline NormalizedRgI toNormalizedRgI(std::uint8_t R, std::uint8_t G, std::uint8_t B) {
  NormalizedRgI c;
  const int sum = int(R) + int(G) + int(B);
  c.intensity = float(sum) * (1.0f / 3.0f);
  if (sum > 0) {
    const float inv = 1.0f / float(sum);
    c.r = float(R) * inv;
    c.g = float(G) * inv;
  }
  return c;
}

}  // namespace psfs
