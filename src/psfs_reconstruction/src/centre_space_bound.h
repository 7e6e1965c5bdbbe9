// Private: empty-space skipping for the single-projection pSfS (PsfsOptions::skip_empty_below
// without multi_projection), made for the hand sub-volumes: two 83^3 cubes projected on the fly
// every frame, of which the hand fills a few per cent.
//
// The single-projection test reads one pixel per voxel and camera, the one under the voxel's
// centre, so a bound needs no footprint model: per cell of 4x4x4 voxels and camera, every
// centre of the cell projects inside the box of the projected corners of the cell's voxel
// faces (the pinhole image of a box is the convex hull of its corners' images; a slack covers
// the lens distortion's curvature, derived per camera from its coefficients, and the float
// arithmetic), and the camera's term is at most the log term of the largest likelihood byte
// on the pixels that box can round to. Unlike the multi-projection bound (empty_space_bound.h),
// this one is strict: a single bright pixel holds a cell up, and no voxel that fuses at or
// above the level is ever skipped.
//  * per camera and frame (TermTiles): the largest byte of the pixels that give evidence, per
//    2x2 pixel tile of the window the grid projects into (squares of 1, 2 and 4 tiles, so a
//    box is a few lookups), and whether a tile holds a pixel that gives none (a known
//    occlusion of ViewImage::active, or a switched-off view);
//  * per cell: the fused mean is at most the mean of the cameras' bounds, with the rules of the
//    multi-projection bound (boundBelow, empty_space_bound.h) for cameras that see only some
//    of the cell's voxels (its box leaves the image or holds pixels without evidence); blocks
//    of 2x2x2 cells first, so the empty far side of a cube costs an eighth;
//  * a margin of two voxels: a chunk (8 voxels along x) is skipped only when every voxel within
//    2 of its voxels along each axis lies in a cell below the level. So marching cubes at an iso
//    above the level (the hand meshes: 0.6) reads only computed voxels, the central
//    differences of its normals included, and gives the same mesh.
// Skipped chunks are set to 0 and their centres are never projected (for a table projected on
// the fly the projection is about half of the fusion's time). A camera that cannot project a
// cell's corner (behind it, beyond the lens model's range) may give that cell's voxels any term.
#pragma once

#include <algorithm>
#include <cstdint>
#include <memory>
#include <vector>

#include <opencv2/core.hpp>

#include "psfs_reconstruction/probability_volume.h"
#include "psfs_reconstruction/projection_table.h"
#include "psfs_reconstruction/view_evidence.h"
#include "voxel_arithmetic.h"

namespace psfs {
namespace detail {

// One camera's likelihood over a window of its image, per 2x2 pixel tile: the largest byte of
// the pixels that give evidence (-1: none does), and whether some pixel gives none.
struct TermTiles {
  static constexpr int kTile = 2;
  static constexpr int kLevels = 3;  // squares of 1, 2 and 4 tiles
  int tx0 = 0, ty0 = 0, tiles_x = 0, tiles_y = 0;  // the window, in tiles
  // The window [u0, u1] x [v0, v1] (pixels, inclusive, inside the image; u1 < u0: empty) of a
  // width x height image of bytes (`step` apart along a row, rows `stride` apart). A pixel gives
  // no evidence where active (CV_8UC1, optional) is 0, or where terms (optional) is > 0.
  void set(const uint8_t* bytes, size_t stride, int step, int width, int height, const cv::Mat& active,
           const int16_t* terms, int u0, int v0, int u1, int v1);
  // Over the pixels [u0, u1] x [v0, v1] (inside the window): the largest byte with evidence
  // (-1: none), and whether a pixel without evidence lies in the tiles read.
  void rectMax(int u0, int v0, int u1, int v1, int* max_byte_out, bool* off_out) const;

 private:
  // A tile's figures in 16 bits: the largest byte + 1 (bits 0-8), a pixel without evidence (15).
  static uint16_t pack(int max_byte, bool off) { return uint16_t((max_byte + 1) | (off ? 0x8000 : 0)); }
  static uint16_t combine(uint16_t a, uint16_t b) {
    return uint16_t(std::max(a & 0x1FF, b & 0x1FF) | ((a | b) & 0x8000));
  }
  // [l][ty * tiles_x + tx]: over the tiles [tx, tx + 2^l) x [ty, ty + 2^l) (clamped to the window;
  // tile_squares.h).
  std::vector<uint16_t> level_[kLevels];
  // Where every tile has evidence and none lacks it (clean_): the levels' largest bytes alone.
  bool clean_ = false;
  std::vector<uint8_t> level8_[kLevels];
};

class CentreSpaceBound {
 public:
  static constexpr int kCell = 4;
  static constexpr int kChunk = ProjectionTable::kChunk;
  static_assert(kChunk % kCell == 0, "a chunk holds whole cells");

  // The chunks of a single-projection table's rows whose voxels provably fuse below
  // max_probability (in (0, 1)) with the fusion's parameters p and occlusion tolerance k, with
  // the margin (file comment): flags[row * chunksPerRow() + chunk] = 1. The views are
  // the frame's evidence (the likelihood bytes and the terms' switched-off pixels), or, for a
  // fusion that runs elsewhere (the GPU's), the images ViewEvidence::set would take. Rows below
  // p.first_layer count as empty. Returns the fraction of the grid's voxels flagged.
  double skippableChunks(const ProjectionTable& table, const ViewEvidence& evidence, const PsfsRowParams& p,
                         int k, double max_probability, int threads, std::vector<uint8_t>* flags);
  double skippableChunks(const ProjectionTable& table, const std::vector<ViewImage>& views,
                         const PsfsRowParams& p, int k, double max_probability, int threads,
                         std::vector<uint8_t>* flags);

  // Tests: after skippableChunks, the pixels [u0, u1] x [v0, v1] (unclamped) the centres of the
  // voxels of cells [X0, X1) x [Y0, Y1) x [Z0, Z1) can land on in camera c; unknown: a corner
  // the camera cannot project.
  struct PixelBox {
    int u0 = 0, v0 = 0, u1 = -1, v1 = -1;
    bool unknown = false;
  };
  PixelBox boxPixels(int c, int X0, int Y0, int Z0, int X1, int Y1, int Z1) const;

 private:
  // The lattice table's packed corner (X, Y, Z) of camera c, and over the 8 corners of the box of
  // cells [X0, X1] x ... (lattice indices): their span in PackedUV units (u1 < 0: none known),
  // unknown where one is not observed.
  struct CornerSpan {
    int u0 = 1 << 30, v0 = 1 << 30, u1 = -1, v1 = -1;
    bool unknown = false;
  };
  uint32_t corner(int c, int X, int Y, int Z) const {
    const size_t row = size_t(Y) + (size_t(cy_) + 1) * size_t(Z);
    return lattice_packed_[(row * size_t(cameras_) + size_t(c)) * size_t(lattice_nxp_) + size_t(X)];
  }
  CornerSpan cornerSpan(int c, int X0, int Y0, int Z0, int X1, int Y1, int Z1) const;
  // Per lattice point (the corners of the cells' face boxes) and camera: its image position.
  void projectLattice(const ProjectionTable& table, int threads);
  template <class SetTiles>
  double flagChunks(const ProjectionTable& table, const SetTiles& set_tiles, const PsfsRowParams& p, int k,
                    double max_probability, int threads, std::vector<uint8_t>* flags);

  int nx_ = 0, ny_ = 0, nz_ = 0, cx_ = 0, cy_ = 0, cz_ = 0, cameras_ = 0;
  std::unique_ptr<ProjectionTable> lattice_table_;  // the cells' corners (projectLattice)
  const uint32_t* lattice_packed_ = nullptr;        // its stored entries: [row][camera][x]
  int lattice_nxp_ = 0;                             // its padded row length
  // The lens slack (1/16 px) of a box whose corners' images span du16 x dv16 (1/16 px) in camera c.
  int lensSlack16(int c, int du16, int dv16) const;
  std::vector<double> lens_k_;  // per camera: lensSlack16's factor (0: no distortion)
  std::vector<tabletop_capture::CameraModel> lens_cameras_;  // what lens_k_ was derived from
  std::vector<TermTiles> tiles_;      // per camera
  std::vector<int> windows_;          // per camera u0, v0, u1, v1
  // A static grid's boxes ([(cell or block) * cameras + c]), kept while the lattice table's
  // revision stays boxes_revision_; last_revision_: the revision of the previous frame.
  std::vector<PixelBox> cell_boxes_, block_boxes_;
  uint64_t boxes_revision_ = 0, last_revision_ = 0;
  uint64_t windows_revision_ = 0;  // the lattice revision windows_ was derived for
  std::vector<uint8_t> below_;        // per cell
  std::vector<uint8_t> x_below_;      // per cell row and chunk: the cells along x the margin reads
};

// Sets the flagged chunks of a volume fused whole (the GPU's) to 0, as PsfsFusion leaves them.
void zeroChunks(const ProjectionTable& table, const std::vector<uint8_t>& flags, ProbabilityVolume* out);

}  // namespace detail
}  // namespace psfs
