// Private: empty-space skipping for the multi-projection pSfS (issue 17; PsfsOptions::
// skip_empty_below).
//
// Most of the workspace is empty, and the multi-projection test spends 3 bilinear lookups per
// voxel and camera there to find a posterior near the floor. A bound that is cheap to evaluate
// for a whole block of voxels tells where nothing comes out above a level:
//  * per camera and frame, per 8x8 pixel tile, the largest byte of the likelihood's 2x2 minimum
//    (TileMaxImage; squares of 2x2 and 4x4 tiles too, so a rectangle is a few lookups);
//  * per cell of 4x4x4 voxels and camera, once per projection table, the tiles that hold every
//    pixel the cell's face samples read (centres +- the sample offsets, the bilinear neighbour
//    and a margin), and whether the camera observes all, none or only some of its voxels;
//  * per cell and frame: the median pair of 6 samples of bytes <= m is <= 2 * 256 * m, so the
//    camera's log term is <= logTermOfPair(that); the fused mean over the observing cameras is
//    at most the mean of these bounds (with occlusion tolerance k: of the n - k largest, as
//    dropping low views only raises the mean; with cameras that observe some of the voxels:
//    the largest over how many of them a voxel has), and the posterior at most exp(mean + offset).
// A chunk of a grid row (8 voxels along x: the kernels' unit, two cells; the last chunk of a
// row may hold one) whose cells are all below the level is not fused but set to the background's posterior (skippedChunks: every
// camera's commonest byte, fused); the rest of the row is fused in spans, the kernels' carried
// faces re-sampled where a span's neighbour was not computed (forEachFaceRow), so every computed
// voxel is the same bytes as without skipping.
//
// What the 2x2 minimum gives up: the plain maximum would make the bound strict, but one noisy
// pixel in a tile then holds it up (on the pipeline's frames it skipped 6 % of the voxels; the
// 2x2 minimum 67 %). A bright structure under 2 px wide in one view (under ~7 mm at 1 m on the
// default rig, half a 16 mm voxel) drops that view's bound to its background, so a voxel it
// would have lifted above the level can be lost in a skipped chunk. test_empty_space_skipping
// checks on the simulated rig's frames (synthetic likelihoods and the real classifier) that no
// voxel at or above the level changes. Cells with an inactive pixel in their tiles are never skipped; a view switched off
// as a whole counts as not observing.
#pragma once

#include <cstdint>
#include <mutex>
#include <vector>

#include <opencv2/core.hpp>

#include "psfs_reconstruction/probability_volume.h"
#include "psfs_reconstruction/projection_table.h"
#include "psfs_reconstruction/psfs_fusion.h"
#include "psfs_reconstruction/view_evidence.h"
#include "centre_space_bound.h"
#include "voxel_arithmetic.h"

namespace psfs {
namespace detail {

// Per 8x8 pixel tile of one camera: the bound's log term of the largest byte of the likelihood's
// 2x2 minimum (see the file comment), and whether a switched-off pixel lies in it; the same over
// squares of 2x2 and 4x4 tiles (level l: the square of 2^l tiles whose top-left tile is (tx, ty)),
// so that any rectangle of tiles is the maximum of a few lookups (tile_squares.h).
struct TileMaxImage {
  static constexpr int kTile = 8;    // pixels per tile side
  static constexpr int kLevels = 3;  // squares of 1, 2 and 4 tiles
  int tiles_x = 0, tiles_y = 0;
  // [level][ty * tiles_x + tx]: the bound (1/1024 log units, <= 0), or kInactive where a pixel
  // of the square gives no evidence (larger than any bound: the maximum then says "inactive").
  static constexpr int32_t kInactive = 1 << 20;
  std::vector<int32_t> bound[kLevels];
  bool absent = false;  // every pixel is switched off: the view observes no voxel
  uint8_t mode = 0;     // the commonest likelihood byte: the view's background
  // likelihood: width x height bytes, rows `stride` apart; active: empty or the view's CV_8UC1
  // mask (0 = off); terms: instead of `active`, the evidence's terms (> 0 = off), or nullptr.
  void set(const uint8_t* likelihood, int width, int height, size_t stride, const cv::Mat& active,
           const int16_t* terms = nullptr);
  // The largest bound over the tiles [tx0, tx1] x [ty0, ty1] (inclusive).
  int32_t rectMax(int tx0, int ty0, int tx1, int ty1) const;

 private:
  std::vector<uint8_t> row_min_, col_max_;
};

class EmptySpaceBound {
 public:
  // Voxels per cell side. Cells of 2 along y and z, or tiles of 4 px, skip 3 % more of the
  // voxels on the pipeline's frame but their bound costs more than that saves (AVX2 on a Zen 5
  // EPYC: 4.5x binary SfS against 3.5x; cells of 8 x 4 x 4: 3.4x, the same within the noise;
  // docs/benchmarks.md).
  static constexpr int kCell = 4;
  static constexpr int kChunk = ProjectionTable::kChunk;
  static_assert(kChunk % kCell == 0, "a chunk holds whole cells");

  // Derives the cells' tiles from a multi-projection table; nothing to do when the table's
  // revision is the one prepared. Throws std::invalid_argument for a table without offsets.
  void prepare(const ProjectionTable& table);
  bool preparedFor(const ProjectionTable& table) const { return revision_ == table.revision(); }

  // flags[(y + ny z) * chunks + a] = 1 where every voxel of chunk a (voxels 8a .. 8a + 7) of
  // the grid row provably fuses below `max_probability` (in (0, 1)) with the fusion's
  // parameters p (offset, min_views, drop rule) and occlusion tolerance k, given each camera's
  // tiles (one per table camera); chunks = ProjectionTable::chunksPerRow(); on `threads`
  // threads (0: all; PsfsOptions::threads). Returns the voxels flagged (the floor's layers
  // included, which skippedChunks then clears).
  size_t skippableChunks(const std::vector<TileMaxImage>& tiles, const PsfsRowParams& p, int k,
                         double max_probability, int threads, std::vector<uint8_t>* flags) const;
  // Writes the flagged chunks of a grid row (flags: the row's chunk flags; out: the row):
  // `fill`, or 0 where a voxel has fewer than min_views observing cameras (what the fusion
  // gives it), the cameras in `absent` (a bit per camera) left out.
  void fillChunks(size_t row, const uint8_t* flags, uint8_t fill, int min_views, uint64_t absent,
                  uint8_t* out) const;

 private:
  enum : uint8_t { kNone = 0, kAll = 1, kMixed = 2 };
  struct CellView {
    uint8_t status = kNone;
    uint16_t tx0 = 0, ty0 = 0, tx1 = 0, ty1 = 0;  // tile range, inclusive
  };
  // True where every voxel of the cell fuses to a mean log term below limit_per_view (1/1024
  // units, offset included) or to 0 (fewer than min_views views).
  bool cellBelow(int cell, const std::vector<TileMaxImage>& tiles, const PsfsRowParams& p, int k,
                 int32_t limit_per_view) const;

  struct CellSummary {
    uint8_t all = 0, some = 0;  // cameras observing all of the cell's voxels, some of them
  };

  uint64_t revision_ = 0;
  int nx_ = 0, ny_ = 0, nz_ = 0, cx_ = 0, cy_ = 0, cz_ = 0, chunks_ = 0, cameras_ = 0;
  std::vector<CellView> cells_;  // [(cell index) * cameras + c], cell = X + cx (Y + cy Z)
  std::vector<CellSummary> summaries_;  // [cell index]
  std::vector<uint64_t> seen_;           // per voxel (grid order): a bit per observing camera
  std::vector<uint8_t> views_seen_;      // per voxel: how many bits seen_ has
  std::vector<uint8_t> chunk_views_;     // per row and chunk: the fewest views_seen_ of its voxels
};

// Cameras a bound handles (a bit each in the per-voxel masks).
constexpr int kMaxBoundCameras = 64;

// Whether no voxel can fuse to a mean log term (offset included, 1/1024 units, per kept view) at
// or above limit_per_view, given per camera an upper bound of its term: `all` for the cameras
// that give every voxel evidence, `some` for those that give it to some voxels (sorted here);
// with p.min_views and occlusion tolerance k (of the n - k largest: dropping low views only
// raises a mean), over every count of the `some` cameras a voxel may have.
bool boundBelow(const int32_t* all, int n_all, int32_t* some, int n_some, const PsfsRowParams& p, int k,
                int32_t limit_per_view);
// The per-view limit of a level: a sum of kept views' terms below kept times this fuses below
// max_probability (in (0, 1); throws std::invalid_argument otherwise).
int32_t boundLimitPerView(const PsfsRowParams& p, double max_probability);

// Whether a fusion with these options skips empty space with this bound (PsfsOptions::
// skip_empty_below with the multi-projection test).
inline bool skipsEmptySpace(const PsfsOptions& o) { return o.multi_projection && o.skip_empty_below > 0.0; }
// ... or with the single projection's (centre_space_bound.h; not with footprint levels).
inline bool skipsCentreSpace(const PsfsOptions& o) {
  return !o.multi_projection && !o.footprint && o.skip_empty_below > 0.0;
}

// The tiles of every view of a frame's evidence (inactive where its terms say "no evidence").
void tileMaxImages(const ViewEvidence& evidence, int threads, std::vector<TileMaxImage>* out);
// The same from the views ViewEvidence::set would take (the GPU paths keep these on the host).
void tileMaxImages(const std::vector<ViewImage>& views, int threads, std::vector<TileMaxImage>* out);

// The skipping's state of one fusion: the bound of the last table and the frame's tiles.
struct EmptySkipCache {
  std::mutex mutex;
  EmptySpaceBound bound;
  CentreSpaceBound centre;  // the single projection's
  std::vector<TileMaxImage> tiles;
  double last_fraction = 0.0;
  uint8_t fill = 0;     // what skipped voxels are set to (skippedChunks)
  uint64_t absent = 0;  // views switched off as a whole this frame, a bit per camera
};

// The chunks a fusion with options o (skip_empty_below > 0, multi-projection) skips this
// frame, from cache->tiles (set by the caller): flags[row * chunksPerRow() + chunk] = 1 (never
// below the floor's layer, which the fusion sets to 0 anyway); and cache->fill, the byte a voxel
// fuses to when every camera shows it its commonest byte (the background's posterior: what
// empty space far from the person is), at most the level's. Returns the skipped fraction of the
// voxels. Skipped chunks are written with cache->bound.fillChunks(row, flags of the row,
// cache->fill, o.min_views, cache->absent, ...).
double skippedChunks(const PsfsOptions& o, const ProjectionTable& table, EmptySkipCache* cache,
                     std::vector<uint8_t>* flags);
// For a fusion that computed every voxel (the GPU's): writes the chunks that PsfsFusion skips
// as it does (fillChunks), so both give the same bytes. cache->tiles must hold this frame's tiles.
void fillSkipped(const PsfsOptions& o, const ProjectionTable& table, EmptySkipCache* cache,
                 ProbabilityVolume* out);

}  // namespace detail
}  // namespace psfs
