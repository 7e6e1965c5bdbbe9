// Private: the per-row inner loops of foreground-class pSfS. All do the same integer and float
// operations in the same order, so they produce identical bytes.
//  * Single projection (also the footprint levels and the hand sub-volumes): one Google
//    Highway source for every instruction set (psfs_row_hwy.cpp), checked against the plain
//    C++ reference in psfs_kernels.cpp.
//  * Multi-projection (the shared face samples): one Google Highway source too
//    (psfs_face_hwy.cpp), faceRowScalar the reference. Until 2026-12-07 x86 ran hand-written
//    AVX-512 and AVX2 kernels; the Highway kernel took their steps where Highway 1.0 lacks them
//    (psfs_face_hwy.cpp) and measured within 3 % of them (16 mm volume, 1 thread, Zen 5 EPYC,
//    medians of per-round ratios, docs/benchmarks.md: AVX3 1.03x the AVX-512 kernel, AVX2
//    1.03x the AVX2 one), so they were retired (issue 17: one kernel source). Its 128-bit
//    target without gathers or FMA, SSE4 (the nearest to a NEON core measurable here), takes
//    1.7x the AVX2 kernel's time in the same run (it takes the log term from a table,
//    log_term_table.h); SCALAR ~6x.
// The plain C++ reference kernels are made of the per-voxel functions of voxel_arithmetic.h,
// which the CUDA kernels (gpu_psfs_fusion.h) run too: one source for the arithmetic.
#pragma once

#include <cstddef>
#include <cstdint>
#include <type_traits>
#include <vector>

#include "voxel_arithmetic.h"

namespace psfs {
namespace detail {

// KernelView and PsfsRowParams: voxel_arithmetic.h (shared with the GPU).

// The part of a grid row a kernel computes: voxels [begin, end), whole chunks of
// ProjectionTable::kChunk (end <= nxp; the whole row is {0, nxp}). x_carry: the multi-projection
// kernels' first -x faces (see below); the single-projection kernels have no carried sample.
struct RowSpan {
  int begin = 0, end = 0;              // multiples of ProjectionTable::kChunk, end <= nxp
  const int32_t* x_carry = nullptr;    // per camera, -1: not observed; nullptr: none (begin 0)
};

// Single projection: voxels [span.begin, min(span.end, nx)) of the row into out[x]. centres:
// ProjectionTable::rowCentres (only the span's entries are read; the vector kernels load the
// span's last chunk masked, never past span.end).
using PsfsRowFn = void (*)(const PsfsRowParams&, const uint32_t* centres, uint8_t* out, const RowSpan& span);

// k = occlusion tolerance (0..4). The best Highway target the CPU and the TABLETOP_SIMD /
// force*Kernels() switches allow, whatever `vector` says (false on a CPU without AVX2, where
// that is SSE4 or NEON); Highway's portable target (SCALAR with GCC < 12.3, else EMU128) only
// when the scalar kernels are forced.
PsfsRowFn selectPsfsRow(int k, bool vector);

// The Highway row kernels (psfs_row_hwy.cpp). Targets are Highway's bits (HWY_AVX2, ...).
std::vector<int64_t> hwyRowTargets();             // compiled and supported by this CPU
PsfsRowFn hwyRowKernel(int64_t target, int k);    // target from hwyRowTargets()
const char* hwyTargetName(int64_t target);
// Index of a target in Highway's dispatch tables (HWY_DISPATCH_TABLE of any exported kernel).
size_t hwyDispatchIndex(int64_t target);
// The best compiled target this CPU supports: any (avx512), any but the AVX-512 ones, or only
// the portable one (EMU128 or SCALAR, whichever is built) when !vector.
int64_t hwyRowTarget(bool vector, bool avx512);
// Tests: selectPsfsRow returns this target's kernel from now on (0: back to normal; -1: the
// plain C++ reference the Highway kernels must equal byte for byte).
void forceRowKernelForTest(int64_t target);

constexpr int kMaxOccludedViews = 4;

// f(std::integral_constant<int, K>{}) for K = k (0 .. kMaxOccludedViews; larger k as the
// largest): how a kernel template is picked by occlusion tolerance, e.g.
// byOcclusion(k, [](auto K) -> PsfsRowFn { return &rowScalar<decltype(K)::value>; }).
template <class F>
auto byOcclusion(int k, F&& f) {
  switch (k) {
    case 0: return f(std::integral_constant<int, 0>{});
    case 1: return f(std::integral_constant<int, 1>{});
    case 2: return f(std::integral_constant<int, 2>{});
    case 3: return f(std::integral_constant<int, 3>{});
    default: return f(std::integral_constant<int, 4>{});
  }
}

// ---- multi-projection: shared face samples ------------------------------------------------
// A voxel's 6 samples are its face centres (ProjectionTable::rowOffsets: centre +- half a voxel
// per axis), bilinear samples of the likelihood, 0 .. 255 * 256. The face between voxels A
// (lower) and B (upper) along an axis is one sample: at A's centre + A's offset when A's centre
// projects into camera c's image (whether or not its pixel is switched off), else at B's
// centre - B's offset. Every kernel follows this rule, so each face is computed once and all
// kernels give the same bytes.
//
// Rows are walked in z-then-y order through a slab of consecutive z layers (forEachFaceRow in
// fusion_common.h), carrying faces:
//  * x faces inside the row (the kernel's own carry);
//  * yface[c * nxp + x]: +y faces of the previous row of this layer (in), this row's (out);
//  * zface[c * nxp + x]: +z faces of this row in the previous layer (in), this layer's (out).
// Both buffers must be readable 16 entries past num_cameras * nxp (whole-vector loads).
// kNoFace (voxel_arithmetic.h) in a buffer (the value of a face whose lower voxel is missing or
// unobserved) makes the kernel sample the face from the upper voxel. voxelMedianPair
// (voxel_arithmetic.h) is the same rule for one voxel without a walk (the GPU's threads).
//
// A kernel computes the span [begin, end) of the row (RowSpan): whole chunks of the table's
// offsets. Its first voxel's -x face is span.x_carry[c], the +x face of voxel begin - 1 as the
// walk left it (plusXFaces), so a span's voxels and faces are the bytes of the whole row's walk;
// only the span's entries of out, yface and zface are written (the vector kernels may read up
// to a vector past the span's end and discard it: hence the buffers' 16 entries of padding).
// Empty-space skipping (fusion_common.h: forEachFaceRow) computes the spans that pass the person.
using PsfsFaceRowFn = void (*)(const PsfsRowParams&, const uint32_t* centres,
                               const uint32_t* offsets, uint16_t* yface, uint16_t* zface,
                               uint8_t* out, const RowSpan& span);
PsfsFaceRowFn selectPsfsFaceRow(int k, bool vector);
// The Highway face kernels (psfs_face_hwy.cpp), for the targets of hwyRowTargets().
PsfsFaceRowFn hwyFaceRowKernel(int64_t target, int k);
// Tests and benchmarks: selectPsfsFaceRow returns this kernel from now on (0: back to normal;
// -1: faceRowScalar, the reference; -2: the default selection (Highway's best allowed target);
// else this Highway target's).
void forceFaceRowKernelForTest(int64_t target);

// The + faces along `axis` (1 = y, 2 = z) of one row, all cameras, into faces[c * nxp + x]
// for x in [x_begin, x_end) (multiples of kChunk; default the whole row): what a walk that
// starts in the middle of the grid, or a span whose neighbour was not computed, needs from the
// row below.
void plusFacesOfRow(const KernelView* views, int num_cameras, int nxp, const uint32_t* centres,
                    const uint32_t* offsets, int axis, uint16_t* faces, int x_begin = 0, int x_end = -1);
// The Highway plusFacesOfRow for a target of hwyRowTargets() (x range: whole chunks, checked by
// plusFacesOfRow, which takes the reference's loop when the scalar kernels are forced).
using PlusFacesFn = void (*)(const KernelView* views, int num_cameras, int nxp, const uint32_t* centres,
                             const uint32_t* offsets, int axis, uint16_t* faces, int x_begin, int x_end);
PlusFacesFn hwyPlusFacesKernel(int64_t target);
// The +x faces of voxel x of one row per camera into carry[c] (-1 where it is not observed):
// RowSpan::x_carry of a span that starts at x + 1.
void plusXFaces(const KernelView* views, int num_cameras, int nxp, const uint32_t* centres,
                const uint32_t* offsets, int x, int32_t* carry);

// Reference variants: per camera and voxel of one row, the sum of the two middle face samples
// (0 .. 2 * 255 * 256; pairs[c * nxp + x]; unobserved voxels get an unspecified value), with
// the same buffers and walk as the kernels.
void medianPairsOfRow(const KernelView* views, int num_cameras, int nxp,
                      const uint32_t* centres, const uint32_t* offsets, uint16_t* yface,
                      uint16_t* zface, int32_t* pairs);
// A median pair as a likelihood byte (0..255), rounded like the kernels' log term sees it.
inline int medianPairByte(int32_t pair) { return (pair + 256) >> 9; }

// Single projection, reference variants: the camera's nearest-pixel likelihood byte, or -1 if
// it gives no evidence (not observed, or the pixel is switched off).
int observeByte(const KernelView& view, const uint8_t* likelihood, uint32_t centre);

}  // namespace detail
}  // namespace psfs
