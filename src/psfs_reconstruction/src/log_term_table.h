// Private: logTermOfPair (voxel_arithmetic.h) for every median pair it can see, as a table, for
// the targets whose multiply-add is not fused (Highway's SSE4, SSSE3, EMU128 and SCALAR).
// There the vector log would round twice per step and differ from the FMA chain in a few
// values, so each lane called logTermOfPair, whose seven fmaf are library calls (software on
// a CPU without FMA): 30 % of the SSE4 face kernel's time (Zen 5, perf, 2026-12-07). A median
// pair has only 130561 values (0 .. 2 * 255 * 256), so the table holds the function's own
// results: the same bytes by construction, one load per lane (255 KiB, int16). A kernel clamps
// m to [0, kMaxMedianPair] first: below 0 the function's floor at 256 gives table[0] anyway,
// and a pair above the range (a kNoFace sample) can only be in the lane of a voxel that is not
// observed (its term is discarded) or of a lane past the span's end (never stored).
#pragma once

#include <cstdint>

#include "voxel_arithmetic.h"

namespace psfs {
namespace detail {

constexpr int32_t kMaxMedianPair = 2 * 255 * 256;  // two face samples of 255 * 256 each

// logTermOfPair(m) for m in [0, kMaxMedianPair]; built on the first call (thread-safe).
const int16_t* logTermTable();

}  // namespace detail
}  // namespace psfs
