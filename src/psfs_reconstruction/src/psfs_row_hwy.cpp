// The single-projection pSfS row kernel (psfs_kernels.h: PsfsRowFn), one source for every
// instruction set through Google Highway (issue 17): AVX-512, AVX2, SSE4, SSSE3 and NEON where
// the compiler targets them, and Highway's portable SCALAR target everywhere else (its EMU128
// needs GCC >= 12.3). SVE and RVV are left out: their vectors are sizeless types, which
// cannot form the array of the K lowest terms below. It serves the
// single-projection volumes, the footprint-filtered volumes and the hand sub-volumes. Each
// target does the integer and float operations of rowScalar (psfs_kernels.cpp, the reference)
// in the same order, so every target writes the same bytes (test_psfs_fusion_kernels checks
// all compiled targets against it).
//
// Highway re-includes this file once per target (foreach_target.h).
#ifndef HWY_DISABLED_TARGETS
#define HWY_DISABLED_TARGETS (HWY_SVE | HWY_SVE2 | HWY_SVE_256 | HWY_SVE2_128 | HWY_RVV)
#endif
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "psfs_row_hwy.cpp"
#include <hwy/foreach_target.h>  // must come before highway.h

#include <hwy/highway.h>

#include <algorithm>
#include <cstdint>
#include <cstring>

#include "psfs_kernels.h"
#include "psfs_reconstruction/projection_table.h"
#include "psfs_reconstruction/view_evidence.h"

#include "psfs_hwy-inl.h"  // centreTerm, accumulateTerm, finaliseLanes

HWY_BEFORE_NAMESPACE();
namespace psfs {
namespace detail {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

#if HWY_TARGET == HWY_SCALAR
constexpr int kScalarBlock = 64;

// Cameras c0 .. c0 + G - 1 added to the accumulators of voxels x0 .. x0 + n - 1.
template <int K, int G>
HWY_INLINE void addCameras(const PsfsRowParams& p, const uint32_t* centres, int c0, int x0, int n,
                           int32_t* sum, int32_t* inactive, int32_t (*m)[kScalarBlock]) {
  const uint32_t* src[G];
  const int16_t* terms[G];
  int width[G];
  for (int k = 0; k < G; ++k) {
    src[k] = centres + size_t(c0 + k) * p.nxp + x0;
    terms[k] = p.views[c0 + k].terms;
    width[k] = p.views[c0 + k].width;
  }
  for (int i = 0; i < n; ++i) {
    int32_t t[G];
    for (int k = 0; k < G; ++k) t[k] = terms[k][pixelOf(src[k][i], width[k])];
    int32_t in = 0, s = 0;
    for (int k = 0; k < G; ++k) {
      in += t[k] > 0;
      s += minI(t[k], 0);
    }
    inactive[i] += in;
    sum[i] += s;
    for (int k = 0; k < G; ++k)
      for (int j = 0; j < K; ++j) {
        const int32_t lo = minI(m[j][i], t[k]);
        t[k] = maxI(m[j][i], t[k]);
        m[j][i] = lo;
      }
  }
}

// The one-lane target (the portable fallback): the vector loop below would finish one voxel
// before it starts the next. Here the loops are turned inside out, camera outer and voxel inner
// over a block of the row, so neighbouring voxels are independent work the CPU overlaps. Each
// voxel still adds its cameras in order and is finalised by voxel_arithmetic.h: the bytes of
// the reference (rowScalar).
template <int K>
void rowHwy(const PsfsRowParams& p, const uint32_t* centres, uint8_t* out, const RowSpan& span) {
  constexpr int kBlock = kScalarBlock;
  for (int c = 0; c < p.num_cameras; ++c)
    for (int i = span.begin; i < span.end; i += 16) __builtin_prefetch(centres + size_t(c) * p.nxp + i, 0, 0);
  const int x_end = std::min(span.end, p.nx);
  for (int x0 = span.begin; x0 < x_end; x0 += kBlock) {
    const int n = std::min(kBlock, x_end - x0);
    int32_t sum[kBlock], inactive[kBlock], m[K > 0 ? K : 1][kBlock];  // of voxels x0 + i
    for (int i = 0; i < n; ++i) {
      sum[i] = inactive[i] = 0;
      for (int j = 0; j < K; ++j) m[j][i] = kVoxNoEvidence;
    }
    // 8 or 4 cameras per pass (then the rest one by one): a fraction of the accumulators' loads and
    // stores, and the views' pointers held in registers (integer sums, so the grouping changes
    // no value; the K lowest still see the cameras in order).
    int c = 0;
    for (; c + 8 <= p.num_cameras; c += 8)
      addCameras<K, 8>(p, centres, c, x0, n, sum, inactive, m);
    for (; c + 4 <= p.num_cameras; c += 4)
      addCameras<K, 4>(p, centres, c, x0, n, sum, inactive, m);
    for (; c < p.num_cameras; ++c) addCameras<K, 1>(p, centres, c, x0, n, sum, inactive, m);
    for (int i = 0; i < n; ++i) {
      int32_t mi[K > 0 ? K : 1];
      for (int j = 0; j < K; ++j) mi[j] = m[j][i];
      out[x0 + i] = finalise(p, sum[i], p.num_cameras - inactive[i], mi, K);
    }
  }
}
#else
template <int K>
void rowHwy(const PsfsRowParams& p, const uint32_t* centres, uint8_t* out, const RowSpan& span) {
  const DI di;
  const DU du;
  const int lanes = static_cast<int>(hn::Lanes(di));
  // The row's projections are read once per frame: fetch them without letting them push the
  // evidence images (gathered every frame) out of the caches.
  for (int c = 0; c < p.num_cameras; ++c)
    for (int i = span.begin; i < span.end; i += 16) __builtin_prefetch(centres + size_t(c) * p.nxp + i, 0, 0);
  const VI zero = hn::Zero(di);
  const int x_end = std::min(span.end, p.nx);
  for (int x0 = span.begin; x0 < x_end; x0 += lanes) {
    // The span holds whole chunks of 8; wider vectors load its last ones masked (lanes past it
    // read pixel 0: computed, never stored).
    const int left = span.end - x0;
    VI sum = zero, inactive = zero;
    VI m[K > 0 ? K : 1];
    for (int j = 0; j < K; ++j) m[j] = hn::Set(di, ViewEvidence::kNoEvidence);
    for (int c = 0; c < p.num_cameras; ++c) {
      const uint32_t* src = centres + size_t(c) * p.nxp + x0;
      const VU uv = left >= lanes ? hn::LoadU(du, src) : hn::MaskedLoad(hn::FirstN(du, left), du, src);
      accumulateTerm<K>(centreTerm(p.views[c], uv), sum, inactive, m);
    }
    finaliseLanes<K>(p, sum, inactive, m, out + x0, x_end - x0);
  }
}
#endif  // HWY_TARGET == HWY_SCALAR

PsfsRowFn RowKernel(int k) {
  return byOcclusion(k, [&](auto K) -> PsfsRowFn { return &rowHwy<decltype(K)::value>; });
}

}  // namespace HWY_NAMESPACE
}  // namespace detail
}  // namespace psfs
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace psfs {
namespace detail {

HWY_EXPORT(RowKernel);

// What ChosenTarget::GetIndex() computes for the chosen target: the fallback (EMU128 or
// SCALAR) sits in the last slot.
size_t hwyDispatchIndex(int64_t target) {
  return hwy::Num0BitsBelowLS1Bit_Nonzero64(static_cast<uint64_t>(
      (HWY_CHOSEN_TARGET_SHIFT(target) | HWY_CHOSEN_TARGET_MASK_SCALAR) & HWY_CHOSEN_TARGET_MASK_TARGETS));
}

std::vector<int64_t> hwyRowTargets() { return hwy::SupportedAndGeneratedTargets(); }

PsfsRowFn hwyRowKernel(int64_t target, int k) { return HWY_DISPATCH_TABLE(RowKernel)[hwyDispatchIndex(target)](k); }

const char* hwyTargetName(int64_t target) { return hwy::TargetName(target); }

int64_t hwyRowTarget(bool vector, bool avx512) {
  const int64_t portable = HWY_EMU128 | HWY_SCALAR;
  int64_t no_avx512 = HWY_AVX3 | HWY_AVX3_DL;
#ifdef HWY_AVX3_ZEN4
  no_avx512 |= HWY_AVX3_ZEN4;
#endif
  const int64_t allowed = !vector ? portable : avx512 ? ~int64_t(0) : ~no_avx512;
  static const int64_t supported = hwy::SupportedTargets();  // it runs CPUID on every call
  const int64_t usable = supported & HWY_TARGETS & allowed;
  const int64_t fallback = HWY_TARGETS & portable;
  return usable != 0 ? usable & -usable : fallback & -fallback;  // lower bit: better target
}

}  // namespace detail
}  // namespace psfs
#endif  // HWY_ONCE
