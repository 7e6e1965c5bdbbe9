// Marching cubes on a probabilistic voxel volume (thesis 6.5, DESIGN.md section 4 "Hand
// meshes"): the hand surface is the iso-surface p = 0.6 of the fused probabilities, with the
// crossing on each grid edge interpolated linearly between the two probabilities, which gives a
// smooth mesh without smoothing filters. The binary variant (threshold first, then mesh; thesis
// fig. 6.6) is kept as the comparison.
//
// Samples sit at the voxel centres; a cell joins 2x2x2 neighbouring samples. The mesh is
// indexed (exactly one vertex per crossed grid edge), watertight on closed surfaces (every edge
// in exactly two triangles: the case table is crack-free by construction, see
// src/mesh/marching_cubes_cases.h), wound counter-clockwise seen from outside (low probability),
// with per-vertex normals from the probability gradient (central differences at the samples,
// interpolated along the edge like the position) pointing outward.
//
// Speed: a hand sub-volume is mostly empty. One vectorised pass turns the bytes into one bit
// per sample ("above iso"); crossed edges, their vertex numbering (prefix sums of popcounts)
// and the non-trivial cells then come from word-wide bit operations, so empty rows cost a few
// instructions and only cells the surface passes are visited. The passes run over z-slabs with
// OpenMP; every vertex and triangle has a slot fixed before the fill pass, so the output is
// byte-identical for any thread count.
//
// Why not VTK: bench/bench_meshing.cpp runs vtkFlyingEdges3D and vtkMarchingCubes on the same
// bytes (normals on, iso 153.5, identical triangle counts), and this code is the faster one on
// hand volumes and on whole persons (figures: see docs/benchmarks.md (bench_meshing)). VTK also
// has no "closed at the border" mode and would be a heavy run-time dependency for one filter;
// it stays a benchmark-only one.
#pragma once

#include <cstdint>
#include <vector>

#include "cvephands_bridge/mesh/probability_grid.h"
#include "cvephands_bridge/mesh/triangle_mesh.h"

namespace cvephands {

enum class MeshingMode {
  kProbabilistic,  // crossings interpolated from the probabilities (the pipeline's mode)
  kBinary,         // threshold first (value > iso: 1, else 0), then mesh that field: crossings
                   // at edge midpoints, normals from the binary field's gradient
};

struct MarchingCubesOptions {
  // Iso level on the byte scale (p * 255), strictly inside (0, 255). Default: p = 0.6, i.e.
  // 153, rounded to the half-integer 153.5 (a voxel is inside iff value > 153, as in pSfS's
  // thresholdByte(0.6)). On uint8 volumes always use a half-integer: no sample can equal it.
  // A sample equal to the iso puts vertices on grid points (zero-length edges, duplicate
  // positions), and implementations disagree on which side such ties fall.
  float iso = 153.5f;
  MeshingMode mode = MeshingMode::kProbabilistic;
  // Treat samples outside the volume as 0, so a hand that touches a face of its sub-volume
  // still gives a closed mesh (the cut is capped half a voxel outside the last samples). When
  // false the surface simply ends at the outermost samples (open there).
  bool close_at_border = true;
  bool compute_normals = true;
  int threads = 0;  // OpenMP threads (0 = OpenMP default)
};

class MarchingCubes {
 public:
  // Throws std::invalid_argument for an iso outside (0, 255) or negative threads.
  explicit MarchingCubes(const MarchingCubesOptions& options = MarchingCubesOptions());
  const MarchingCubesOptions& options() const { return options_; }

  // Meshes `grid` into `mesh` (replacing its content, keeping its capacity). Vertices are in the
  // grid's frame (metres). A grid with a zero dimension gives an empty mesh. Throws
  // std::invalid_argument for an invalid grid (ProbabilityGridView::validate) or one too large
  // for 32-bit vertex indices. Scratch memory is kept between calls: reuse one object per
  // stream of frames; one object must not be used by two threads at once.
  void extract(const ProbabilityGridView& grid, TriangleMesh* mesh);

 private:
  MarchingCubesOptions options_;
  // Per lattice row (fixed y, z), W 64-bit words each: sample above iso, and crossed edges
  // along x, y, z starting at that sample.
  std::vector<uint64_t> above_, cross_[3];
  // Per row and axis and word: first vertex index relative to the row's first vertex.
  std::vector<uint32_t> word_offset_;
  // Per row: vertices owned by the row / triangles of the cell row, then their prefix sums.
  std::vector<uint32_t> row_vertices_;
  std::vector<uint64_t> row_triangles_;
};

// One-shot convenience (allocates its scratch on every call).
TriangleMesh marchingCubes(const ProbabilityGridView& grid,
                           const MarchingCubesOptions& options = MarchingCubesOptions());

}  // namespace cvephands
