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

// Drop, normalise, decide and map to bytes: finalise() of psfs_kernels.cpp lane by lane.
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
  const VI b = hn::GatherIndex(di, p.exp_table, hn::ConvertTo(di, e));
  const VI b_in = hn::Max(b, hn::Set(di, p.t_byte + 1));
  const VI b_out = p.zero_outside ? hn::Zero(di) : hn::Min(b, hn::Set(di, p.t_byte));
  const VI r = hn::IfThenElseZero(valid, hn::IfThenElse(in, b_in, b_out));
  HWY_ALIGN uint8_t bytes[hn::MaxLanes(d8)];
  hn::Store(hn::DemoteTo(d8, r), d8, bytes);
  std::memcpy(out, bytes, static_cast<size_t>(std::min(static_cast<int>(hn::Lanes(di)), count)));
}

template <int K>
void rowHwy(const PsfsRowParams& p, const uint32_t* centres, uint8_t* out) {
  const DI di;
  const DU du;
  const int lanes = static_cast<int>(hn::Lanes(di));
  // The row's projections are read once per frame: fetch them without letting them push the
  // evidence images (gathered every frame) out of the caches.
  for (int i = 0; i < p.num_cameras * p.nxp; i += 16) __builtin_prefetch(centres + i, 0, 0);
  const VI zero = hn::Zero(di);
  for (int x0 = 0; x0 < p.nx; x0 += lanes) {
    // The padded row (nxp) holds whole chunks of 8; wider vectors load its last ones masked
    // (lanes past it read pixel 0: computed, never stored).
    const int left = p.nxp - x0;
    VI sum = zero, inactive = zero;
    VI m[K > 0 ? K : 1];
    for (int j = 0; j < K; ++j) m[j] = hn::Set(di, ViewEvidence::kNoEvidence);
    for (int c = 0; c < p.num_cameras; ++c) {
      const uint32_t* src = centres + size_t(c) * p.nxp + x0;
      const VU uv = left >= lanes ? hn::LoadU(du, src) : hn::MaskedLoad(hn::FirstN(du, left), du, src);
      VI t = centreTerm(p.views[c], uv);
      inactive = hn::Sub(inactive, hn::VecFromMask(di, hn::Gt(t, zero)));
      sum = hn::Add(sum, hn::Min(t, zero));
      for (int j = 0; j < K; ++j) {  // the K lowest terms, ascending
        const VI lo = hn::Min(m[j], t);
        t = hn::Max(m[j], t);
        m[j] = lo;
      }
    }
    finaliseLanes<K>(p, sum, inactive, m, out + x0, p.nx - x0);
  }
}

PsfsRowFn RowKernel(int k) {
  switch (k) {
    case 0: return &rowHwy<0>;
    case 1: return &rowHwy<1>;
    case 2: return &rowHwy<2>;
    case 3: return &rowHwy<3>;
    default: return &rowHwy<4>;
  }
}

}  // namespace HWY_NAMESPACE
}  // namespace detail
}  // namespace psfs
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace psfs {
namespace detail {

HWY_EXPORT(RowKernel);

namespace {
// Index into Highway's dispatch tables of one target (what ChosenTarget::GetIndex() computes
// for the chosen one): the fallback (EMU128 or SCALAR) sits in the last slot.
size_t tableIndexOf(int64_t target) {
  return hwy::Num0BitsBelowLS1Bit_Nonzero64(static_cast<uint64_t>(
      (HWY_CHOSEN_TARGET_SHIFT(target) | HWY_CHOSEN_TARGET_MASK_SCALAR) & HWY_CHOSEN_TARGET_MASK_TARGETS));
}
}  // namespace

std::vector<int64_t> hwyRowTargets() { return hwy::SupportedAndGeneratedTargets(); }

PsfsRowFn hwyRowKernel(int64_t target, int k) { return HWY_DISPATCH_TABLE(RowKernel)[tableIndexOf(target)](k); }

const char* hwyTargetName(int64_t target) { return hwy::TargetName(target); }

int64_t hwyRowTarget(bool vector, bool avx512) {
  const int64_t portable = HWY_EMU128 | HWY_SCALAR;
  int64_t no_avx512 = HWY_AVX3 | HWY_AVX3_DL;
#ifdef HWY_AVX3_ZEN4
  no_avx512 |= HWY_AVX3_ZEN4;
#endif
  const int64_t allowed = !vector ? portable : avx512 ? ~int64_t(0) : ~no_avx512;
  const int64_t usable = hwy::SupportedTargets() & HWY_TARGETS & allowed;
  const int64_t fallback = HWY_TARGETS & portable;
  return usable != 0 ? usable & -usable : fallback & -fallback;  // lower bit: better target
}

}  // namespace detail
}  // namespace psfs
#endif  // HWY_ONCE
