#include "psfs_kernels.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <vector>

#include "cpu_dispatch.h"
#include "psfs_reconstruction/projection_table.h"
#include "psfs_reconstruction/simd_dispatch.h"
#include "psfs_reconstruction/view_evidence.h"

#if PSFS_HAVE_X86_DISPATCH
#include <immintrin.h>
#endif

namespace psfs {
namespace detail {
namespace {

// Memory bound, not only accuracy: a sample at the largest offset from the not-observed marker
// (u = 0) or from the image border must stay inside the pair image's replicated border.
static_assert(ProjectionTable::kMaxSampleOffsetPx * PackedUV::kOne <= kPad16,
              "sample offsets must stay within the pair images' border");
static_assert(kVoxLogScale == ViewEvidence::kLogScale && kVoxNoEvidence == ViewEvidence::kNoEvidence &&
                  kVoxQuadPad == ViewEvidence::kQuadPad && kVoxOne == PackedUV::kOne &&
                  kVoxChunk == ProjectionTable::kChunk,
              "voxel_arithmetic.h's constants must be the layout's");
constexpr int32_t kNoEv = ViewEvidence::kNoEvidence;
// The log series' coefficients as an array for the vector kernels' loops.
constexpr float kLnP[7] = {kLnP0, kLnP1, kLnP2, kLnP3, kLnP4, kLnP5, kLnP6};

// ---------------------------------------------------------------------------- scalar -------
// The reference kernels: the per-voxel arithmetic of voxel_arithmetic.h (the GPU's too).

// One camera's walk over the voxels [begin, end) of one row (psfs_kernels.h): the median pair
// of each (scratch for unobserved ones) and the row's +y / +z faces into yf / zf.
// off: this camera's chunk offsets of the row, [chunk * 3 + axis]; carry: the +x face of voxel
// begin - 1 (-1 if it is not observed or begin is 0).
void facePairsScalar(const KernelView& v, int begin, int end, const uint32_t* cen, const uint32_t* off,
                     uint16_t* yf, uint16_t* zf, int32_t* pairs, int32_t carry) {
  for (int x = begin; x < end; ++x) {
    const uint32_t uv = cen[x];
    const bool obs = uv != v.not_observed;
    const uint32_t* o = off + (x / ProjectionTable::kChunk) * 3;
    // The sharing rule (sharedFace) with the lower voxels' + faces carried: a carried face is
    // there exactly when the lower voxel is observed.
    int32_t s[6];
    s[1] = plusFace(v, uv, o[0]);
    s[3] = plusFace(v, uv, o[1]);
    s[5] = plusFace(v, uv, o[2]);
    s[0] = carry >= 0 ? carry : minusFace(v, uv, o[0]);
    s[2] = yf[x] != kNoFace ? yf[x] : minusFace(v, uv, o[1]);
    s[4] = zf[x] != kNoFace ? zf[x] : minusFace(v, uv, o[2]);
    carry = obs ? s[1] : -1;
    yf[x] = obs ? static_cast<uint16_t>(s[3]) : kNoFace;
    zf[x] = obs ? static_cast<uint16_t>(s[5]) : kNoFace;
    pairs[x] = middlePair6(s);
  }
}

// One voxel from its per-camera terms term(c) (> 0: no evidence), as the vector kernels fuse
// them: sum, count of observing views, the K lowest terms.
template <int K, class TermFn>
uint8_t fuseTermsScalar(const PsfsRowParams& p, const TermFn& term) {
  TermFusion<K> f;
  for (int c = 0; c < p.num_cameras; ++c) f.add(term(c));
  return f.finish(p);
}

template <int K>
void rowScalar(const PsfsRowParams& p, const uint32_t* centres, uint8_t* out, const RowSpan& span) {
  for (int x = span.begin; x < std::min(span.end, p.nx); ++x)
    out[x] = fuseTermsScalar<K>(p, [&](int c) { return centreTerm(p.views[c], centres[c * p.nxp + x]); });
}

template <int K>
void faceRowScalar(const PsfsRowParams& p, const uint32_t* centres, const uint32_t* offsets,
                   uint16_t* yface, uint16_t* zface, uint8_t* out, const RowSpan& span) {
  thread_local std::vector<int32_t> pairs;
  pairs.resize(size_t(p.num_cameras) * p.nxp);
  for (int c = 0; c < p.num_cameras; ++c)
    facePairsScalar(p.views[c], span.begin, span.end, centres + c * p.nxp, offsets + c * p.chunks * 3,
                    yface + c * p.nxp, zface + c * p.nxp, pairs.data() + size_t(c) * p.nxp,
                    span.x_carry ? span.x_carry[c] : -1);
  for (int x = span.begin; x < std::min(span.end, p.nx); ++x)
    out[x] = fuseTermsScalar<K>(p, [&](int c) {
      return faceTerm(centreTerm(p.views[c], centres[c * p.nxp + x]), pairs[size_t(c) * p.nxp + x]);
    });
}

// ------------------------------------------------------------------------------ AVX2 -------
#if PSFS_HAVE_X86_DISPATCH
#define PSFS_AVX2 __attribute__((target("avx2,fma"), always_inline)) inline

PSFS_AVX2 __m256i lerpAvx2(__m256i q, __m256i su, __m256i sv) {
  const __m256i fu = _mm256_and_si256(su, _mm256_set1_epi32(15));
  const __m256i fv = _mm256_and_si256(sv, _mm256_set1_epi32(15));
  // Two pairs: bytes (a, c, b, d) = (top left, bottom left, top right, bottom right).
  // bytes (16 - fv, fv, 16 - fv, fv): one maddubs gives the left and right column lerps...
  const __m256i wv = _mm256_add_epi32(_mm256_mullo_epi32(fv, _mm256_set1_epi32(0x00FF00FF)),
                                      _mm256_set1_epi32(0x00100010));
  const __m256i lr = _mm256_maddubs_epi16(q, wv);
  // ...and one madd with int16 (16 - fu, fu) the horizontal lerp.
  const __m256i wu = _mm256_add_epi32(_mm256_sub_epi32(_mm256_slli_epi32(fu, 16), fu),
                                      _mm256_set1_epi32(16));
  return _mm256_madd_epi16(lr, wu);
}

// Positions packed as 16-bit (u | v << 16) per lane, as the AVX-512 kernel keeps them (all lie
// in [0, 65535]: PackedUV::kMaxImageSide): one 16-bit add moves a position by a chunk's packed
// offset, and one madd gives the quad index u0 + v0 * stride.
PSFS_AVX2 __m256i quadIndexAvx2(const KernelView& v, __m256i s) {
  return _mm256_madd_epi16(_mm256_srli_epi16(s, 4), _mm256_set1_epi32(1 | (v.quad_stride << 16)));
}

PSFS_AVX2 __m256i bilinearAvx2(const KernelView& v, __m256i s) {
  const __m256i q = _mm256_i32gather_epi32(reinterpret_cast<const int*>(v.pairs), quadIndexAvx2(v, s), 2);
  return lerpAvx2(q, s, _mm256_srli_epi32(s, 16));
}

// Only the lanes in `need` (all bits set) are sampled; the others keep `src`.
PSFS_AVX2 __m256i bilinearAvx2Masked(const KernelView& v, __m256i src, __m256i need, __m256i s) {
  const __m256i q = _mm256_mask_i32gather_epi32(_mm256_setzero_si256(), reinterpret_cast<const int*>(v.pairs),
                                                quadIndexAvx2(v, s), need, 2);
  return _mm256_blendv_epi8(src, lerpAvx2(q, s, _mm256_srli_epi32(s, 16)), need);
}

// A packed position (the centre plus the padding) moved by a packed offset, +1 or -1 times.
PSFS_AVX2 __m256i plusOffsetAvx2(__m256i s, uint32_t off) {
  return _mm256_add_epi16(s, _mm256_set1_epi32(static_cast<int>(off)));
}
PSFS_AVX2 __m256i minusOffsetAvx2(__m256i s, uint32_t off) {
  return _mm256_sub_epi16(s, _mm256_set1_epi32(static_cast<int>(off)));
}
PSFS_AVX2 __m256i paddedAvx2(__m256i uv) { return _mm256_add_epi16(uv, _mm256_set1_epi16(kPad16)); }

PSFS_AVX2 void cswapAvx2(__m256i& a, __m256i& b) {
  const __m256i lo = _mm256_min_epi32(a, b);
  b = _mm256_max_epi32(a, b);
  a = lo;
}

PSFS_AVX2 __m256i middlePair6Avx2(__m256i s[6]) {
  cswapAvx2(s[0], s[5]), cswapAvx2(s[1], s[3]), cswapAvx2(s[2], s[4]);
  cswapAvx2(s[1], s[2]), cswapAvx2(s[3], s[4]);
  cswapAvx2(s[0], s[3]), cswapAvx2(s[2], s[5]);
  cswapAvx2(s[0], s[1]), cswapAvx2(s[2], s[3]), cswapAvx2(s[4], s[5]);
  cswapAvx2(s[1], s[2]), cswapAvx2(s[3], s[4]);
  return _mm256_add_epi32(s[2], s[3]);
}

// -y or -z faces of 8 voxels from a face buffer (kNoFace: sample from this voxel), and this
// row's + faces stored back for the next row / layer.
PSFS_AVX2 __m256i carryFacesAvx2(const KernelView& v, uint16_t* buf, __m256i plus, __m256i obs,
                                 __m256i minus_s) {
  const __m256i nf = _mm256_set1_epi32(kNoFace);
  const __m256i below = _mm256_cvtepu16_epi32(_mm_loadu_si128(reinterpret_cast<const __m128i*>(buf)));
  const __m256i need = _mm256_and_si256(obs, _mm256_cmpeq_epi32(below, nf));
  const __m256i keep = _mm256_blendv_epi8(nf, plus, obs);
  const __m256i packed = _mm256_permute4x64_epi64(_mm256_packus_epi32(keep, keep), 0x08);
  _mm_storeu_si128(reinterpret_cast<__m128i*>(buf), _mm256_castsi256_si128(packed));
  if (_mm256_testz_si256(need, need)) return below;
  return bilinearAvx2Masked(v, below, need, minus_s);
}

PSFS_AVX2 __m256i logTermAvx2(__m256i m) {  // = logTermOfPair per lane
  const __m256 x = _mm256_cvtepi32_ps(_mm256_max_epi32(m, _mm256_set1_epi32(256)));
  const __m256i bits = _mm256_castps_si256(x);
  const __m256 e = _mm256_cvtepi32_ps(_mm256_sub_epi32(_mm256_srli_epi32(bits, 23), _mm256_set1_epi32(127)));
  const __m256 f = _mm256_castsi256_ps(_mm256_or_si256(_mm256_and_si256(bits, _mm256_set1_epi32(0x007FFFFF)),
                                                       _mm256_set1_epi32(0x3F800000)));
  const __m256 t = _mm256_sub_ps(f, _mm256_set1_ps(1.0f));
  __m256 p = _mm256_set1_ps(kLnP[6]);
  for (int k = 5; k >= 0; --k) p = _mm256_fmadd_ps(p, t, _mm256_set1_ps(kLnP[k]));
  const __m256 lnx = _mm256_fmadd_ps(e, _mm256_set1_ps(kLn2), _mm256_mul_ps(p, t));
  return _mm256_cvtps_epi32(_mm256_mul_ps(_mm256_sub_ps(lnx, _mm256_set1_ps(kLnFullPair)),
                                          _mm256_set1_ps(static_cast<float>(ViewEvidence::kLogScale))));
}

// Finalise 8 voxels: drop, normalise, decide, map to bytes (same steps as finalise()).
template <int K>
PSFS_AVX2 void finaliseAvx2(const PsfsRowParams& p, __m256i sum, __m256i inactive, __m256i* m,
                            uint8_t* out, int count) {
  const __m256i zero = _mm256_setzero_si256();
  __m256i n = _mm256_sub_epi32(_mm256_set1_epi32(p.num_cameras), inactive);
  for (int j = 0; j < K; ++j) {
    const __m256i drop = _mm256_cmpgt_epi32(_mm256_set1_epi32(p.drop_below), m[j]);
    sum = _mm256_sub_epi32(sum, _mm256_and_si256(drop, m[j]));
    n = _mm256_add_epi32(n, drop);
  }
  const __m256i valid = _mm256_cmpgt_epi32(n, _mm256_set1_epi32(p.min_views - 1));
  __m256 mean = _mm256_mul_ps(_mm256_cvtepi32_ps(sum), _mm256_set1_ps(1.0f / ViewEvidence::kLogScale));
  mean = _mm256_div_ps(mean, _mm256_cvtepi32_ps(n));
  mean = _mm256_add_ps(mean, _mm256_set1_ps(p.offset));
  const __m256i in = _mm256_castps_si256(_mm256_cmp_ps(mean, _mm256_set1_ps(p.log_t), _CMP_GT_OQ));
  __m256 e = _mm256_mul_ps(_mm256_sub_ps(_mm256_setzero_ps(), mean), _mm256_set1_ps(p.exp_scale));
  e = _mm256_min_ps(e, _mm256_set1_ps(static_cast<float>(p.exp_table_size - 1)));  // NaN -> max
  e = _mm256_max_ps(e, _mm256_setzero_ps());
  const __m256i b = _mm256_i32gather_epi32(p.exp_table, _mm256_cvttps_epi32(e), 4);
  const __m256i b_in = _mm256_max_epi32(b, _mm256_set1_epi32(p.t_byte + 1));
  const __m256i b_out = p.zero_outside ? zero : _mm256_min_epi32(b, _mm256_set1_epi32(p.t_byte));
  const __m256i r = _mm256_and_si256(_mm256_blendv_epi8(b_out, b_in, in), valid);
  // Pack 8 int32 (0..255) to 8 bytes.
  const __m256i r16 = _mm256_packus_epi32(r, r);  // per 128-bit lane
  const __m256i r8 = _mm256_packus_epi16(r16, r16);
  const uint32_t lo = static_cast<uint32_t>(_mm256_extract_epi32(r8, 0));
  const uint32_t hi = static_cast<uint32_t>(_mm256_extract_epi32(r8, 4));
  uint8_t bytes[8];
  std::memcpy(bytes, &lo, 4);
  std::memcpy(bytes + 4, &hi, 4);
  std::memcpy(out, bytes, static_cast<size_t>(std::min(8, count)));
}

// Adds one camera's term t (8 voxels) to the running sum, inactive count and k lowest terms.
template <int K>
PSFS_AVX2 void accumulateAvx2(__m256i t, __m256i& sum, __m256i& inactive, __m256i* m) {
  const __m256i zero = _mm256_setzero_si256();
  inactive = _mm256_sub_epi32(inactive, _mm256_cmpgt_epi32(t, zero));
  sum = _mm256_add_epi32(sum, _mm256_min_epi32(t, zero));
  for (int j = 0; j < K; ++j) {
    const __m256i lo = _mm256_min_epi32(m[j], t);
    t = _mm256_max_epi32(m[j], t);
    m[j] = lo;
  }
}

PSFS_AVX2 __m256i centreTermAvx2(const KernelView& v, __m256i uv) {
  const __m256i pix = _mm256_add_epi32(
      _mm256_mullo_epi32(_mm256_srli_epi32(uv, 20), _mm256_set1_epi32(v.width)),
      _mm256_srli_epi32(_mm256_and_si256(uv, _mm256_set1_epi32(0xFFFF)), 4));
  const __m256i g = _mm256_i32gather_epi32(reinterpret_cast<const int*>(v.terms), pix, 2);
  return _mm256_srai_epi32(_mm256_slli_epi32(g, 16), 16);
}

// The row's projections are read once per frame: fetch them without letting them push the
// evidence images (gathered every frame) out of the caches.
inline void prefetchRow(const PsfsRowParams& p, const uint32_t* centres, const RowSpan& span) {
  for (int c = 0; c < p.num_cameras; ++c)
    for (int x = span.begin; x < span.end; x += 16)
      _mm_prefetch(reinterpret_cast<const char*>(centres + c * p.nxp + x), _MM_HINT_NTA);
}

// The +x face carried into a span's first voxel per camera.
inline void startCarry(const PsfsRowParams& p, const RowSpan& span, int32_t* carry) {
  for (int c = 0; c < p.num_cameras; ++c) carry[c] = span.x_carry ? span.x_carry[c] : -1;
}

// N cameras' terms for the 8 voxels of chunk `chunk` (from x0), stage by stage across the
// cameras: each camera's chain (index, gather, lerp, median, log) is long and serial, and
// interleaving four keeps more gathers in flight (groups of 2: -2..7 %, of 4: -5..8 % more, of 8: as 4, in the frame's time on a Zen 5 under the AVX2 switch).
// Added to the running sum, inactive count and k lowest terms in camera order.
template <int K, int N>
PSFS_AVX2 void faceCamerasAvx2(const PsfsRowParams& p, int c0, int chunk, int x0, const uint32_t* centres,
                               const uint32_t* offsets, uint16_t* yface, uint16_t* zface, int32_t* carry,
                               __m256i& sum, __m256i& inactive, __m256i* m) {
  const __m256i no_ev = _mm256_set1_epi32(kNoEv);
  const __m256i shift1 = _mm256_setr_epi32(0, 0, 1, 2, 3, 4, 5, 6);
  __m256i uv[N], unobs[N], obs[N], sc[N], s[N][6];
  const uint32_t* off[N];
  for (int j = 0; j < N; ++j) {
    const int c = c0 + j;
    uv[j] = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(centres + c * p.nxp + x0));
    unobs[j] = _mm256_cmpeq_epi32(uv[j], _mm256_set1_epi32(static_cast<int>(p.views[c].not_observed)));
    obs[j] = _mm256_xor_si256(unobs[j], _mm256_set1_epi32(-1));
    sc[j] = paddedAvx2(uv[j]);
    off[j] = offsets + (c * p.chunks + chunk) * 3;
  }
  for (int a = 0; a < 3; ++a)
    for (int j = 0; j < N; ++j) s[j][2 * a + 1] = bilinearAvx2(p.views[c0 + j], plusOffsetAvx2(sc[j], off[j][a]));
  for (int j = 0; j < N; ++j) {
    const int c = c0 + j;
    const KernelView& v = p.views[c];
    // -x faces: the previous voxel's +x face where it is observed.
    const __m256i cf = _mm256_set1_epi32(carry[c]);
    const __m256i lower = _mm256_blend_epi32(_mm256_permutevar8x32_epi32(obs[j], shift1),
                                             _mm256_cmpgt_epi32(cf, _mm256_set1_epi32(-1)), 0x01);
    s[j][0] = _mm256_blend_epi32(_mm256_permutevar8x32_epi32(s[j][1], shift1), cf, 0x01);
    const __m256i need = _mm256_andnot_si256(lower, obs[j]);
    if (!_mm256_testz_si256(need, need))
      s[j][0] = bilinearAvx2Masked(v, s[j][0], need, minusOffsetAvx2(sc[j], off[j][0]));
    carry[c] = _mm256_extract_epi32(obs[j], 7) ? _mm256_extract_epi32(s[j][1], 7) : -1;
    s[j][2] = carryFacesAvx2(v, yface + c * p.nxp + x0, s[j][3], obs[j], minusOffsetAvx2(sc[j], off[j][1]));
    s[j][4] = carryFacesAvx2(v, zface + c * p.nxp + x0, s[j][5], obs[j], minusOffsetAvx2(sc[j], off[j][2]));
  }
  __m256i tm[N];
  for (int j = 0; j < N; ++j) tm[j] = logTermAvx2(middlePair6Avx2(s[j]));
  for (int j = 0; j < N; ++j) {
    const KernelView& v = p.views[c0 + j];
    // No evidence: not observed, or (with an active mask) the centre's pixel switched off.
    const __m256i off_view =
        v.has_mask ? _mm256_cmpgt_epi32(centreTermAvx2(v, uv[j]), _mm256_setzero_si256()) : unobs[j];
    accumulateAvx2<K>(_mm256_blendv_epi8(tm[j], no_ev, off_view), sum, inactive, m);
  }
}

template <int K>
__attribute__((target("avx2,fma"))) void faceRowAvx2(const PsfsRowParams& p, const uint32_t* centres,
                                                     const uint32_t* offsets, uint16_t* yface,
                                                     uint16_t* zface, uint8_t* out, const RowSpan& span) {
  const __m256i no_ev = _mm256_set1_epi32(kNoEv);
  thread_local std::vector<int32_t> carry_store;
  carry_store.resize(size_t(p.num_cameras));
  int32_t* carry = carry_store.data();  // +x face of voxel x0 - 1 per camera, -1: not observed
  startCarry(p, span, carry);
  prefetchRow(p, centres, span);
  const int last = std::min(span.end, p.nx);
  for (int x0 = span.begin; x0 < span.end; x0 += 8) {
    const int chunk = x0 / ProjectionTable::kChunk;
    __m256i sum = _mm256_setzero_si256(), inactive = _mm256_setzero_si256();
    __m256i m[K > 0 ? K : 1];
    for (int j = 0; j < K; ++j) m[j] = no_ev;
    int c = 0;
    for (; c + 4 <= p.num_cameras; c += 4)
      faceCamerasAvx2<K, 4>(p, c, chunk, x0, centres, offsets, yface, zface, carry, sum, inactive, m);
    for (; c + 2 <= p.num_cameras; c += 2)
      faceCamerasAvx2<K, 2>(p, c, chunk, x0, centres, offsets, yface, zface, carry, sum, inactive, m);
    for (; c < p.num_cameras; ++c)
      faceCamerasAvx2<K, 1>(p, c, chunk, x0, centres, offsets, yface, zface, carry, sum, inactive, m);
    finaliseAvx2<K>(p, sum, inactive, m, out + x0, last - x0);  // x0 < last: nxp - nx < 8
  }
}

// + faces of one row along one axis (plusFacesOfRow), 8 voxels (one chunk of offsets) at a time.
__attribute__((target("avx2,fma"))) void plusFacesAvx2(const KernelView* views, int num_cameras, int nxp,
                                                       const uint32_t* centres, const uint32_t* offsets,
                                                       int axis, uint16_t* faces, int x_begin, int x_end) {
  const int chunks = nxp / ProjectionTable::kChunk;
  const __m256i nf = _mm256_set1_epi32(kNoFace);
  for (int c = 0; c < num_cameras; ++c) {
    const KernelView& v = views[c];
    const __m256i not_obs = _mm256_set1_epi32(static_cast<int>(v.not_observed));
    for (int x0 = x_begin; x0 < x_end; x0 += ProjectionTable::kChunk) {
      const __m256i uv = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(centres + c * nxp + x0));
      const uint32_t off = offsets[(c * chunks + x0 / ProjectionTable::kChunk) * 3 + axis];
      const __m256i obs = _mm256_xor_si256(_mm256_cmpeq_epi32(uv, not_obs), _mm256_set1_epi32(-1));
      // Unobserved lanes are not sampled (their positions may lie outside the pair image).
      const __m256i f = bilinearAvx2Masked(v, nf, obs, plusOffsetAvx2(paddedAvx2(uv), off));
      const __m256i packed = _mm256_permute4x64_epi64(_mm256_packus_epi32(f, f), 0x08);
      _mm_storeu_si128(reinterpret_cast<__m128i*>(faces + c * nxp + x0), _mm256_castsi256_si128(packed));
    }
  }
}

// ---------------------------------------------------------------------------- AVX-512 ------
// GCC 12's AVX-512 shift intrinsics start from _mm512_undefined_epi32(), which
// -Wmaybe-uninitialized reports inside inlined callers (GCC bug 105593): silence it here only.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
// The AVX2 kernel 16 voxels at a time (two chunks of the table's sample offsets per step); the
// same integer and float operations lane by lane, so the same bytes. Masks replace blends.
#define PSFS_AVX512 __attribute__((target("avx512f,avx512bw,avx2,fma"), always_inline)) inline

// Bilinear sample at the padded fixed-point position s, packed as 16-bit (u | v << 16) per
// lane: the same integers as bilinear() (all positions lie in [0, 65535]:
// PackedUV::kMaxImageSide). Packed 16-bit arithmetic replaces the split/multiply/add of the
// index (u0 + v0 * stride in one madd), and the weights come from 16-entry tables.
PSFS_AVX512 __m512i quadIndex512(const KernelView& v, __m512i s) {
  return _mm512_madd_epi16(_mm512_srli_epi16(s, 4), _mm512_set1_epi32(1 | (v.quad_stride << 16)));
}

PSFS_AVX512 __m512i lerp512(__m512i q, __m512i s) {
  // vpermd reads only the low 4 bits of each index lane: fu is bits 0-3 of s, fv bits 16-19.
  // Vertical weights, bytes (16 - fv, fv, 16 - fv, fv): one maddubs gives the left and right
  // column lerps; horizontal weights, words (16 - fu, fu): one madd the horizontal lerp.
  const __m512i wv_table = _mm512_setr_epi32(
      0x00100010, 0x010F010F, 0x020E020E, 0x030D030D, 0x040C040C, 0x050B050B, 0x060A060A, 0x07090709,
      0x08080808, 0x09070907, 0x0A060A06, 0x0B050B05, 0x0C040C04, 0x0D030D03, 0x0E020E02, 0x0F010F01);
  const __m512i wu_table = _mm512_setr_epi32(
      0x00000010, 0x0001000F, 0x0002000E, 0x0003000D, 0x0004000C, 0x0005000B, 0x0006000A, 0x00070009,
      0x00080008, 0x00090007, 0x000A0006, 0x000B0005, 0x000C0004, 0x000D0003, 0x000E0002, 0x000F0001);
  const __m512i wv = _mm512_permutexvar_epi32(_mm512_srli_epi32(s, 16), wv_table);
  const __m512i wu = _mm512_permutexvar_epi32(s, wu_table);
  return _mm512_madd_epi16(_mm512_maddubs_epi16(q, wv), wu);
}

PSFS_AVX512 __m512i bilinear512(const KernelView& v, __m512i s) {
  return lerp512(_mm512_i32gather_epi32(quadIndex512(v, s), v.pairs, 2), s);
}

// Only the lanes in `need` are sampled (a masked gather loads only those); the others keep src.
PSFS_AVX512 __m512i bilinear512Masked(const KernelView& v, __m512i src, __mmask16 need, __m512i s) {
  const __m512i q = _mm512_mask_i32gather_epi32(_mm512_setzero_si512(), need, quadIndex512(v, s), v.pairs, 2);
  return _mm512_mask_mov_epi32(src, need, lerp512(q, s));
}

PSFS_AVX512 void cswap512(__m512i& a, __m512i& b) {
  const __m512i lo = _mm512_min_epi32(a, b);
  b = _mm512_max_epi32(a, b);
  a = lo;
}

PSFS_AVX512 __m512i middlePair6_512(__m512i s[6]) {
  cswap512(s[0], s[5]), cswap512(s[1], s[3]), cswap512(s[2], s[4]);
  cswap512(s[1], s[2]), cswap512(s[3], s[4]);
  cswap512(s[0], s[3]), cswap512(s[2], s[5]);
  cswap512(s[0], s[1]), cswap512(s[2], s[3]), cswap512(s[4], s[5]);
  cswap512(s[1], s[2]), cswap512(s[3], s[4]);
  return _mm512_add_epi32(s[2], s[3]);
}

// -y or -z faces of 16 voxels from a face buffer (kNoFace: sample from this voxel at s), and
// this row's + faces stored back for the next row / layer. buf is readable 16 entries on.
PSFS_AVX512 __m512i carryFaces512(const KernelView& v, uint16_t* buf, __mmask16 lanes, __m512i plus,
                                  __mmask16 obs, __m512i s) {
  const __m512i nf = _mm512_set1_epi32(kNoFace);
  const __m512i below = _mm512_cvtepu16_epi32(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(buf)));
  const __mmask16 need = obs & _mm512_cmpeq_epi32_mask(below, nf);
  _mm512_mask_cvtepi32_storeu_epi16(buf, lanes, _mm512_mask_mov_epi32(nf, obs, plus));
  return need ? bilinear512Masked(v, below, need, s) : below;
}

PSFS_AVX512 __m512i logTerm512(__m512i m) {  // = logTermOfPair per lane
  const __m512 x = _mm512_cvtepi32_ps(_mm512_max_epi32(m, _mm512_set1_epi32(256)));
  // getexp / getmant give exactly the exponent and the mantissa in [1, 2) of a normal float.
  const __m512 e = _mm512_getexp_ps(x);
  const __m512 t = _mm512_sub_ps(_mm512_getmant_ps(x, _MM_MANT_NORM_1_2, _MM_MANT_SIGN_src), _mm512_set1_ps(1.0f));
  __m512 p = _mm512_set1_ps(kLnP[6]);
  for (int k = 5; k >= 0; --k) p = _mm512_fmadd_ps(p, t, _mm512_set1_ps(kLnP[k]));
  const __m512 lnx = _mm512_fmadd_ps(e, _mm512_set1_ps(kLn2), _mm512_mul_ps(p, t));
  return _mm512_cvtps_epi32(_mm512_mul_ps(_mm512_sub_ps(lnx, _mm512_set1_ps(kLnFullPair)),
                                          _mm512_set1_ps(static_cast<float>(ViewEvidence::kLogScale))));
}

template <int K>
PSFS_AVX512 void accumulate512(__m512i t, __m512i& sum, __m512i& inactive, __m512i* m) {
  const __m512i zero = _mm512_setzero_si512();
  inactive = _mm512_mask_add_epi32(inactive, _mm512_cmpgt_epi32_mask(t, zero), inactive, _mm512_set1_epi32(1));
  sum = _mm512_add_epi32(sum, _mm512_min_epi32(t, zero));
  for (int j = 0; j < K; ++j) {
    const __m512i lo = _mm512_min_epi32(m[j], t);
    t = _mm512_max_epi32(m[j], t);
    m[j] = lo;
  }
}

template <int K>
PSFS_AVX512 void finalise512(const PsfsRowParams& p, __m512i sum, __m512i inactive, __m512i* m,
                             uint8_t* out, int count) {
  const __m512i zero = _mm512_setzero_si512();
  const __m512i one = _mm512_set1_epi32(1);
  __m512i n = _mm512_sub_epi32(_mm512_set1_epi32(p.num_cameras), inactive);
  for (int j = 0; j < K; ++j) {
    const __mmask16 drop = _mm512_cmpgt_epi32_mask(_mm512_set1_epi32(p.drop_below), m[j]);
    sum = _mm512_mask_sub_epi32(sum, drop, sum, m[j]);
    n = _mm512_mask_sub_epi32(n, drop, n, one);
  }
  const __mmask16 valid = _mm512_cmpgt_epi32_mask(n, _mm512_set1_epi32(p.min_views - 1));
  __m512 mean = _mm512_mul_ps(_mm512_cvtepi32_ps(sum), _mm512_set1_ps(1.0f / ViewEvidence::kLogScale));
  mean = _mm512_div_ps(mean, _mm512_cvtepi32_ps(n));
  mean = _mm512_add_ps(mean, _mm512_set1_ps(p.offset));
  const __mmask16 in = _mm512_cmp_ps_mask(mean, _mm512_set1_ps(p.log_t), _CMP_GT_OQ);
  __m512 e = _mm512_mul_ps(_mm512_sub_ps(_mm512_setzero_ps(), mean), _mm512_set1_ps(p.exp_scale));
  e = _mm512_min_ps(e, _mm512_set1_ps(static_cast<float>(p.exp_table_size - 1)));  // NaN -> max
  e = _mm512_max_ps(e, _mm512_setzero_ps());
  const __m512i b = _mm512_i32gather_epi32(_mm512_cvttps_epi32(e), p.exp_table, 4);
  const __m512i b_in = _mm512_max_epi32(b, _mm512_set1_epi32(p.t_byte + 1));
  const __m512i b_out = p.zero_outside ? zero : _mm512_min_epi32(b, _mm512_set1_epi32(p.t_byte));
  const __m512i r = _mm512_maskz_mov_epi32(valid, _mm512_mask_mov_epi32(b_out, in, b_in));
  uint8_t bytes[16];
  _mm_storeu_si128(reinterpret_cast<__m128i*>(bytes), _mm512_cvtusepi32_epi8(r));
  std::memcpy(out, bytes, static_cast<size_t>(std::min(16, count)));
}

PSFS_AVX512 __m512i centreTerm512(const KernelView& v, __m512i uv) {
  const __m512i pix = _mm512_add_epi32(
      _mm512_mullo_epi32(_mm512_srli_epi32(uv, 20), _mm512_set1_epi32(v.width)),
      _mm512_srli_epi32(_mm512_and_si512(uv, _mm512_set1_epi32(0xFFFF)), 4));
  const __m512i g = _mm512_i32gather_epi32(pix, v.terms, 2);
  return _mm512_srai_epi32(_mm512_slli_epi32(g, 16), 16);
}

// 16 packed centres, or 8 (upper lanes 0) at the end of a span (or row) that holds an odd
// number of chunks. Masked loads only where needed: on Zen 4 a masked load that misses the cache costs
// several times a plain one (measured without the row prefetch: 15 ms instead of 5 ms for
// the 16 mm multi-projection volume, 1 thread).
PSFS_AVX512 __m512i loadCentres512(const uint32_t* p, bool two) {
  return two ? _mm512_loadu_si512(p) : _mm512_maskz_loadu_epi32(__mmask16(0x00FF), p);
}

// Offsets of two consecutive chunks (lanes 0-7 and 8-15) as packed int16 (du | dv << 16).
PSFS_AVX512 __m512i chunkOffsets512(const uint32_t* off0, const uint32_t* off1, int axis) {
  return _mm512_inserti64x4(_mm512_set1_epi32(static_cast<int32_t>(off0[axis])),
                            _mm256_set1_epi32(static_cast<int32_t>(off1[axis])), 1);
}

// N cameras' terms for the 16 voxels from x0 (lanes: one or two chunks), stage by stage across
// the cameras as faceCamerasAvx2 does (groups of 2 on a Zen 5: -16 % in the frame's
// multi-projection time, -18 % with skipping; groups of 4 no better).
constexpr int kAvx512Group = 2;
template <int K, int N>
PSFS_AVX512 void faceCameras512(const PsfsRowParams& p, int c0, int chunk, int x0, bool two, __mmask16 lanes,
                                const uint32_t* centres, const uint32_t* offsets, uint16_t* yface,
                                uint16_t* zface, int32_t* carry, __m512i& sum, __m512i& inactive, __m512i* m) {
  const __m512i no_ev = _mm512_set1_epi32(kNoEv);
  const __m512i pad = _mm512_set1_epi16(kPad16);
  __m512i uv[N], pp[N], d[N][3], s[N][6];
  __mmask16 obs[N];
  for (int j = 0; j < N; ++j) {
    const int c = c0 + j;
    uv[j] = loadCentres512(centres + c * p.nxp + x0, two);
    obs[j] = lanes & _mm512_cmpneq_epi32_mask(uv[j], _mm512_set1_epi32(static_cast<int>(p.views[c].not_observed)));
    // Both halves of uv plus the pad, as 16-bit lanes; the offsets are packed (du | dv << 16)
    // int16 pairs already, so one 16-bit add / sub gives both coordinates of a sample.
    pp[j] = _mm512_add_epi16(uv[j], pad);
    const uint32_t* off0 = offsets + (c * p.chunks + chunk) * 3;
    const uint32_t* off1 = two ? off0 + 3 : off0;
    for (int a = 0; a < 3; ++a) d[j][a] = chunkOffsets512(off0, off1, a);
  }
  for (int a = 0; a < 3; ++a)
    for (int j = 0; j < N; ++j) s[j][2 * a + 1] = bilinear512(p.views[c0 + j], _mm512_add_epi16(pp[j], d[j][a]));
  for (int j = 0; j < N; ++j) {
    const int c = c0 + j;
    const KernelView& v = p.views[c];
    // -x faces: the previous voxel's +x face where it is observed.
    const int32_t cf = carry[c];
    s[j][0] = _mm512_alignr_epi32(s[j][1], _mm512_set1_epi32(cf), 15);
    const __mmask16 lower = static_cast<__mmask16>((obs[j] << 1) | (cf >= 0 ? 1 : 0));
    const __mmask16 need = obs[j] & static_cast<__mmask16>(~lower);
    if (need) s[j][0] = bilinear512Masked(v, s[j][0], need, _mm512_sub_epi16(pp[j], d[j][0]));
    carry[c] = (obs[j] >> 15) & 1 ? _mm_extract_epi32(_mm512_extracti32x4_epi32(s[j][1], 3), 3) : -1;
    s[j][2] = carryFaces512(v, yface + c * p.nxp + x0, lanes, s[j][3], obs[j], _mm512_sub_epi16(pp[j], d[j][1]));
    s[j][4] = carryFaces512(v, zface + c * p.nxp + x0, lanes, s[j][5], obs[j], _mm512_sub_epi16(pp[j], d[j][2]));
  }
  __m512i tm[N];
  for (int j = 0; j < N; ++j) tm[j] = logTerm512(middlePair6_512(s[j]));
  for (int j = 0; j < N; ++j) {
    const KernelView& v = p.views[c0 + j];
    const __mmask16 off_view = v.has_mask ? _mm512_cmpgt_epi32_mask(centreTerm512(v, uv[j]), _mm512_setzero_si512())
                                          : static_cast<__mmask16>(~obs[j]);
    accumulate512<K>(_mm512_mask_mov_epi32(tm[j], off_view, no_ev), sum, inactive, m);
  }
}

template <int K>
__attribute__((target("avx512f,avx512bw,avx2,fma"))) void faceRowAvx512(
    const PsfsRowParams& p, const uint32_t* centres, const uint32_t* offsets, uint16_t* yface,
    uint16_t* zface, uint8_t* out, const RowSpan& span) {
  const __m512i no_ev = _mm512_set1_epi32(kNoEv);
  thread_local std::vector<int32_t> carry_store;
  carry_store.resize(size_t(p.num_cameras));
  int32_t* carry = carry_store.data();  // +x face of voxel x0 - 1 per camera, -1: not observed
  startCarry(p, span, carry);
  prefetchRow(p, centres, span);
  const int last = std::min(span.end, p.nx);
  for (int x0 = span.begin; x0 < span.end; x0 += 16) {
    const bool two = x0 + 8 < span.end;
    const __mmask16 lanes = two ? __mmask16(0xFFFF) : __mmask16(0x00FF);
    const int chunk = x0 / ProjectionTable::kChunk;
    __m512i sum = _mm512_setzero_si512(), inactive = _mm512_setzero_si512();
    __m512i m[K > 0 ? K : 1];
    for (int j = 0; j < K; ++j) m[j] = no_ev;
    int c = 0;
    for (; c + kAvx512Group <= p.num_cameras; c += kAvx512Group)
      faceCameras512<K, kAvx512Group>(p, c, chunk, x0, two, lanes, centres, offsets, yface, zface, carry, sum, inactive, m);
    for (; c < p.num_cameras; ++c)
      faceCameras512<K, 1>(p, c, chunk, x0, two, lanes, centres, offsets, yface, zface, carry, sum, inactive, m);
    finalise512<K>(p, sum, inactive, m, out + x0, last - x0);  // x0 < last: nxp - nx < 8
  }
}

// + faces of one row along one axis (plusFacesOfRow), 16 voxels at a time.
__attribute__((target("avx512f,avx512bw,avx2,fma"))) void plusFaces512(
    const KernelView* views, int num_cameras, int nxp, const uint32_t* centres,
    const uint32_t* offsets, int axis, uint16_t* faces, int x_begin, int x_end) {
  const int chunks = nxp / ProjectionTable::kChunk;
  for (int c = 0; c < num_cameras; ++c)
    for (int x0 = x_begin; x0 < x_end; x0 += 16) {
      const bool two = x0 + 8 < x_end;
      const __mmask16 lanes = two ? __mmask16(0xFFFF) : __mmask16(0x00FF);
      const __m512i uv = loadCentres512(centres + c * nxp + x0, two);
      const __mmask16 obs = lanes & _mm512_cmpneq_epi32_mask(uv, _mm512_set1_epi32(static_cast<int>(views[c].not_observed)));
      const uint32_t* off0 = offsets + (c * chunks + x0 / ProjectionTable::kChunk) * 3;
      const __m512i d = chunkOffsets512(off0, two ? off0 + 3 : off0, axis);
      const __m512i f = bilinear512(views[c], _mm512_add_epi16(_mm512_add_epi16(uv, _mm512_set1_epi16(kPad16)), d));
      _mm512_mask_cvtepi32_storeu_epi16(faces + c * nxp + x0, lanes,
                                        _mm512_mask_mov_epi32(_mm512_set1_epi32(kNoFace), obs, f));
    }
}

bool useAvx512() { return avx512KernelsActive(); }
#pragma GCC diagnostic pop
#endif

// The hand-written x86 kernels where the CPU and switches allow; else the Highway kernel, like
// selectPsfsRow (its SCALAR target measured 0.94x faceRowScalar's time, SSE4 0.58x;
// docs/benchmarks.md).
template <int K>
PsfsFaceRowFn pickFace(bool vector) {
#if PSFS_HAVE_X86_DISPATCH
  if (vector && useAvx512()) return &faceRowAvx512<K>;
  if (vector) return &faceRowAvx2<K>;
#endif
  // No AVX2 (an older x86, ARM): Highway's best target (SSE4, NEON), unless scalar is forced.
  return hwyFaceRowKernel(hwyRowTarget(!scalarKernelsForced(), false), K);
}

PsfsRowFn referenceRow(int k) {
  return byOcclusion(k, [&](auto K) -> PsfsRowFn { return &rowScalar<decltype(K)::value>; });
}

std::atomic<int64_t> g_forced_row_target{0};
std::atomic<int64_t> g_forced_face_target{0};

}  // namespace

void forceRowKernelForTest(int64_t target) { g_forced_row_target.store(target); }

PsfsRowFn selectPsfsRow(int k, bool vector) {
  if (k < 0 || k > kMaxOccludedViews) throw std::invalid_argument("psfs: occluded_views must be in 0..4");
  const int64_t forced = g_forced_row_target.load(std::memory_order_relaxed);
  if (forced == -1) return referenceRow(k);
  if (forced != 0) return hwyRowKernel(forced, k);
  // `vector` is false on a CPU without AVX2 (an older x86, ARM): Highway's best target there
  // (SSE4, NEON) unless the scalar kernels are forced.
  return hwyRowKernel(hwyRowTarget(vector || !scalarKernelsForced(), avx512KernelsActive()), k);
}

void forceFaceRowKernelForTest(int64_t target) { g_forced_face_target.store(target); }

PsfsFaceRowFn selectPsfsFaceRow(int k, bool vector) {
  if (k < 0 || k > kMaxOccludedViews) throw std::invalid_argument("psfs: occluded_views must be in 0..4");
  const int64_t forced = g_forced_face_target.load(std::memory_order_relaxed);
  if (forced > 0) return hwyFaceRowKernel(forced, k);
  if (forced == -1) {
    return byOcclusion(k, [&](auto K) -> PsfsFaceRowFn { return &faceRowScalar<decltype(K)::value>; });
  }
  // 0 and -2: the default
  return byOcclusion(k, [&](auto K) -> PsfsFaceRowFn { return pickFace<decltype(K)::value>(vector); });
}

void plusFacesOfRow(const KernelView* views, int num_cameras, int nxp, const uint32_t* centres,
                    const uint32_t* offsets, int axis, uint16_t* faces, int x_begin, int x_end) {
  if (x_end < 0) x_end = nxp;
  // The vector paths write whole chunks: a range inside one would overwrite faces kept.
  if (x_begin < 0 || x_end > nxp || x_begin % ProjectionTable::kChunk != 0 || x_end % ProjectionTable::kChunk != 0)
    throw std::logic_error("psfs::plusFacesOfRow: x range must be whole chunks of the row");
#if PSFS_HAVE_X86_DISPATCH
  if (useAvx512()) {
    plusFaces512(views, num_cameras, nxp, centres, offsets, axis, faces, x_begin, x_end);
    return;
  }
  if (vectorKernelsActive()) {
    plusFacesAvx2(views, num_cameras, nxp, centres, offsets, axis, faces, x_begin, x_end);
    return;
  }
#endif
  const int chunks = nxp / ProjectionTable::kChunk;
  for (int c = 0; c < num_cameras; ++c)
    for (int x = x_begin; x < x_end; ++x) {
      const uint32_t uv = centres[c * nxp + x];
      const uint32_t off = offsets[(c * chunks + x / ProjectionTable::kChunk) * 3 + axis];
      faces[c * nxp + x] = uv == views[c].not_observed ? kNoFace : static_cast<uint16_t>(plusFace(views[c], uv, off));
    }
}

void plusXFaces(const KernelView* views, int num_cameras, int nxp, const uint32_t* centres,
                const uint32_t* offsets, int x, int32_t* carry) {
  const int chunks = nxp / ProjectionTable::kChunk;
  for (int c = 0; c < num_cameras; ++c) {
    const uint32_t uv = centres[c * nxp + x];
    carry[c] = uv == views[c].not_observed
                   ? -1
                   : plusFace(views[c], uv, offsets[(c * chunks + x / ProjectionTable::kChunk) * 3]);
  }
}

void medianPairsOfRow(const KernelView* views, int num_cameras, int nxp,
                      const uint32_t* centres, const uint32_t* offsets, uint16_t* yface,
                      uint16_t* zface, int32_t* pairs) {
  const int chunks = nxp / ProjectionTable::kChunk;
  for (int c = 0; c < num_cameras; ++c)
    facePairsScalar(views[c], 0, nxp, centres + c * nxp, offsets + c * chunks * 3, yface + c * nxp,
                    zface + c * nxp, pairs + size_t(c) * nxp, -1);
}

int observeByte(const KernelView& view, const uint8_t* likelihood, uint32_t centre) {
  const int pix = pixelOf(centre, view.width);
  return view.terms[pix] > 0 ? -1 : likelihood[pix];
}

}  // namespace detail
}  // namespace psfs
