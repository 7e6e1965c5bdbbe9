// Private: the per-voxel arithmetic of foreground-class pSfS, written once for the CPU's
// reference kernels (psfs_kernels.cpp: rowScalar, faceRowScalar), the host emulation of the GPU
// (volume_fusion_host.cpp) and the CUDA kernels (cuda/volume_fusion.cu). The Highway kernels
// (every instruction set) do the same integer and float operations lane by lane, so every
// path writes the same bytes.
//  * per camera: the term of a voxel (single projection: the pixel's log term; multi-projection:
//    the log of the median of its 6 face samples, each a bilinear sample of the likelihood);
//  * per voxel: the sum of the terms, the count of observing views and the K lowest terms,
//    finalised into a byte (drop, normalise, decide, map).
// Plain C++ with PSFS_HD (host_device.h); no CUDA types, no std:: calls device code lacks.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstring>

#include "host_device.h"

namespace psfs {
namespace detail {

// The layout constants (ViewEvidence, PackedUV; static_assert in psfs_kernels.cpp).
constexpr int kVoxLogScale = 1024;       // ViewEvidence::kLogScale
constexpr int32_t kVoxNoEvidence = 1;    // ViewEvidence::kNoEvidence
constexpr int kVoxQuadPad = 8;           // ViewEvidence::kQuadPad
constexpr int kVoxOne = 16;              // PackedUV::kOne
constexpr int kVoxChunk = 8;             // ProjectionTable::kChunk
// Fixed-point position of pixel -kQuadPad's origin in a padded pair image: 16 P - 8.
constexpr int kPad16 = kVoxQuadPad * kVoxOne - kVoxOne / 2;
// kNoFace in a face buffer of the CPU walk: the face of a missing or unobserved lower voxel.
constexpr uint16_t kNoFace = 0xFFFF;
static_assert(255 * 256 < kNoFace, "a face sample must never read as the kNoFace marker");

// One camera's evidence as the kernels read it (host or device memory).
struct KernelView {
  const int16_t* terms;    // ViewEvidence::terms
  const uint16_t* pairs;   // ViewEvidence::pairs (multi-projection only)
  int width;
  int quad_stride;
  bool has_mask;           // some pixel switched off (else only unobserved voxels lack evidence)
  uint32_t not_observed;   // PackedUV::notObserved(height)
};

struct PsfsRowParams {
  int nx = 0, nxp = 0, num_cameras = 0, chunks = 0;
  const KernelView* views = nullptr;
  int32_t drop_below = 0;        // fixed-point log term: observations below are droppable
  int min_views = 1;
  float offset = 0.0f;           // per observing view: ln(P(H)^(1/C) / P(G1[c]))
  float log_t = 0.0f;            // ln t
  const int32_t* exp_table = nullptr;  // byte of exp(-(i + 0.5) / exp_scale)
  int exp_table_size = 0;
  float exp_scale = 0.0f;
  int32_t t_byte = 0;
  bool zero_outside = false;
  int first_layer = 0;           // z layers below it are 0 and not computed (PsfsOptions::floor_z)
};

// ---- small helpers device code has no std:: for --------------------------------------------
PSFS_HD int32_t minI(int32_t a, int32_t b) { return b < a ? b : a; }  // = std::min
PSFS_HD int32_t maxI(int32_t a, int32_t b) { return a < b ? b : a; }  // = std::max
PSFS_HD float minF(float a, float b) { return b < a ? b : a; }
PSFS_HD float maxF(float a, float b) { return a < b ? b : a; }
PSFS_HD uint32_t floatBits(float f) {
#if defined(__CUDA_ARCH__)
  return __float_as_uint(f);
#else
  uint32_t u;
  std::memcpy(&u, &f, 4);
  return u;
#endif
}
PSFS_HD float bitsFloat(uint32_t u) {
#if defined(__CUDA_ARCH__)
  return __uint_as_float(u);
#else
  float f;
  std::memcpy(&f, &u, 4);
  return f;
#endif
}

// ---- single projection ---------------------------------------------------------------------
PSFS_HD int pixelOf(uint32_t uv, int width) {  // = PackedUV::pixelIndex
  return static_cast<int>(uv >> 20) * width + static_cast<int>((uv & 0xFFFFu) >> 4);
}
// The camera's log term at a packed centre (> 0: no evidence; the guard pixel when unobserved).
PSFS_HD int32_t centreTerm(const KernelView& v, uint32_t uv) { return v.terms[pixelOf(uv, v.width)]; }

// ---- multi-projection: face samples --------------------------------------------------------
// Bilinear sample at padded fixed-point position (su, sv) (1/16 px, origin at pixel -kQuadPad):
// the same integer arithmetic as maddubs + madd in the Highway kernel's x86 targets. Result in
// [0, 255 * 256].
PSFS_HD int32_t bilinear(const KernelView& v, int32_t su, int32_t sv) {
  const int32_t u0 = su >> 4, fu = su & 15, v0 = sv >> 4, fv = sv & 15;
  const uint16_t* q = v.pairs + v0 * v.quad_stride + u0;
  const int32_t q0 = q[0], q1 = q[1];
  const int32_t a = q0 & 255, c = q0 >> 8, b = q1 & 255, d = q1 >> 8;
  const int32_t left = a * (16 - fv) + c * fv;
  const int32_t right = b * (16 - fv) + d * fv;
  return left * (16 - fu) + right * fu;  // = top (16 - fv) + bottom fv, the same integer
}

PSFS_HD void cswap(int32_t& a, int32_t& b) {
  const int32_t lo = minI(a, b), hi = maxI(a, b);
  a = lo;
  b = hi;
}

// Sum of the two middle values of 6 (optimal 12-comparator sorting network, pruned by the
// compiler to what positions 2 and 3 need).
PSFS_HD int32_t middlePair6(int32_t s[6]) {
  cswap(s[0], s[5]), cswap(s[1], s[3]), cswap(s[2], s[4]);
  cswap(s[1], s[2]), cswap(s[3], s[4]);
  cswap(s[0], s[3]), cswap(s[2], s[5]);
  cswap(s[0], s[1]), cswap(s[2], s[3]), cswap(s[4], s[5]);
  cswap(s[1], s[2]), cswap(s[3], s[4]);
  return s[2] + s[3];
}

// Bilinear sample at voxel centre `uv` (packed) +- the packed offset `off` (sign +1 or -1).
PSFS_HD int32_t faceSample(const KernelView& v, uint32_t uv, uint32_t off, int sign) {
  const int32_t uf = static_cast<int32_t>(uv & 0xFFFFu) + kPad16;
  const int32_t vf = static_cast<int32_t>(uv >> 16) + kPad16;
  const int32_t du = static_cast<int16_t>(off & 0xFFFFu);
  const int32_t dv = static_cast<int32_t>(off) >> 16;
  return bilinear(v, uf + sign * du, vf + sign * dv);
}
PSFS_HD int32_t plusFace(const KernelView& v, uint32_t uv, uint32_t off) { return faceSample(v, uv, off, 1); }
PSFS_HD int32_t minusFace(const KernelView& v, uint32_t uv, uint32_t off) { return faceSample(v, uv, off, -1); }

// The face between voxels A (lower) and B (upper) along an axis, one sample for both voxels
// (psfs_kernels.h): at A's centre + A's offset when A's centre projects into the camera's
// image (whether or not its pixel is switched off), else at B's centre - B's offset. A
// missing A (B on the grid's lower border) is passed as not_observed.
PSFS_HD int32_t sharedFace(const KernelView& v, uint32_t lower_uv, uint32_t lower_off, uint32_t uv,
                           uint32_t off) {
  return lower_uv != v.not_observed ? plusFace(v, lower_uv, lower_off) : minusFace(v, uv, off);
}

// A voxel's median pair (sum of the two middle face samples, 0 .. 2 * 255 * 256) in one
// camera, from its own centre and chunk offsets (off[axis]) and, per axis, its lower
// neighbour's centre and that neighbour's chunk offset along the axis. What the CPU's walk
// with carried faces computes (faceRowScalar), for one voxel on its own: a GPU thread.
PSFS_HD int32_t voxelMedianPair(const KernelView& v, uint32_t uv, const uint32_t off[3],
                                const uint32_t lower_uv[3], const uint32_t lower_off[3]) {
  int32_t s[6];
  for (int a = 0; a < 3; ++a) {
    s[2 * a] = sharedFace(v, lower_uv[a], lower_off[a], uv, off[a]);
    s[2 * a + 1] = plusFace(v, uv, off[a]);
  }
  return middlePair6(s);
}

// Log term of a median pair m (likelihood m / 130560), floored at half a byte step like
// ViewEvidence::logTerm: round(1024 ln(max(m, 256) / 130560)). Computed, not looked up (a
// gather costs more than these dozen operations): m = 2^e f, f in [1, 2), t = f - 1,
// ln f = t P(t) with P the degree-6 least-squares fit of ln(1 + t) / t on Chebyshev nodes
// (|error| < 3e-7 in float, 3e-4 of a fixed-point step; no division, unlike the atanh series).
// Same float operations (with FMA) as the Highway kernel's logTermLanes (targets without FMA
// take this function's values from a table, log_term_table.h), so all give the same bytes.
constexpr float kLn2 = 0.693147180559945f;
constexpr float kLnFullPair = 11.779591f;  // ln(2 * 255 * 256) = ln 130560
constexpr float kLnP0 = 0.999978516f, kLnP1 = -0.499423297f, kLnP2 = 0.327937181f,
                kLnP3 = -0.225006931f, kLnP4 = 0.133351158f, kLnP5 = -0.0541751417f,
                kLnP6 = 0.0104858724f;
PSFS_HD int32_t logTermOfPair(int32_t m) {
  const float x = static_cast<float>(maxI(m, 256));
  const uint32_t bits = floatBits(x);
  const float e = static_cast<float>(static_cast<int32_t>(bits >> 23) - 127);
  const float f = bitsFloat((bits & 0x007FFFFFu) | 0x3F800000u);
  const float t = f - 1.0f;
  float p = kLnP6;
  p = fmaf(p, t, kLnP5);
  p = fmaf(p, t, kLnP4);
  p = fmaf(p, t, kLnP3);
  p = fmaf(p, t, kLnP2);
  p = fmaf(p, t, kLnP1);
  p = fmaf(p, t, kLnP0);
  const float lnx = fmaf(e, kLn2, p * t);
  return static_cast<int32_t>(rintf((lnx - kLnFullPair) * static_cast<float>(kVoxLogScale)));
}

// A camera's multi-projection term: no evidence where the centre's pixel gives none (not
// observed, or switched off), else the log of the median pair.
PSFS_HD int32_t faceTerm(int32_t centre_term, int32_t median_pair) {
  return centre_term > 0 ? kVoxNoEvidence : logTermOfPair(median_pair);
}

// ---- per voxel: fusion of the camera terms -------------------------------------------------
// Drop, normalise, decide, map to a byte. m: the k lowest terms, ascending.
PSFS_HD uint8_t finalise(const PsfsRowParams& p, int32_t sum, int32_t n, const int32_t* m, int k) {
  for (int j = 0; j < k; ++j)
    if (m[j] < p.drop_below) {
      sum -= m[j];
      n -= 1;
    }
  if (n < p.min_views) return 0;
  float mean = static_cast<float>(sum) * (1.0f / kVoxLogScale);
  mean = mean / static_cast<float>(n);
  mean = mean + p.offset;
  const bool in = mean > p.log_t;
  float e = -mean * p.exp_scale;
  e = minF(e, static_cast<float>(p.exp_table_size - 1));
  e = maxF(e, 0.0f);
  const int32_t b = p.exp_table[static_cast<int32_t>(e)];
  if (in) return static_cast<uint8_t>(maxI(b, p.t_byte + 1));
  return p.zero_outside ? 0 : static_cast<uint8_t>(minI(b, p.t_byte));
}

// The running sum, count of views without evidence and the K lowest terms of one voxel, as the
// vector kernels accumulate them camera by camera.
template <int K>
struct TermFusion {
  int32_t sum = 0, inactive = 0;
  int32_t m[K > 0 ? K : 1];
  PSFS_HD TermFusion() {
    for (int j = 0; j < K; ++j) m[j] = kVoxNoEvidence;
  }
  PSFS_HD void add(int32_t t) {  // t > 0: no evidence
    inactive += t > 0;
    sum += minI(t, 0);
    for (int j = 0; j < K; ++j) {
      const int32_t lo = minI(m[j], t);
      t = maxI(m[j], t);
      m[j] = lo;
    }
  }
  PSFS_HD uint8_t finish(const PsfsRowParams& p) const {
    return finalise(p, sum, p.num_cameras - inactive, m, K);
  }
};

// ---- one voxel of a whole grid -------------------------------------------------------------
// A stored projection table's layout (ProjectionTable::rowCentres / rowOffsets over all rows),
// in host or device memory.
struct TableView {
  const uint32_t* centres = nullptr;  // [row][camera][nxp]
  const uint32_t* offsets = nullptr;  // [row][camera][chunk][3] (multi-projection only)
  int nx = 0, ny = 0, nz = 0, nxp = 0, chunks = 0;
};

// Byte of voxel (x, y, z), x < nx: p.views (p.num_cameras of them) and the table; multi: the
// multi-projection test (the table has offsets, the views pairs).
template <int K>
PSFS_HD uint8_t fuseVoxel(const PsfsRowParams& p, const TableView& t, bool multi, int x, int y, int z) {
  if (z < p.first_layer) return 0;  // below the floor (each thread reads its faces itself)
  const size_t C = static_cast<size_t>(p.num_cameras);
  const size_t row = static_cast<size_t>(y) + static_cast<size_t>(t.ny) * static_cast<size_t>(z);
  TermFusion<K> f;
  for (int c = 0; c < p.num_cameras; ++c) {
    const KernelView& v = p.views[c];
    const size_t cr = row * C + c;  // (row, camera)
    const uint32_t uv = t.centres[cr * t.nxp + x];
    int32_t term = centreTerm(v, uv);
    if (multi) {
      if (term <= 0) {
        const uint32_t* off = t.offsets + (cr * t.chunks + x / kVoxChunk) * 3;
        uint32_t lower_uv[3] = {v.not_observed, v.not_observed, v.not_observed};
        uint32_t lower_off[3] = {0, 0, 0};
        if (x > 0) {
          lower_uv[0] = t.centres[cr * t.nxp + x - 1];
          lower_off[0] = t.offsets[(cr * t.chunks + (x - 1) / kVoxChunk) * 3 + 0];
        }
        if (y > 0) {
          const size_t cl = cr - C;  // row - 1
          lower_uv[1] = t.centres[cl * t.nxp + x];
          lower_off[1] = t.offsets[(cl * t.chunks + x / kVoxChunk) * 3 + 1];
        }
        if (z > 0) {
          const size_t cl = cr - static_cast<size_t>(t.ny) * C;  // row - ny
          lower_uv[2] = t.centres[cl * t.nxp + x];
          lower_off[2] = t.offsets[(cl * t.chunks + x / kVoxChunk) * 3 + 2];
        }
        term = faceTerm(term, voxelMedianPair(v, uv, off, lower_uv, lower_off));
      } else {
        term = kVoxNoEvidence;
      }
    }
    f.add(term);
  }
  return f.finish(p);
}

}  // namespace detail
}  // namespace psfs
