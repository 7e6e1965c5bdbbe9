// The marching cubes case table (internal to the meshing library): for each of the 256
// above/below patterns of a cell's eight corners, the surface triangles as cell edges.
//
// Cell corners (offsets along x, y, z) and edges follow Lorensen & Cline / Bourke's numbering:
//   corners 0 (0,0,0) 1 (1,0,0) 2 (1,1,0) 3 (0,1,0) 4 (0,0,1) 5 (1,0,1) 6 (1,1,1) 7 (0,1,1)
//   edges 0: 0-1, 1: 1-2, 2: 3-2, 3: 0-3, 4: 4-5, 5: 5-6, 6: 7-6, 7: 4-7, 8: 0-4, 9: 1-5,
//         10: 2-6, 11: 3-7 (each listed from its lower to its upper corner).
// Bit k of a case index is set when corner k is above the iso level ("inside").
//
// The table is generated (once, on first use) instead of typed in, from one rule per cell face,
// so it is crack-free by construction:
//  - on every face the contour segments depend only on that face's four corners, and on an
//    ambiguous face (two diagonal corners above) they always separate the two above corners.
//    Both cells sharing the face therefore cut it identically: no cracks, no holes;
//  - the segments chain into closed loops on the cell boundary, oriented so that the triangles
//    are counter-clockwise seen from below the iso level (outside);
//  - each loop is triangulated with diagonals that never join two vertices lying on one cell
//    face. A diagonal on a face could also be chosen by the neighbour across that face, which
//    would give an edge of four triangles; diagonals through the cell interior belong to this
//    cell alone, so every mesh edge is shared by exactly two triangles on closed surfaces.
// The classic typed-in table (VTK's vtkMarchingCubesTriangleCases) makes the same face choices:
// on random 40^3 fields it gives the same vertex and triangle counts and Euler characteristic
// as this one, also watertight; only the diagonals inside a cell differ. Generating the table
// makes both properties hold by construction rather than by inspection of 256 rows; the tests
// check them on random fields that meet every case (a fan with a face diagonal fails them).
#pragma once

#include <cstdint>

namespace cvephands {
namespace mc {

constexpr int kCornerOffset[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                     {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
constexpr int kEdgeCorners[12][2] = {{0, 1}, {1, 2}, {3, 2}, {0, 3}, {4, 5}, {5, 6},
                                     {7, 6}, {4, 7}, {0, 4}, {1, 5}, {2, 6}, {3, 7}};

// As in the classic table; the generator checks it.
constexpr int kMaxTrianglesPerCell = 5;

struct CaseTable {
  uint8_t num_triangles[256];
  uint8_t edges[256][3 * kMaxTrianglesPerCell];  // 3 cell edges per triangle
  uint16_t edge_mask[256];                        // bit e: cell edge e is crossed
  // Per cell edge: the grid edge it is, as axis (0 x, 1 y, 2 z) and the offset of its lower
  // corner from the cell's corner 0.
  uint8_t edge_axis[12];
  uint8_t edge_offset[12][3];
  // The 12 edges lie on 8 (lattice row, axis) pairs: slot (dy, dz, axis) of each pair, and
  // each edge's slot (its x offset is edge_offset[e][0]).
  uint8_t slot[8][3];
  uint8_t edge_slot[12];
};

// Built on first call (thread-safe), then shared.
const CaseTable& caseTable();

}  // namespace mc
}  // namespace cvephands
