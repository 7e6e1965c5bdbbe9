// Private: the per-row inner loops of foreground-class pSfS, scalar and AVX2. Both do the same
// integer and float operations in the same order, so they produce identical bytes.
#pragma once

#include <cstdint>

namespace psfs {
namespace detail {

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
};

// centres: ProjectionTable::rowCentres; offsets: rowOffsets or nullptr (single projection).
using PsfsRowFn = void (*)(const PsfsRowParams&, const uint32_t* centres, const uint32_t* offsets,
                           uint8_t* out);

// k = occlusion tolerance (0..4). Returns the AVX2 kernel when `vector` (caller checked the CPU).
PsfsRowFn selectPsfsRow(int k, bool multi, bool vector);

constexpr int kMaxOccludedViews = 4;

// Shared by the reference variants: the camera's observation of a voxel as a likelihood byte,
// nearest pixel or median of the 6 bilinear samples. Returns -1 if the camera gives no evidence.
int observeByte(const KernelView& view, const uint8_t* likelihood, uint32_t centre,
                const uint32_t* chunk_offsets /* 3 entries or nullptr */);
// Median-of-6 bilinear sample (0..255) as the kernels compute it.
int medianSampleByte(const KernelView& view, uint32_t centre, const uint32_t* chunk_offsets);

}  // namespace detail
}  // namespace psfs
