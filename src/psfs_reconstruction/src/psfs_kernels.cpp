#include "psfs_kernels.h"

#include <algorithm>
#include <atomic>
#include <stdexcept>
#include <vector>

#include "psfs_reconstruction/projection_table.h"
#include "psfs_reconstruction/simd_dispatch.h"
#include "psfs_reconstruction/view_evidence.h"

namespace psfs {
namespace detail {
namespace {

// Memory bound, not only accuracy: a sample at the largest offset from the not-observed marker
// (u = 0) or from the image border must stay inside the pair image's replicated border.
static_assert(ProjectionTable::kMaxSampleOffsetPx * PackedUV::kOne <= kPad16,
              "sample offsets must stay within the pair images' border");
// The far side: from the not-observed marker's v = 16 * height (or a centre in the last pixel),
// padded and moved by the largest offset, the quad's second row / column (+ 1) must still be
// inside the pair image of height (width) + 2 kQuadPad: the Highway kernels gather the + faces
// of unobserved lanes unmasked.
static_assert((ProjectionTable::kMaxSampleOffsetPx * PackedUV::kOne + kPad16) / PackedUV::kOne + 2 <=
                  2 * ViewEvidence::kQuadPad,
              "sample offsets must stay within the pair images' far border");
static_assert(kVoxLogScale == ViewEvidence::kLogScale && kVoxNoEvidence == ViewEvidence::kNoEvidence &&
                  kVoxQuadPad == ViewEvidence::kQuadPad && kVoxOne == PackedUV::kOne &&
                  kVoxChunk == ProjectionTable::kChunk,
              "voxel_arithmetic.h's constants must be the layout's");

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

// The Highway target every kernel takes: the best the CPU and the switches allow. `vector` is
// false on a CPU without AVX2 (an older x86, ARM), where that is still its best target (SSE4,
// NEON); Highway's portable target only when the scalar kernels are forced.
int64_t selectedHwyTarget(bool vector) {
  return hwyRowTarget(vector || !scalarKernelsForced(), avx512KernelsActive());
}

template <int K>
PsfsFaceRowFn pickFace(bool vector) {
  return hwyFaceRowKernel(selectedHwyTarget(vector), K);
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
  return hwyRowKernel(selectedHwyTarget(vector), k);
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
  if (!scalarKernelsForced()) {  // Highway's best target; else the reference below
    hwyPlusFacesKernel(selectedHwyTarget(true))(views, num_cameras, nxp, centres, offsets, axis, faces, x_begin,
                                                x_end);
    return;
  }
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
