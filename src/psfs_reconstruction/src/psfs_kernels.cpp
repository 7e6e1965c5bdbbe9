#include "psfs_kernels.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include "cpu_dispatch.h"
#include "psfs_reconstruction/projection_table.h"
#include "psfs_reconstruction/view_evidence.h"

#if PSFS_HAVE_X86_DISPATCH
#include <immintrin.h>
#endif

namespace psfs {
namespace detail {
namespace {

constexpr int kPad16 = ViewEvidence::kQuadPad * PackedUV::kOne - PackedUV::kOne / 2;  // 16P - 8
constexpr int32_t kNoEv = ViewEvidence::kNoEvidence;

// ---------------------------------------------------------------------------- scalar -------

inline int pixelOf(uint32_t uv, int width) { return PackedUV::pixelIndex(uv, width); }

// Bilinear sample at padded fixed-point position (su, sv) (1/16 px, origin at pixel -kQuadPad):
// the same integer arithmetic as maddubs + madd in the AVX2 kernel. Result in [0, 255 * 256].
inline int32_t bilinear(const KernelView& v, int32_t su, int32_t sv) {
  const int32_t u0 = su >> 4, fu = su & 15, v0 = sv >> 4, fv = sv & 15;
  const uint16_t* q = v.pairs + v0 * v.quad_stride + u0;
  const int32_t a = q[0] & 255, c = q[0] >> 8, b = q[1] & 255, d = q[1] >> 8;
  const int32_t left = a * (16 - fv) + c * fv;
  const int32_t right = b * (16 - fv) + d * fv;
  return left * (16 - fu) + right * fu;  // = top (16 - fv) + bottom fv, the same integer
}

inline void cswap(int32_t& a, int32_t& b) {
  const int32_t lo = std::min(a, b), hi = std::max(a, b);
  a = lo;
  b = hi;
}

// Sum of the two middle values of 6 (optimal 12-comparator sorting network, pruned by the
// compiler to what positions 2 and 3 need).
inline int32_t middlePair6(int32_t s[6]) {
  cswap(s[0], s[5]), cswap(s[1], s[3]), cswap(s[2], s[4]);
  cswap(s[1], s[2]), cswap(s[3], s[4]);
  cswap(s[0], s[3]), cswap(s[2], s[5]);
  cswap(s[0], s[1]), cswap(s[2], s[3]), cswap(s[4], s[5]);
  cswap(s[1], s[2]), cswap(s[3], s[4]);
  return s[2] + s[3];
}

// Sum of the two middle bilinear samples (0 .. 2 * 255 * 256).
inline int32_t medianPair(const KernelView& v, uint32_t uv, const uint32_t* off) {
  const int32_t uf = static_cast<int32_t>(uv & 0xFFFFu) + kPad16;
  const int32_t vf = static_cast<int32_t>(uv >> 16) + kPad16;
  int32_t s[6];
  for (int a = 0; a < 3; ++a) {
    const int32_t du = static_cast<int16_t>(off[a] & 0xFFFFu);
    const int32_t dv = static_cast<int32_t>(off[a]) >> 16;
    s[2 * a] = bilinear(v, uf + du, vf + dv);
    s[2 * a + 1] = bilinear(v, uf - du, vf - dv);
  }
  return middlePair6(s);
}

inline int32_t medianByte(const KernelView& v, uint32_t uv, const uint32_t* off) {
  return (medianPair(v, uv, off) + 256) >> 9;
}

// Log term of a median pair m (likelihood m / 130560), floored at half a byte step like
// ViewEvidence::logTerm: round(1024 ln(max(m, 256) / 130560)). Computed, not looked up (a
// gather costs more than these dozen operations): m = 2^e f, f in [1, 2),
// ln f = 2 atanh(z), z = (f - 1) / (f + 1) in [0, 1/3), series to z^11 (error < 1e-7).
// Same float operations (with FMA) as logTermAvx2, so both kernels give the same bytes.
constexpr float kLn2 = 0.693147180559945f;
constexpr float kLnFullPair = 11.779591f;  // ln(2 * 255 * 256) = ln 130560
inline int32_t logTermOfPair(int32_t m) {
  const float x = static_cast<float>(std::max(m, 256));
  uint32_t bits;
  std::memcpy(&bits, &x, 4);
  const float e = static_cast<float>(static_cast<int32_t>(bits >> 23) - 127);
  const uint32_t fb = (bits & 0x007FFFFFu) | 0x3F800000u;
  float f;
  std::memcpy(&f, &fb, 4);
  const float z = (f - 1.0f) / (f + 1.0f);
  const float z2 = z * z;
  float p = std::fma(z2, 2.0f / 11.0f, 2.0f / 9.0f);
  p = std::fma(z2, p, 2.0f / 7.0f);
  p = std::fma(z2, p, 2.0f / 5.0f);
  p = std::fma(z2, p, 2.0f / 3.0f);
  p = std::fma(z2, p, 2.0f);
  const float lnx = std::fma(e, kLn2, z * p);
  return static_cast<int32_t>(std::nearbyint((lnx - kLnFullPair) * static_cast<float>(ViewEvidence::kLogScale)));
}

inline uint8_t finalise(const PsfsRowParams& p, int32_t sum, int32_t n, const int32_t* m, int k) {
  for (int j = 0; j < k; ++j)
    if (m[j] < p.drop_below) {
      sum -= m[j];
      n -= 1;
    }
  if (n < p.min_views) return 0;
  float mean = static_cast<float>(sum) * (1.0f / ViewEvidence::kLogScale);
  mean = mean / static_cast<float>(n);
  mean = mean + p.offset;
  const bool in = mean > p.log_t;
  float e = -mean * p.exp_scale;
  e = std::min(e, static_cast<float>(p.exp_table_size - 1));
  e = std::max(e, 0.0f);
  const int32_t b = p.exp_table[static_cast<int32_t>(e)];
  if (in) return static_cast<uint8_t>(std::max(b, p.t_byte + 1));
  return p.zero_outside ? 0 : static_cast<uint8_t>(std::min(b, p.t_byte));
}

template <int K, bool kMulti>
void rowScalar(const PsfsRowParams& p, const uint32_t* centres, const uint32_t* offsets,
               uint8_t* out) {
  for (int x = 0; x < p.nx; ++x) {
    int32_t sum = 0, inactive = 0;
    int32_t m[K > 0 ? K : 1];
    for (int j = 0; j < K; ++j) m[j] = kNoEv;
    for (int c = 0; c < p.num_cameras; ++c) {
      const KernelView& v = p.views[c];
      const uint32_t uv = centres[c * p.nxp + x];
      int32_t t = v.terms[pixelOf(uv, v.width)];
      if (kMulti) {
        const uint32_t* off = offsets + (c * p.chunks + x / ProjectionTable::kChunk) * 3;
        const int32_t tm = logTermOfPair(medianPair(v, uv, off));
        t = t > 0 ? kNoEv : tm;
      }
      inactive += t > 0;
      sum += std::min(t, 0);
      for (int j = 0; j < K; ++j) {
        const int32_t lo = std::min(m[j], t);
        t = std::max(m[j], t);
        m[j] = lo;
      }
    }
    out[x] = finalise(p, sum, p.num_cameras - inactive, m, K);
  }
}

// ------------------------------------------------------------------------------ AVX2 -------
#if PSFS_HAVE_X86_DISPATCH
#define PSFS_AVX2 __attribute__((target("avx2,fma"), always_inline)) inline

PSFS_AVX2 __m256i bilinearAvx2(const KernelView& v, __m256i su, __m256i sv) {
  const __m256i u0 = _mm256_srli_epi32(su, 4), fu = _mm256_and_si256(su, _mm256_set1_epi32(15));
  const __m256i v0 = _mm256_srli_epi32(sv, 4), fv = _mm256_and_si256(sv, _mm256_set1_epi32(15));
  const __m256i idx = _mm256_add_epi32(_mm256_mullo_epi32(v0, _mm256_set1_epi32(v.quad_stride)), u0);
  // Two pairs: bytes (a, c, b, d) = (top left, bottom left, top right, bottom right).
  const __m256i q = _mm256_i32gather_epi32(reinterpret_cast<const int*>(v.pairs), idx, 2);
  // bytes (16 - fv, fv, 16 - fv, fv): one maddubs gives the left and right column lerps...
  const __m256i wv = _mm256_add_epi32(_mm256_mullo_epi32(fv, _mm256_set1_epi32(0x00FF00FF)),
                                      _mm256_set1_epi32(0x00100010));
  const __m256i lr = _mm256_maddubs_epi16(q, wv);
  // ...and one madd with int16 (16 - fu, fu) the horizontal lerp.
  const __m256i wu = _mm256_add_epi32(_mm256_sub_epi32(_mm256_slli_epi32(fu, 16), fu),
                                      _mm256_set1_epi32(16));
  return _mm256_madd_epi16(lr, wu);
}

PSFS_AVX2 void cswapAvx2(__m256i& a, __m256i& b) {
  const __m256i lo = _mm256_min_epi32(a, b);
  b = _mm256_max_epi32(a, b);
  a = lo;
}

PSFS_AVX2 __m256i medianPairAvx2(const KernelView& v, __m256i uv, const uint32_t* off) {
  const __m256i pad = _mm256_set1_epi32(kPad16);
  const __m256i uf = _mm256_add_epi32(_mm256_and_si256(uv, _mm256_set1_epi32(0xFFFF)), pad);
  const __m256i vf = _mm256_add_epi32(_mm256_srli_epi32(uv, 16), pad);
  __m256i s[6];
  for (int a = 0; a < 3; ++a) {
    const __m256i du = _mm256_set1_epi32(static_cast<int16_t>(off[a] & 0xFFFFu));
    const __m256i dv = _mm256_set1_epi32(static_cast<int32_t>(off[a]) >> 16);
    s[2 * a] = bilinearAvx2(v, _mm256_add_epi32(uf, du), _mm256_add_epi32(vf, dv));
    s[2 * a + 1] = bilinearAvx2(v, _mm256_sub_epi32(uf, du), _mm256_sub_epi32(vf, dv));
  }
  cswapAvx2(s[0], s[5]), cswapAvx2(s[1], s[3]), cswapAvx2(s[2], s[4]);
  cswapAvx2(s[1], s[2]), cswapAvx2(s[3], s[4]);
  cswapAvx2(s[0], s[3]), cswapAvx2(s[2], s[5]);
  cswapAvx2(s[0], s[1]), cswapAvx2(s[2], s[3]), cswapAvx2(s[4], s[5]);
  cswapAvx2(s[1], s[2]), cswapAvx2(s[3], s[4]);
  return _mm256_add_epi32(s[2], s[3]);
}

PSFS_AVX2 __m256i logTermAvx2(__m256i m) {  // = logTermOfPair per lane
  const __m256 x = _mm256_cvtepi32_ps(_mm256_max_epi32(m, _mm256_set1_epi32(256)));
  const __m256i bits = _mm256_castps_si256(x);
  const __m256 e = _mm256_cvtepi32_ps(_mm256_sub_epi32(_mm256_srli_epi32(bits, 23), _mm256_set1_epi32(127)));
  const __m256 f = _mm256_castsi256_ps(_mm256_or_si256(_mm256_and_si256(bits, _mm256_set1_epi32(0x007FFFFF)),
                                                       _mm256_set1_epi32(0x3F800000)));
  const __m256 one = _mm256_set1_ps(1.0f);
  const __m256 z = _mm256_div_ps(_mm256_sub_ps(f, one), _mm256_add_ps(f, one));
  const __m256 z2 = _mm256_mul_ps(z, z);
  __m256 p = _mm256_fmadd_ps(z2, _mm256_set1_ps(2.0f / 11.0f), _mm256_set1_ps(2.0f / 9.0f));
  p = _mm256_fmadd_ps(z2, p, _mm256_set1_ps(2.0f / 7.0f));
  p = _mm256_fmadd_ps(z2, p, _mm256_set1_ps(2.0f / 5.0f));
  p = _mm256_fmadd_ps(z2, p, _mm256_set1_ps(2.0f / 3.0f));
  p = _mm256_fmadd_ps(z2, p, _mm256_set1_ps(2.0f));
  const __m256 lnx = _mm256_fmadd_ps(e, _mm256_set1_ps(kLn2), _mm256_mul_ps(z, p));
  return _mm256_cvtps_epi32(_mm256_mul_ps(_mm256_sub_ps(lnx, _mm256_set1_ps(kLnFullPair)),
                                          _mm256_set1_ps(static_cast<float>(ViewEvidence::kLogScale))));
}

template <int K, bool kMulti>
__attribute__((target("avx2,fma"))) void rowAvx2(const PsfsRowParams& p, const uint32_t* centres,
                                                 const uint32_t* offsets, uint8_t* out) {
  const __m256i zero = _mm256_setzero_si256();
  const __m256i no_ev = _mm256_set1_epi32(kNoEv);
  const __m256i lo16 = _mm256_set1_epi32(0xFFFF);
  // The row's projections are read once per frame: fetch them without letting them push the
  // evidence images (gathered every frame) out of the caches.
  for (int i = 0; i < p.num_cameras * p.nxp; i += 16)
    _mm_prefetch(reinterpret_cast<const char*>(centres + i), _MM_HINT_NTA);
  for (int x0 = 0; x0 < p.nx; x0 += 8) {
    __m256i sum = zero, inactive = zero;
    __m256i m[K > 0 ? K : 1];
    for (int j = 0; j < K; ++j) m[j] = no_ev;
    for (int c = 0; c < p.num_cameras; ++c) {
      const KernelView& v = p.views[c];
      const __m256i uv = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(centres + c * p.nxp + x0));
      const __m256i pix = _mm256_add_epi32(  // unused (optimised out) when not needed
          _mm256_mullo_epi32(_mm256_srli_epi32(uv, 20), _mm256_set1_epi32(v.width)),
          _mm256_srli_epi32(_mm256_and_si256(uv, lo16), 4));
      __m256i t;
      if (!kMulti || v.has_mask) {
        const __m256i g = _mm256_i32gather_epi32(reinterpret_cast<const int*>(v.terms), pix, 2);
        t = _mm256_srai_epi32(_mm256_slli_epi32(g, 16), 16);
      }
      if (kMulti) {
        // Without an active mask the centre's term is not needed: only whether the camera
        // observes the voxel, which the packed centre says (saves a gather).
        const __m256i off_view = v.has_mask ? _mm256_cmpgt_epi32(t, zero)
                                            : _mm256_cmpeq_epi32(uv, _mm256_set1_epi32(static_cast<int>(v.not_observed)));
        const uint32_t* off = offsets + (c * p.chunks + x0 / ProjectionTable::kChunk) * 3;
        const __m256i tm = logTermAvx2(medianPairAvx2(v, uv, off));
        t = _mm256_blendv_epi8(tm, no_ev, off_view);
      }
      inactive = _mm256_sub_epi32(inactive, _mm256_cmpgt_epi32(t, zero));
      sum = _mm256_add_epi32(sum, _mm256_min_epi32(t, zero));
      for (int j = 0; j < K; ++j) {
        const __m256i lo = _mm256_min_epi32(m[j], t);
        t = _mm256_max_epi32(m[j], t);
        m[j] = lo;
      }
    }
    // Finalise 8 voxels: drop, normalise, decide, map to bytes (same steps as finalise()).
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
    const __m256i r16 = _mm256_packus_epi32(r, r);      // per 128-bit lane
    const __m256i r8 = _mm256_packus_epi16(r16, r16);
    const uint32_t lo = static_cast<uint32_t>(_mm256_extract_epi32(r8, 0));
    const uint32_t hi = static_cast<uint32_t>(_mm256_extract_epi32(r8, 4));
    uint8_t bytes[8];
    std::memcpy(bytes, &lo, 4);
    std::memcpy(bytes + 4, &hi, 4);
    std::memcpy(out + x0, bytes, static_cast<size_t>(std::min(8, p.nx - x0)));
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

// Bilinear sample at the padded fixed-point position packed as 16-bit (u | v << 16) per lane,
// the same integers as bilinear() (all positions lie in [0, 65535]: PackedUV::kMaxImageSide).
// Packed 16-bit arithmetic replaces the split/multiply/add of the index and the weights:
// idx = u0 + v0 * stride in one madd, the weight bytes and words from byte shuffles.
PSFS_AVX512 __m512i bilinear512(const KernelView& v, __m512i s) {
  const __m512i idx = _mm512_madd_epi16(_mm512_srli_epi16(s, 4),
                                        _mm512_set1_epi32(1 | (v.quad_stride << 16)));
  const __m512i q = _mm512_i32gather_epi32(idx, v.pairs, 2);
  const __m512i f = _mm512_and_si512(s, _mm512_set1_epi32(0x000F000F));  // fu | fv << 16
  // Vertical weights, bytes (16 - fv, fv, 16 - fv, fv): fv (byte 2) into every byte, then
  // 16 - fv in the even ones.
  const __m512i fv4 = _mm512_shuffle_epi8(
      f, _mm512_set4_epi32(0x0E0E0E0E, 0x0A0A0A0A, 0x06060606, 0x02020202));
  const __m512i wv = _mm512_mask_sub_epi8(fv4, __mmask64(0x5555555555555555ull),
                                          _mm512_set1_epi8(16), fv4);
  const __m512i lr = _mm512_maddubs_epi16(q, wv);
  // Horizontal weights, words (16 - fu, fu): fu (byte 0) into both words, then 16 - fu below.
  const __m512i fu2 = _mm512_shuffle_epi8(
      f, _mm512_set4_epi32(int(0x800C800Cu), int(0x80088008u), int(0x80048004u), int(0x80008000u)));
  const __m512i wu = _mm512_mask_sub_epi16(fu2, __mmask32(0x55555555u), _mm512_set1_epi16(16), fu2);
  return _mm512_madd_epi16(lr, wu);
}

PSFS_AVX512 void cswap512(__m512i& a, __m512i& b) {
  const __m512i lo = _mm512_min_epi32(a, b);
  b = _mm512_max_epi32(a, b);
  a = lo;
}

// Offsets of two consecutive chunks (off0 for lanes 0-7, off1 for lanes 8-15).
PSFS_AVX512 __m512i pairOf(int32_t lo, int32_t hi) {
  return _mm512_inserti64x4(_mm512_set1_epi32(lo), _mm256_set1_epi32(hi), 1);
}

PSFS_AVX512 __m512i medianPair512(const KernelView& v, __m512i uv, const uint32_t* off0,
                                  const uint32_t* off1) {
  // Both halves of uv plus the pad, as 16-bit lanes; the offsets are packed (du | dv << 16)
  // int16 pairs already, so one 16-bit add / sub gives both coordinates of a sample.
  const __m512i p = _mm512_add_epi16(uv, _mm512_set1_epi16(kPad16));
  __m512i s[6];
  for (int a = 0; a < 3; ++a) {
    const __m512i d = pairOf(static_cast<int32_t>(off0[a]), static_cast<int32_t>(off1[a]));
    s[2 * a] = bilinear512(v, _mm512_add_epi16(p, d));
    s[2 * a + 1] = bilinear512(v, _mm512_sub_epi16(p, d));
  }
  cswap512(s[0], s[5]), cswap512(s[1], s[3]), cswap512(s[2], s[4]);
  cswap512(s[1], s[2]), cswap512(s[3], s[4]);
  cswap512(s[0], s[3]), cswap512(s[2], s[5]);
  cswap512(s[0], s[1]), cswap512(s[2], s[3]), cswap512(s[4], s[5]);
  cswap512(s[1], s[2]), cswap512(s[3], s[4]);
  return _mm512_add_epi32(s[2], s[3]);
}

PSFS_AVX512 __m512i logTerm512(__m512i m) {  // = logTermOfPair per lane
  const __m512 x = _mm512_cvtepi32_ps(_mm512_max_epi32(m, _mm512_set1_epi32(256)));
  const __m512i bits = _mm512_castps_si512(x);
  const __m512 e = _mm512_cvtepi32_ps(_mm512_sub_epi32(_mm512_srli_epi32(bits, 23), _mm512_set1_epi32(127)));
  const __m512 f = _mm512_castsi512_ps(_mm512_or_si512(_mm512_and_si512(bits, _mm512_set1_epi32(0x007FFFFF)),
                                                       _mm512_set1_epi32(0x3F800000)));
  const __m512 one = _mm512_set1_ps(1.0f);
  const __m512 z = _mm512_div_ps(_mm512_sub_ps(f, one), _mm512_add_ps(f, one));
  const __m512 z2 = _mm512_mul_ps(z, z);
  __m512 p = _mm512_fmadd_ps(z2, _mm512_set1_ps(2.0f / 11.0f), _mm512_set1_ps(2.0f / 9.0f));
  p = _mm512_fmadd_ps(z2, p, _mm512_set1_ps(2.0f / 7.0f));
  p = _mm512_fmadd_ps(z2, p, _mm512_set1_ps(2.0f / 5.0f));
  p = _mm512_fmadd_ps(z2, p, _mm512_set1_ps(2.0f / 3.0f));
  p = _mm512_fmadd_ps(z2, p, _mm512_set1_ps(2.0f));
  const __m512 lnx = _mm512_fmadd_ps(e, _mm512_set1_ps(kLn2), _mm512_mul_ps(z, p));
  return _mm512_cvtps_epi32(_mm512_mul_ps(_mm512_sub_ps(lnx, _mm512_set1_ps(kLnFullPair)),
                                          _mm512_set1_ps(static_cast<float>(ViewEvidence::kLogScale))));
}

template <int K, bool kMulti>
__attribute__((target("avx512f,avx512bw,avx2,fma"))) void rowAvx512(const PsfsRowParams& p,
                                                                  const uint32_t* centres,
                                                                  const uint32_t* offsets,
                                                                  uint8_t* out) {
  const __m512i zero = _mm512_setzero_si512();
  const __m512i one = _mm512_set1_epi32(1);
  const __m512i no_ev = _mm512_set1_epi32(kNoEv);
  const __m512i lo16 = _mm512_set1_epi32(0xFFFF);
  for (int i = 0; i < p.num_cameras * p.nxp; i += 16)  // as in the AVX2 kernel
    _mm_prefetch(reinterpret_cast<const char*>(centres + i), _MM_HINT_NTA);
  for (int x0 = 0; x0 < p.nx; x0 += 16) {
    // The padded row holds whole chunks of 8: the last step may have only one.
    const bool two = x0 + 8 < p.nxp;
    const __mmask16 lanes = two ? __mmask16(0xFFFF) : __mmask16(0x00FF);
    const int chunk = x0 / ProjectionTable::kChunk;
    __m512i sum = zero, inactive = zero;
    __m512i m[K > 0 ? K : 1];
    for (int j = 0; j < K; ++j) m[j] = no_ev;
    for (int c = 0; c < p.num_cameras; ++c) {
      const KernelView& v = p.views[c];
      // Lanes past the row read 0 (pixel 0): computed, never stored.
      const __m512i uv = _mm512_maskz_loadu_epi32(lanes, centres + c * p.nxp + x0);
      __m512i t = zero;
      if (!kMulti || v.has_mask) {
        const __m512i pix = _mm512_add_epi32(
            _mm512_mullo_epi32(_mm512_srli_epi32(uv, 20), _mm512_set1_epi32(v.width)),
            _mm512_srli_epi32(_mm512_and_si512(uv, lo16), 4));
        const __m512i g = _mm512_i32gather_epi32(pix, v.terms, 2);
        t = _mm512_srai_epi32(_mm512_slli_epi32(g, 16), 16);
      }
      if (kMulti) {
        const __mmask16 off_view = v.has_mask
                                       ? _mm512_cmpgt_epi32_mask(t, zero)
                                       : _mm512_cmpeq_epi32_mask(uv, _mm512_set1_epi32(static_cast<int>(v.not_observed)));
        const uint32_t* off0 = offsets + (c * p.chunks + chunk) * 3;
        const uint32_t* off1 = two ? off0 + 3 : off0;
        const __m512i tm = logTerm512(medianPair512(v, uv, off0, off1));
        t = _mm512_mask_mov_epi32(tm, off_view, no_ev);
      }
      inactive = _mm512_mask_add_epi32(inactive, _mm512_cmpgt_epi32_mask(t, zero), inactive, one);
      sum = _mm512_add_epi32(sum, _mm512_min_epi32(t, zero));
      for (int j = 0; j < K; ++j) {
        const __m512i lo = _mm512_min_epi32(m[j], t);
        t = _mm512_max_epi32(m[j], t);
        m[j] = lo;
      }
    }
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
    std::memcpy(out + x0, bytes, static_cast<size_t>(std::min(16, p.nx - x0)));
  }
}

bool useAvx512() { return avx512KernelsActive(); }
#pragma GCC diagnostic pop
#endif

template <int K>
PsfsRowFn pick(bool multi, bool vector) {
#if PSFS_HAVE_X86_DISPATCH
  if (vector && useAvx512()) return multi ? &rowAvx512<K, true> : &rowAvx512<K, false>;
  if (vector) return multi ? &rowAvx2<K, true> : &rowAvx2<K, false>;
#endif
  (void)vector;
  return multi ? &rowScalar<K, true> : &rowScalar<K, false>;
}

}  // namespace

PsfsRowFn selectPsfsRow(int k, bool multi, bool vector) {
  switch (k) {
    case 0: return pick<0>(multi, vector);
    case 1: return pick<1>(multi, vector);
    case 2: return pick<2>(multi, vector);
    case 3: return pick<3>(multi, vector);
    case 4: return pick<4>(multi, vector);
  }
  throw std::invalid_argument("psfs: occluded_views must be in 0..4");
}

int medianSampleByte(const KernelView& view, uint32_t centre, const uint32_t* chunk_offsets) {
  return medianByte(view, centre, chunk_offsets);
}

int observeByte(const KernelView& view, const uint8_t* likelihood, uint32_t centre,
                const uint32_t* chunk_offsets) {
  const int pix = pixelOf(centre, view.width);
  if (view.terms[pix] > 0) return -1;
  return chunk_offsets ? medianByte(view, centre, chunk_offsets) : likelihood[pix];
}

}  // namespace detail
}  // namespace psfs
