// The multi-projection (shared face samples) pSfS row kernel (psfs_kernels.h: PsfsFaceRowFn),
// one Google Highway source for every instruction set (issue 17), the targets of
// psfs_row_hwy.cpp (same HWY_DISABLED_TARGETS, so the same dispatch tables). Each target does
// the integer and float operations of faceRowScalar (psfs_kernels.cpp, the reference) with the
// same face-buffer protocol, so every target writes the same bytes (test_psfs_fusion_kernels
// checks all compiled targets against it).
//
// Highway 1.0 has neither x86's byte multiply-adds (maddubs) nor masked gathers, so:
//  * the bilinear lerp runs in 32-bit lanes on packed 16-bit pairs (lerpLanes) on every
//    target, SCALAR too; x86 targets (SSSE3 up) take x86's own steps instead (as the
//    hand-written AVX2 and AVX-512 kernels this file replaced did): the index and the row lerp
//    with pmaddwd, the column lerps with pmaddubsw, the weights from 16-entry tables on AVX-512;
//  * a face sampled from the upper voxel gathers only the lanes that need it on AVX2 and
//    AVX-512 (masked gathers, bilinearLanesMasked); elsewhere all lanes (they all stay inside
//    the pair image's replicated border, as do the unmasked + face gathers) and keeps those.
// Such target-specific steps give the same integers as the portable ones (the tests compare
// every target's bytes with faceRowScalar's).
//
// It is the multi-projection kernel on every CPU (psfs_kernels.h: within 3 % of the
// hand-written x86 kernels it replaced), and plusFacesOfRow's vector path.
//
// Highway re-includes this file once per target (foreach_target.h).
#ifndef HWY_DISABLED_TARGETS
#define HWY_DISABLED_TARGETS (HWY_SVE | HWY_SVE2 | HWY_SVE_256 | HWY_SVE2_128 | HWY_RVV)
#endif
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "psfs_face_hwy.cpp"
#include <hwy/foreach_target.h>  // must come before highway.h

#include <hwy/highway.h>

#include <algorithm>
#include <cstdint>
#include <vector>

#include "log_term_table.h"
#include "psfs_kernels.h"
#include "psfs_reconstruction/projection_table.h"

#include "psfs_hwy-inl.h"  // centreTerm, accumulateTerm, finaliseLanes

HWY_BEFORE_NAMESPACE();
namespace psfs {
namespace detail {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

// Whether MulAdd is one fused operation (fmaf's single rounding) here. SSE4, SSSE3, SCALAR and
// EMU128 multiply and add with two roundings: there the log term is logTermOfPair per lane.
#if (HWY_ARCH_X86 && HWY_TARGET <= HWY_AVX2) || \
    (HWY_TARGET == HWY_NEON && (HWY_ARCH_ARM_A64 || defined(__ARM_VFPV4__)))
constexpr bool kFusedMulAdd = true;
#else
constexpr bool kFusedMulAdd = false;
#endif

// x86's vector targets multiply and add int16 pairs into int32 in one instruction (pmaddwd,
// Highway's ReorderWidenMulAccumulate); elsewhere the same sums take 32-bit multiplies.
#undef PSFS_HWY_PAIR_MUL_ADD
#if HWY_ARCH_X86 && HWY_TARGET != HWY_SCALAR && HWY_TARGET != HWY_EMU128
#define PSFS_HWY_PAIR_MUL_ADD 1

// x0 w0 + x1 w1 per 32-bit lane of int16 pairs (x0 | x1 << 16) and (w0 | w1 << 16).
HWY_INLINE VI pairMulAdd(VU x, VU w) {
  const DI di;
  const hn::Repartition<int16_t, DI> d16;
  VI unused = hn::Zero(di);
  return hn::RearrangeToOddPlusEven(
      hn::ReorderWidenMulAccumulate(di, hn::BitCast(d16, x), hn::BitCast(d16, w), hn::Zero(di), unused), unused);
}

// The column lerps as one byte multiply-add (pmaddubsw, which Highway 1.0 lacks): bytes of q
// (a, c, b, d) = (top left, bottom left, top right, bottom right) times bytes (16 - fv, fv,
// 16 - fv, fv) give (left | right << 16), the values of the portable lerp below. AVX-512 takes
// the weights from 16-entry tables (vpermd reads only the low 4 bits of each index: fv is bits
// 16-19 of s).
HWY_INLINE VU columnLerpX86(VU q, VU s) {
#if HWY_TARGET <= HWY_AVX3
  const __m512i wv_table = _mm512_setr_epi32(
      0x00100010, 0x010F010F, 0x020E020E, 0x030D030D, 0x040C040C, 0x050B050B, 0x060A060A, 0x07090709,
      0x08080808, 0x09070907, 0x0A060A06, 0x0B050B05, 0x0C040C04, 0x0D030D03, 0x0E020E02, 0x0F010F01);
  return VU{_mm512_maddubs_epi16(q.raw, _mm512_permutexvar_epi32(_mm512_srli_epi32(s.raw, 16), wv_table))};
#else
  const DU du;
  const VU fv = hn::And(hn::ShiftRight<16>(s), hn::Set(du, 15u));
  const VU wv = hn::Add(hn::Mul(fv, hn::Set(du, 0x00FF00FFu)), hn::Set(du, 0x00100010u));
#if HWY_TARGET <= HWY_AVX2
  return VU{_mm256_maddubs_epi16(q.raw, wv.raw)};
#else
  return VU{_mm_maddubs_epi16(q.raw, wv.raw)};
#endif
#endif
}

// The row lerp's int16 weights (16 - fu | fu << 16), fu = bits 0-3 of s.
HWY_INLINE VU rowWeightsX86(VU s) {
#if HWY_TARGET <= HWY_AVX3
  const __m512i wu_table = _mm512_setr_epi32(
      0x00000010, 0x0001000F, 0x0002000E, 0x0003000D, 0x0004000C, 0x0005000B, 0x0006000A, 0x00070009,
      0x00080008, 0x00090007, 0x000A0006, 0x000B0005, 0x000C0004, 0x000D0003, 0x000E0002, 0x000F0001);
  return VU{_mm512_permutexvar_epi32(s.raw, wu_table)};
#else
  const DU du;
  const VU fu = hn::And(s, hn::Set(du, 15u));
  return hn::Add(hn::Sub(hn::ShiftLeft<16>(fu), fu), hn::Set(du, 16u));
#endif
}
#else
#define PSFS_HWY_PAIR_MUL_ADD 0
#endif

// Byte offsets of the quads under padded fixed-point positions s, packed (su | sv << 16,
// 1/16 px, origin at pixel -kQuadPad, each in [0, 65535]); the pair images are uint16:
// 2 (u0 + v0 stride), u0 = su >> 4, v0 = sv >> 4.
HWY_INLINE VI quadOffsets(const KernelView& v, VU s) {
  const DI di;
  const DU du;
#if PSFS_HWY_PAIR_MUL_ADD
  const hn::Repartition<uint16_t, DI> du16;  // 2 stride < 2^15: PackedUV::kMaxImageSide
  (void)di;
  return pairMulAdd(hn::BitCast(du, hn::ShiftRight<4>(hn::BitCast(du16, s))),
                    hn::Set(du, 2u | (2u * v.quad_stride) << 16));
#else
  return hn::BitCast(di, hn::Add(hn::Mul(hn::ShiftRight<20>(s), hn::Set(du, 2u * v.quad_stride)),
                                 hn::And(hn::ShiftRight<3>(s), hn::Set(du, 0x1FFEu))));
#endif
}

// The bilinear sample of gathered quads q at s: the integers of bilinear() (voxel_arithmetic.h).
// Two pairs in one 32-bit lane of q: bytes (a, c, b, d) = (top left, bottom left, top right,
// bottom right).
HWY_INLINE VI lerpLanes(VU q, VU s) {
#if PSFS_HWY_PAIR_MUL_ADD
  return pairMulAdd(columnLerpX86(q, s), rowWeightsX86(s));
#else
  const DI di;
  const DU du;
  const VU mask8 = hn::Set(du, 0x00FF00FFu);
  const VU ab = hn::And(q, mask8), cd = hn::And(hn::ShiftRight<8>(q), mask8);
  // Both column lerps at once: (left | right << 16) = 16 (a | b << 16) + fv ((c | d << 16) -
  // (a | b << 16)) is linear in the packed pair, so it holds mod 2^32, and left, right lie in
  // [0, 4080]: the halves never carry.
  const VU fv = hn::And(hn::ShiftRight<16>(s), hn::Set(du, 15u));
  const VU lr = hn::Add(hn::ShiftLeft<4>(ab), hn::Mul(hn::Sub(cd, ab), fv));
  const VU fu = hn::And(s, hn::Set(du, 15u));
  // The row lerp is the upper half of one product: (left | right << 16) (fu | (16 - fu) << 16)
  // = left fu + (left (16 - fu) + right fu) << 16 mod 2^32, with left fu < 2^16 and the
  // result (<= 255 * 256) < 2^16. fu + (16 - fu) << 16 = fu (1 - 2^16) + 16 << 16.
  const VU wu = hn::Add(hn::Mul(fu, hn::Set(du, 0xFFFF0001u)), hn::Set(du, 16u << 16));
  return hn::BitCast(di, hn::ShiftRight<16>(hn::Mul(lr, wu)));
#endif
}

// Bilinear samples at padded packed positions s.
HWY_INLINE VI bilinearLanes(const KernelView& v, VU s) {
  const DI di;
  const DU du;
  return lerpLanes(hn::BitCast(du, hn::GatherOffset(di, reinterpret_cast<const int32_t*>(v.pairs),
                                                    quadOffsets(v, s))), s);
}

// Bilinear samples in the lanes of `need`, src in the others. AVX2 and AVX-512 gather only
// those lanes (masked gathers, which Highway 1.0 lacks); elsewhere every lane is gathered (all
// positions lie inside the pair image's replicated border) and the others discarded.
HWY_INLINE VI bilinearLanesMasked(const KernelView& v, VI src, hn::Mask<DI> need, VU s) {
#if PSFS_HWY_PAIR_MUL_ADD && HWY_TARGET <= HWY_AVX3
  const DU du;
  const VI q{_mm512_mask_i32gather_epi32(_mm512_setzero_si512(), need.raw, quadOffsets(v, s).raw, v.pairs, 1)};
  return hn::IfThenElse(need, lerpLanes(hn::BitCast(du, q), s), src);
#elif PSFS_HWY_PAIR_MUL_ADD && HWY_TARGET <= HWY_AVX2
  const DU du;
  const DI di;
  const VI q{_mm256_mask_i32gather_epi32(_mm256_setzero_si256(), reinterpret_cast<const int*>(v.pairs),
                                         quadOffsets(v, s).raw, hn::VecFromMask(di, need).raw, 1)};
  return hn::IfThenElse(need, lerpLanes(hn::BitCast(du, q), s), src);
#else
  return hn::IfThenElse(need, bilinearLanes(v, s), src);
#endif
}

// Positions moved by + or - a chunk's sample offset (du | dv << 16, int16 each). The positions'
// halves stay in [0, 65535], so one 16-bit add or subtract moves both coordinates
// (laneOffset: the offset as the table stores it). SCALAR, whose one lane cannot be split in
// halves, adds the offset as one int32, du + dv 2^16 (the same positions).
#if HWY_TARGET == HWY_SCALAR
HWY_INLINE uint32_t laneOffset(uint32_t off) {
  return (off & 0xFFFF0000u) + static_cast<uint32_t>(static_cast<int32_t>(static_cast<int16_t>(off & 0xFFFFu)));
}
HWY_INLINE VU plusOffset(VU s, VU d) { return hn::Add(s, d); }
HWY_INLINE VU minusOffset(VU s, VU d) { return hn::Sub(s, d); }
#else
HWY_INLINE uint32_t laneOffset(uint32_t off) { return off; }
HWY_INLINE VU plusOffset(VU s, VU d) {
  const hn::Repartition<uint16_t, DU> d16;
  return hn::BitCast(DU(), hn::Add(hn::BitCast(d16, s), hn::BitCast(d16, d)));
}
HWY_INLINE VU minusOffset(VU s, VU d) {
  const hn::Repartition<uint16_t, DU> d16;
  return hn::BitCast(DU(), hn::Sub(hn::BitCast(d16, s), hn::BitCast(d16, d)));
}
#endif

// The offsets along `axis` of the chunk(s) under the vector: one chunk of 8 voxels, or two
// (lanes 0-7 and 8-15) for 16 lanes.
template <class D>
HWY_INLINE hn::Vec<D> chunkOffsets(D d, const uint32_t* off0, const uint32_t* off1, int axis) {
  static_assert(hn::MaxLanes(D()) <= 2 * ProjectionTable::kChunk, "at most two chunks per vector");
#if HWY_TARGET != HWY_SCALAR  // which has no Combine
  if constexpr (hn::MaxLanes(D()) > ProjectionTable::kChunk) {
    const hn::Half<D> dh;
    return hn::Combine(d, hn::Set(dh, laneOffset(off1[axis])), hn::Set(dh, laneOffset(off0[axis])));
  }
#endif
  (void)off1;
  return hn::Set(d, laneOffset(off0[axis]));
}

HWY_INLINE void cswap(VI& a, VI& b) {
  const VI lo = hn::Min(a, b);
  b = hn::Max(a, b);
  a = lo;
}

HWY_INLINE VI middlePair6Lanes(VI s[6]) {  // = middlePair6
  cswap(s[0], s[5]), cswap(s[1], s[3]), cswap(s[2], s[4]);
  cswap(s[1], s[2]), cswap(s[3], s[4]);
  cswap(s[0], s[3]), cswap(s[2], s[5]);
  cswap(s[0], s[1]), cswap(s[2], s[3]), cswap(s[4], s[5]);
  cswap(s[1], s[2]), cswap(s[3], s[4]);
  return hn::Add(s[2], s[3]);
}

// -y or -z faces from a face buffer (kNoFace: sample from this voxel at s), and this row's
// + faces stored back for the next row / layer; `left` entries from buf on belong to this
// camera's row (the buffer is readable 16 entries past the last one).
// A row's packed centres from src, of which `left` belong to the row (a shorter tail is loaded
// masked: its other lanes read 0), and the lanes whose voxel the camera observes.
HWY_INLINE VU centreLanes(const uint32_t* src, int left, uint32_t not_observed, hn::Mask<DI>* obs) {
  const DI di;
  const DU du;
  const bool whole = left >= static_cast<int>(hn::Lanes(di));
  const VU uv = whole ? hn::LoadU(du, src) : hn::MaskedLoad(hn::FirstN(du, left), du, src);
  *obs = hn::RebindMask(di, hn::Ne(uv, hn::Set(du, not_observed)));
  if (!whole) *obs = hn::And(*obs, hn::FirstN(di, left));
  return uv;
}

// Faces (lanes in [0, 0xFFFF]) as uint16 into dst: the first `left` lanes only.
HWY_INLINE void storeFaceLanes(VI faces, uint16_t* dst, int left) {
  const hn::Rebind<uint16_t, DI> d16;
  if (left >= static_cast<int>(hn::Lanes(d16))) {
    hn::StoreU(hn::DemoteTo(d16, faces), d16, dst);
  } else {
    hn::BlendedStore(hn::DemoteTo(d16, faces), hn::FirstN(d16, static_cast<size_t>(left)), d16, dst);
  }
}

HWY_INLINE VI carryFaces(const KernelView& v, uint16_t* buf, int left, VI plus, hn::Mask<DI> obs, VU s) {
  const DI di;
  const hn::Rebind<uint16_t, DI> d16;
  const VI nf = hn::Set(di, kNoFace);
  const VI below = hn::PromoteTo(di, hn::LoadU(d16, buf));
  const auto need = hn::And(obs, hn::Eq(below, nf));
  storeFaceLanes(hn::IfThenElse(obs, plus, nf), buf, left);
  if (hn::AllFalse(di, need)) return below;
  return bilinearLanesMasked(v, below, need, s);
}

// logTermOfPair lane by lane: the same float operations, each fmaf a MulAdd where that is
// fused, else the function's own values from its table (log_term_table.h) per lane.
HWY_INLINE VI logTermLanes(VI m, const int16_t* table) {
  const DI di;
  if constexpr (!kFusedMulAdd) {
    // The clamp: log_term_table.h. Plain loads into an array that is loaded whole, as
    // Highway's own GatherIndex on SSE4, so that the compiler inserts lane by lane.
    const VI index = hn::Min(hn::Max(m, hn::Zero(di)), hn::Set(di, kMaxMedianPair));
    HWY_ALIGN int32_t in[hn::MaxLanes(DI())];
    HWY_ALIGN int32_t lanes[hn::MaxLanes(DI())];
    hn::Store(index, di, in);
    for (size_t i = 0; i < hn::Lanes(di); ++i) lanes[i] = table[in[i]];
    return hn::Load(di, lanes);
  } else {
    const DF df;
    const VF x = hn::ConvertTo(df, hn::Max(m, hn::Set(di, 256)));
#if HWY_ARCH_X86 && HWY_TARGET <= HWY_AVX3
    // getexp / getmant give exactly the exponent and the mantissa in [1, 2) of a normal float.
    const VF e{_mm512_getexp_ps(x.raw)};
    const VF t = hn::Sub(VF{_mm512_getmant_ps(x.raw, _MM_MANT_NORM_1_2, _MM_MANT_SIGN_src)}, hn::Set(df, 1.0f));
#else
    const VI bits = hn::BitCast(di, x);
    const VF e = hn::ConvertTo(df, hn::Sub(hn::ShiftRight<23>(bits), hn::Set(di, 127)));
    const VF f = hn::BitCast(df, hn::Or(hn::And(bits, hn::Set(di, 0x007FFFFF)), hn::Set(di, 0x3F800000)));
    const VF t = hn::Sub(f, hn::Set(df, 1.0f));
#endif
    auto p = hn::Set(df, kLnP6);
    p = hn::MulAdd(p, t, hn::Set(df, kLnP5));
    p = hn::MulAdd(p, t, hn::Set(df, kLnP4));
    p = hn::MulAdd(p, t, hn::Set(df, kLnP3));
    p = hn::MulAdd(p, t, hn::Set(df, kLnP2));
    p = hn::MulAdd(p, t, hn::Set(df, kLnP1));
    p = hn::MulAdd(p, t, hn::Set(df, kLnP0));
    const auto lnx = hn::MulAdd(e, hn::Set(df, kLn2), hn::Mul(p, t));
    // Rounded to nearest even, as rintf does in the default rounding mode.
    // Within [-6400, 0].
    return intInRange<true>(hn::Mul(hn::Sub(lnx, hn::Set(df, kLnFullPair)), hn::Set(df, float(kVoxLogScale))));
  }
}

// Lane i of the result: lane i - 1 of v; lane 0: first. up: kUp's indices.
template <class Indices>
HWY_INLINE VI shiftUpOne(VI v, int32_t first, const Indices& up) {
  const DI di;
  return hn::IfThenElse(hn::FirstN(di, 1), hn::Set(di, first), hn::TableLookupLanes(v, up));
}

// N cameras' terms for the lanes from x0, stage by stage across the cameras: each camera's chain
// of index, gather, lerp, median and log is long and serial, and interleaving a group's chains
// keeps more gathers in flight.
template <int K, int N, class Indices>
HWY_INLINE void faceCameras(const PsfsRowParams& p, int c0, int chunk, int x0, int left, const uint32_t* centres,
                            const uint32_t* offsets, uint16_t* yface, uint16_t* zface, int32_t* carry,
                            const Indices& up, const int16_t* log_table, VI& sum, VI& inactive, VI* m) {
  const DI di;
  const DU du;
  const int lanes = static_cast<int>(hn::Lanes(di));
  const VI zero = hn::Zero(di), no_ev = hn::Set(di, kVoxNoEvidence);
  const VU pad = hn::Set(du, static_cast<uint32_t>(kPad16) * 0x10001u);  // both coordinates
  VU uv[N], base[N];
  VI s[N][6];
  hn::Mask<DI> obs[N];
  // The chunks' offsets: held in registers with 16 lanes (AVX-512 has 32 of them, and two
  // chunks' offsets take a combine), else broadcast where they are used (AVX2: 12 more for 4
  // cameras spill on its 16 registers; 1.07x -> 1.03x the hand-written AVX2 kernel's time).
  constexpr bool kHoldOffsets = hn::MaxLanes(DI()) >= 16;
  const uint32_t* off0[N];
  const uint32_t* off1[N];
  VU held[N][3];
  for (int j = 0; j < N; ++j) {
    const int c = c0 + j;
    const uint32_t* src = centres + size_t(c) * p.nxp + x0;
    uv[j] = centreLanes(src, left, p.views[c].not_observed, &obs[j]);
    base[j] = hn::Add(uv[j], pad);
    off0[j] = offsets + (size_t(c) * p.chunks + chunk) * 3;
    off1[j] = left > ProjectionTable::kChunk ? off0[j] + 3 : off0[j];
  }
  if constexpr (kHoldOffsets)
    for (int j = 0; j < N; ++j)
      for (int a = 0; a < 3; ++a) held[j][a] = chunkOffsets(du, off0[j], off1[j], a);
  auto d = [&](int j, int a) {
    if constexpr (kHoldOffsets) return held[j][a];
    return chunkOffsets(du, off0[j], off1[j], a);
  };
  for (int a = 0; a < 3; ++a)
    for (int j = 0; j < N; ++j) s[j][2 * a + 1] = bilinearLanes(p.views[c0 + j], plusOffset(base[j], d(j, a)));
  for (int j = 0; j < N; ++j) {
    const int c = c0 + j;
    const KernelView& v = p.views[c];
    // -x faces: the previous voxel's +x face where it is observed.
    const int32_t cf = carry[c];
    s[j][0] = shiftUpOne(s[j][1], cf, up);
    const auto lower = hn::MaskFromVec(shiftUpOne(hn::VecFromMask(di, obs[j]), cf >= 0 ? -1 : 0, up));
    const auto need = hn::AndNot(lower, obs[j]);
    if (!hn::AllFalse(di, need)) s[j][0] = bilinearLanesMasked(v, s[j][0], need, minusOffset(base[j], d(j, 0)));
    carry[c] = hn::ExtractLane(hn::VecFromMask(di, obs[j]), lanes - 1) ? hn::ExtractLane(s[j][1], lanes - 1) : -1;
    s[j][2] = carryFaces(v, yface + size_t(c) * p.nxp + x0, left, s[j][3], obs[j], minusOffset(base[j], d(j, 1)));
    s[j][4] = carryFaces(v, zface + size_t(c) * p.nxp + x0, left, s[j][5], obs[j], minusOffset(base[j], d(j, 2)));
  }
  VI tm[N];
  for (int j = 0; j < N; ++j) tm[j] = logTermLanes(middlePair6Lanes(s[j]), log_table);
  for (int j = 0; j < N; ++j) {
    const KernelView& v = p.views[c0 + j];
    // No evidence: not observed, or (with an active mask) the centre's pixel switched off.
    const auto off_view = v.has_mask ? hn::Gt(centreTerm(v, uv[j]), zero) : hn::Not(obs[j]);
    accumulateTerm<K>(hn::IfThenElse(off_view, no_ev, tm[j]), sum, inactive, m);
  }
}

// Cameras per group: 2 for 16 lanes, else 4 (as measured for the hand-written kernels); one on
// the one-lane and emulated targets, where it measured 7 % slower (Zen 5, BM_PsfsFace: AVX2
// -8 %, AVX3 -4 %, SSE4 -2 % with groups).
#if HWY_TARGET == HWY_SCALAR || HWY_TARGET == HWY_EMU128
constexpr int kCameraGroup = 1;
#else
constexpr int kCameraGroup = hn::MaxLanes(DI()) >= 16 ? 2 : 4;
#endif

template <int K>
void faceRowHwy(const PsfsRowParams& p, const uint32_t* centres, const uint32_t* offsets, uint16_t* yface,
                uint16_t* zface, uint8_t* out, const RowSpan& span) {
  const DI di;
  const int lanes = static_cast<int>(hn::Lanes(di));
  const VI zero = hn::Zero(di), no_ev = hn::Set(di, kVoxNoEvidence);
  HWY_ALIGN static constexpr int32_t kUp[16] = {0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14};
  const auto up = hn::SetTableIndices(di, kUp);
  const int16_t* log_table = kFusedMulAdd ? nullptr : logTermTable();
  thread_local std::vector<int32_t> carry_store;
  carry_store.resize(size_t(p.num_cameras));
  int32_t* carry = carry_store.data();  // +x face of voxel x0 - 1 per camera, -1: not observed
  for (int c = 0; c < p.num_cameras; ++c) carry[c] = span.x_carry ? span.x_carry[c] : -1;
  // The row's projections are read once per frame: fetch them without letting them push the
  // evidence images (gathered every frame) out of the caches.
  for (int c = 0; c < p.num_cameras; ++c)
    for (int x = span.begin; x < span.end; x += 16) __builtin_prefetch(centres + c * p.nxp + x, 0, 0);
  const int last = std::min(span.end, p.nx);
  for (int x0 = span.begin; x0 < span.end; x0 += lanes) {
    // A span holds whole chunks of 8: only 16 lanes can overhang it (by one chunk), and those
    // lanes load centre 0 (sampled in bounds, never stored).
    const int left = span.end - x0;
    const int chunk = x0 / ProjectionTable::kChunk;
    VI sum = zero, inactive = zero;
    VI m[K > 0 ? K : 1];
    for (int j = 0; j < K; ++j) m[j] = no_ev;
    int c = 0;
    for (; c + kCameraGroup <= p.num_cameras; c += kCameraGroup)
      faceCameras<K, kCameraGroup>(p, c, chunk, x0, left, centres, offsets, yface, zface, carry, up, log_table, sum, inactive, m);
    for (; c < p.num_cameras; ++c)
      faceCameras<K, 1>(p, c, chunk, x0, left, centres, offsets, yface, zface, carry, up, log_table, sum, inactive, m);
    // Fewer than 8 lanes: the row's last vectors may hold only padding.
    if (x0 < last) finaliseLanes<K>(p, sum, inactive, m, out + x0, last - x0);
  }
}

PsfsFaceRowFn FaceRowKernel(int k) {
  return byOcclusion(k, [&](auto K) -> PsfsFaceRowFn { return &faceRowHwy<decltype(K)::value>; });
}

// plusFacesOfRow (psfs_kernels.h) for x in [x_begin, x_end), whole chunks: each camera's + face
// along `axis` of every observed voxel, kNoFace for the others (whose lanes are not sampled
// where gathers can be masked; elsewhere their positions stay inside the pair image's border).
void PlusFacesRow(const KernelView* views, int num_cameras, int nxp, const uint32_t* centres,
                  const uint32_t* offsets, int axis, uint16_t* faces, int x_begin, int x_end) {
  const DI di;
  const DU du;
  const int lanes = static_cast<int>(hn::Lanes(di));
  const int chunks = nxp / ProjectionTable::kChunk;
  const VU pad = hn::Set(du, static_cast<uint32_t>(kPad16) * 0x10001u);
  const VI nf = hn::Set(di, kNoFace);
  for (int c = 0; c < num_cameras; ++c) {
    const KernelView& v = views[c];
    for (int x0 = x_begin; x0 < x_end; x0 += lanes) {
      const int left = x_end - x0;
      hn::Mask<DI> obs;
      const VU uv = centreLanes(centres + size_t(c) * nxp + x0, left, v.not_observed, &obs);
      const uint32_t* off0 = offsets + (size_t(c) * chunks + x0 / ProjectionTable::kChunk) * 3;
      const uint32_t* off1 = left > ProjectionTable::kChunk ? off0 + 3 : off0;
      const VI f = bilinearLanesMasked(v, nf, obs, plusOffset(hn::Add(uv, pad), chunkOffsets(du, off0, off1, axis)));
      storeFaceLanes(f, faces + size_t(c) * nxp + x0, left);
    }
  }
}

}  // namespace HWY_NAMESPACE
}  // namespace detail
}  // namespace psfs
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace psfs {
namespace detail {

HWY_EXPORT(FaceRowKernel);
HWY_EXPORT(PlusFacesRow);

PsfsFaceRowFn hwyFaceRowKernel(int64_t target, int k) {
  return HWY_DISPATCH_TABLE(FaceRowKernel)[hwyDispatchIndex(target)](k);
}

PlusFacesFn hwyPlusFacesKernel(int64_t target) { return HWY_DISPATCH_TABLE(PlusFacesRow)[hwyDispatchIndex(target)]; }

}  // namespace detail
}  // namespace psfs
#endif  // HWY_ONCE
