// Private: the per-frame footprint filters of ViewEvidence (issue 17). Plain integer
// loops that GCC vectorises, compiled once per instruction set (target clones), so every CPU
// gets the same values; footprint_filter.cpp has the brute-force definitions they must match
// (test_footprint_fusion checks them).
#pragma once

#include <cstdint>
#include <vector>

namespace psfs {
namespace detail {

struct FootprintScratch {
  std::vector<int16_t> rows;   // padded row and row medians
  std::vector<uint16_t> sums;  // box sums
  std::vector<uint8_t> bytes;  // box means
};

// dst[v * W + u] = separable median over the (2R + 1)^2 window of the int16 image src (W x H,
// replicated border): the median over dv of the medians over du. R in {1, 2}.
void medianFilterTerms(const int16_t* src, int W, int H, int R, int16_t* dst, FootprintScratch* scratch);

// dst = lut[round(box mean of the bytes over the (2R + 1)^2 window)], replicated border:
// (sum + n / 2) / n exactly, n = (2R + 1)^2. R in {1, 2}.
void meanFilterTerms(const uint8_t* src, int W, int H, int R, const int16_t* lut, int16_t* dst,
                     FootprintScratch* scratch);

// Brute-force references (tests).
int16_t separableMedianAt(const int16_t* src, int W, int H, int R, int u, int v);
uint8_t boxMeanAt(const uint8_t* src, int W, int H, int R, int u, int v);

}  // namespace detail
}  // namespace psfs
