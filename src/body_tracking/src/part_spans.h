// Private: the intervals of many rows of one part at once (part_score.h's rowSpan), the CPU's
// hot path of the PAPF observation. A row's two intervals (the part's and its shell's: two square
// roots, up to eight divisions) are most of a row's work and each row's are independent, so they
// run a SIMD vector of rows at a time: one Google Highway source (part_spans_hwy.cpp), dispatched
// at run time like the pSfS kernels (AVX-512, AVX2 under TABLETOP_SIMD=avx2, SSE4, NEON, or
// Highway's portable target under TABLETOP_SIMD=scalar). Every target does rowSpan's operations
// in its order, so the scores are the same bytes as part_score::scorePart's (test_volume_observation
// checks every compiled target). The spans of rows that meet the part are the same values (a
// zero's sign may differ: Highway's SSSE3 and SCALAR Ceil / Floor; the scores read the ends as
// integers); those of rows that miss it (ok = 0) are never read.
#pragma once

#include <cstdint>
#include <vector>

#include "part_score.h"

namespace body_tracking {
namespace part_spans {

// The rows' spans as arrays (structure of arrays; ok and shell_ok 1.0 or 0.0), `n` rows padded
// to whole vectors.
struct SpanRows {
  std::vector<double> yy, z;  // the rows' lattice coordinates (inputs)
  std::vector<double> A, B, xlo, xhi, olo, ohi, ok, shell_ok;
  void resize(size_t n);
};

// Fills the spans of rows [0, n) of `rows` (yy and z set) for the part.
using SpansFn = void (*)(const part_score::PartSetup& s, const part_score::PartQuadric& q, double h,
                         size_t n, SpanRows* rows);

// The function for the target the pSfS kernels use now (psfs/simd_dispatch.h).
SpansFn activeSpans();

// Every target this build has and this CPU runs, with its name (tests compare them all).
struct Target {
  int64_t bits;
  const char* name;
  SpansFn fn;
};
std::vector<Target> availableTargets();

// The part's score (part_score::scorePart, the same bytes) with the rows' spans from `spans`;
// `rows` is scratch.
double scorePart(const part_score::PartQuadric& q, const part_score::ObservationGrid& g,
                 const part_score::RowSumsView& sums, SpansFn spans, SpanRows* rows);

}  // namespace part_spans
}  // namespace body_tracking
