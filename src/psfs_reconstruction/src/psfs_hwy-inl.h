// Private: the per-voxel fusion steps shared by the Highway row kernels (psfs_row_hwy.cpp,
// psfs_face_hwy.cpp): a camera's centre term, the running sum / count / K lowest terms, and
// finalise() of voxel_arithmetic.h lane by lane. Highway's per-target header convention: the
// including file re-includes it once per target (foreach_target.h), so it has no #pragma once.
#if defined(PSFS_HWY_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef PSFS_HWY_INL_H_
#undef PSFS_HWY_INL_H_
#else
#define PSFS_HWY_INL_H_
#endif

#include <hwy/highway.h>

#include <algorithm>
#include <cstdint>
#include <cstring>

#include "psfs_kernels.h"
#include "psfs_reconstruction/view_evidence.h"

HWY_BEFORE_NAMESPACE();
namespace psfs {
namespace detail {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

using DI = hn::ScalableTag<int32_t>;
using DU = hn::RebindToUnsigned<DI>;
using DF = hn::RebindToFloat<DI>;
using VI = hn::Vec<DI>;
using VU = hn::Vec<DU>;
using VF = hn::Vec<DF>;

// Float to int32 for values that lie in int32's range (NaN excluded), rounded to nearest even
// (kNearest) or toward zero: x86's conversion alone, without the fix-up for overflow that
// Highway's NearestInt / ConvertTo add (4 operations per vector, in the face kernel's log term
// per camera). The same integers.
template <bool kNearest>
HWY_INLINE VI intInRange(VF v) {
#if HWY_ARCH_X86 && HWY_TARGET != HWY_SCALAR && HWY_TARGET != HWY_EMU128
#if HWY_TARGET <= HWY_AVX3
  return VI{kNearest ? _mm512_cvtps_epi32(v.raw) : _mm512_cvttps_epi32(v.raw)};
#elif HWY_TARGET <= HWY_AVX2
  return VI{kNearest ? _mm256_cvtps_epi32(v.raw) : _mm256_cvttps_epi32(v.raw)};
#else
  return VI{kNearest ? _mm_cvtps_epi32(v.raw) : _mm_cvttps_epi32(v.raw)};
#endif
#else
  if constexpr (kNearest) return hn::NearestInt(v);
  return hn::ConvertTo(DI(), v);
#endif
}

// The camera's log term at each packed centre (PackedUV: u in 1/16 px in the low half, v in
// the high half, 1/16 px). A 32-bit gather at the term's byte offset, sign-extended from its
// low half: the terms are readable 4 bytes past the image (ViewEvidence::terms).
HWY_INLINE VI centreTerm(const KernelView& v, VU uv) {
  const DI di;
  const DU du;
  const VU pix = hn::Add(hn::Mul(hn::ShiftRight<20>(uv), hn::Set(du, static_cast<uint32_t>(v.width))),
                         hn::ShiftRight<4>(hn::And(uv, hn::Set(du, 0xFFFFu))));
  const VI g = hn::GatherOffset(di, reinterpret_cast<const int32_t*>(v.terms),
                                hn::BitCast(di, hn::ShiftLeft<1>(pix)));
  return hn::ShiftRight<16>(hn::ShiftLeft<16>(g));
}

// Adds one camera's terms t (> 0: no evidence) to the running sum, the count of views without
// evidence and the K lowest terms (ascending): TermFusion::add lane by lane.
template <int K>
HWY_INLINE void accumulateTerm(VI t, VI& sum, VI& inactive, VI* m) {
  const VI zero = hn::Zero(DI());
  inactive = hn::Sub(inactive, hn::VecFromMask(DI(), hn::Gt(t, zero)));
  sum = hn::Add(sum, hn::Min(t, zero));
  for (int j = 0; j < K; ++j) {
    const VI lo = hn::Min(m[j], t);
    t = hn::Max(m[j], t);
    m[j] = lo;
  }
}

// Drop, normalise, decide and map to bytes: finalise() lane by lane; the first
// min(lanes, count) bytes go to out.
template <int K>
HWY_INLINE void finaliseLanes(const PsfsRowParams& p, VI sum, VI inactive, const VI* m, uint8_t* out,
                              int count) {
  const DI di;
  const DF df;
  const hn::Rebind<uint8_t, DI> d8;
  VI n = hn::Sub(hn::Set(di, p.num_cameras), inactive);
  for (int j = 0; j < K; ++j) {
    const auto drop = hn::Gt(hn::Set(di, p.drop_below), m[j]);
    sum = hn::Sub(sum, hn::IfThenElseZero(drop, m[j]));
    n = hn::Add(n, hn::VecFromMask(di, drop));  // -1 per dropped view
  }
  const auto valid = hn::Gt(n, hn::Set(di, p.min_views - 1));
  // Lanes with no view (n = 0) are invalid; dividing by max(n, 1) keeps them finite, so the
  // table index below is always in range.
  auto mean = hn::Mul(hn::ConvertTo(df, sum), hn::Set(df, 1.0f / ViewEvidence::kLogScale));
  mean = hn::Div(mean, hn::ConvertTo(df, hn::Max(n, hn::Set(di, 1))));
  mean = hn::Add(mean, hn::Set(df, p.offset));
  const auto in = hn::RebindMask(di, hn::Gt(mean, hn::Set(df, p.log_t)));
  auto e = hn::Mul(hn::Sub(hn::Zero(df), mean), hn::Set(df, p.exp_scale));
  e = hn::Min(e, hn::Set(df, static_cast<float>(p.exp_table_size - 1)));
  e = hn::Max(e, hn::Zero(df));
  const VI b = hn::GatherIndex(di, p.exp_table, intInRange<false>(e));  // e in [0, size - 1]
  const VI b_in = hn::Max(b, hn::Set(di, p.t_byte + 1));
  const VI b_out = p.zero_outside ? hn::Zero(di) : hn::Min(b, hn::Set(di, p.t_byte));
  const VI r = hn::IfThenElseZero(valid, hn::IfThenElse(in, b_in, b_out));
  HWY_ALIGN uint8_t bytes[hn::MaxLanes(d8)];
  hn::Store(hn::DemoteTo(d8, r), d8, bytes);
  std::memcpy(out, bytes, static_cast<size_t>(std::min(static_cast<int>(hn::Lanes(di)), count)));
}

}  // namespace HWY_NAMESPACE
}  // namespace detail
}  // namespace psfs
HWY_AFTER_NAMESPACE();

#endif  // PSFS_HWY_INL_H_ toggle
