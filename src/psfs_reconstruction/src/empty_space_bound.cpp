#include "empty_space_bound.h"

#include <algorithm>
#include <bitset>
#include <cmath>
#include <functional>
#include <limits>
#include <stdexcept>
#include <string>

#include "cpu_dispatch.h"
#include "tile_squares.h"
#include "volume_fusion.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace psfs {
namespace detail {
namespace {

// Pixels added around a cell's sample box: 1 for the bilinear neighbour, 1 for the rounding of
// a face sampled from the other voxel's offsets (another chunk's, a fraction of a pixel apart),
// 1 to spare.
constexpr int kMarginPx = 3;
// Fixed-point units added to each camera's bound: the log polynomial's rounding (< 1 unit).
constexpr int32_t kTermMargin = 2;

// The bound's log term of a byte: the log term of the largest median pair that 6 samples of
// bytes <= b can give (2 * 256 * b), plus the margin, at most 0.
const std::vector<int32_t>& byteBounds() {
  static const std::vector<int32_t> table = [] {
    std::vector<int32_t> t(256);
    for (int b = 0; b < 256; ++b) t[size_t(b)] = std::min<int32_t>(0, logTermOfPair(2 * 256 * b) + kTermMargin);
    return t;
  }();
  return table;
}

}  // namespace

void TileMaxImage::set(const uint8_t* likelihood, int width, int height, size_t stride, const cv::Mat& active,
                       const int16_t* terms) {
  tiles_x = (width + kTile - 1) / kTile;
  tiles_y = (height + kTile - 1) / kTile;
  const size_t nt = size_t(tiles_x) * tiles_y;
  bound[0].resize(nt);  // every tile written below; the squares sized by buildTileSquares
  row_min_.resize(size_t(width));
  // Whole tiles and a vector past the last (zeros: no byte is below 0) for the tiles' maxima.
  col_max_.resize(size_t(tiles_x) * kTile + 16);
  size_t off_tiles = 0;
  // Every 4th row is plenty for the commonest byte (the background covers most of a view).
  // Eight histograms, a pixel's by u % 8: most pixels hold the same byte, and one counter would
  // make each increment wait for the last (store to load).
  constexpr int kHist = 8;
  int histograms[kHist][256] = {{0}};
  for (int v = 0; v < height; v += 4) {
    const uint8_t* r = likelihood + size_t(v) * stride;
    int u = 0;
    for (; u + kHist <= width; u += kHist)
      for (int i = 0; i < kHist; ++i) ++histograms[i][r[u + i]];
    for (; u < width; ++u) ++histograms[0][r[u]];
  }
  int histogram[256];
  for (int i = 0; i < 256; ++i) {
    histogram[i] = 0;
    for (int j = 0; j < kHist; ++j) histogram[i] += histograms[j][i];
  }
  mode = uint8_t(std::max_element(histogram, histogram + 256) - histogram);
  const std::vector<int32_t>& term = byteBounds();
  std::vector<uint8_t> off(static_cast<size_t>(tiles_x));
  for (int ty = 0; ty < tiles_y; ++ty) {
    std::fill(col_max_.begin(), col_max_.end(), uint8_t(0));
    std::fill(off.begin(), off.end(), uint8_t(0));
    for (int v = ty * kTile; v < std::min(height, (ty + 1) * kTile); ++v) {
      const uint8_t* __restrict r0 = likelihood + size_t(v) * stride;
      const uint8_t* __restrict r1 = likelihood + size_t(std::min(v + 1, height - 1)) * stride;
      uint8_t* __restrict mn = row_min_.data();
      uint8_t* __restrict mx = col_max_.data();
      // The 2x2 minimum (right and lower neighbours, replicated at the border): one pixel or a
      // one-pixel line of noise does not raise it.
      for (int u = 0; u + 1 < width; ++u) {
        const uint8_t a = r0[u] < r0[u + 1] ? r0[u] : r0[u + 1];
        const uint8_t b = r1[u] < r1[u + 1] ? r1[u] : r1[u + 1];
        mn[u] = a < b ? a : b;
      }
      mn[width - 1] = std::min(r0[width - 1], r1[width - 1]);
      for (int u = 0; u < width; ++u) mx[u] = mx[u] > mn[u] ? mx[u] : mn[u];
      if (!active.empty()) {
        const uint8_t* a = active.ptr<uint8_t>(v);
        for (int u = 0; u < width; ++u) off[size_t(u / kTile)] |= a[u] == 0;
      } else if (terms) {
        const int16_t* tr = terms + size_t(v) * width;
        for (int u = 0; u < width; ++u) off[size_t(u / kTile)] |= tr[u] > 0;
      }
    }
    int32_t* b0 = &bound[0][size_t(ty) * tiles_x];
    int tx = 0;
#if defined(__SSE2__)
    // Two tiles per vector: the largest byte of each 8-byte half ends in its low byte.
    for (; tx + 2 <= tiles_x; tx += 2) {
      __m128i m = _mm_loadu_si128(reinterpret_cast<const __m128i*>(&col_max_[size_t(tx) * kTile]));
      m = _mm_max_epu8(m, _mm_srli_epi64(m, 32));
      m = _mm_max_epu8(m, _mm_srli_epi64(m, 16));
      m = _mm_max_epu8(m, _mm_srli_epi64(m, 8));
      b0[tx] = off[size_t(tx)] ? kInactive : term[size_t(_mm_cvtsi128_si32(m) & 0xFF)];
      b0[tx + 1] = off[size_t(tx) + 1] ? kInactive : term[size_t(_mm_extract_epi16(m, 4) & 0xFF)];
    }
#endif
    for (; tx < tiles_x; ++tx) {
      const uint8_t* c = &col_max_[size_t(tx) * kTile];
      b0[tx] = off[size_t(tx)] ? kInactive : term[*std::max_element(c, c + kTile)];
    }
    for (int t = 0; t < tiles_x; ++t) off_tiles += off[size_t(t)];
  }
  // A view switched off as a whole (a dark or missing camera) observes nothing.
  absent = false;
  if (off_tiles == nt) {
    size_t off_pixels = 0;
    for (int v = 0; v < height; ++v)
      for (int u = 0; u < width; ++u)
        off_pixels += !active.empty() ? active.ptr<uint8_t>(v)[u] == 0 : terms[size_t(v) * width + u] > 0;
    absent = off_pixels == size_t(width) * height;
  }
  buildTileSquares(bound, kLevels, tiles_x, tiles_y, MaxOf());
}

int32_t TileMaxImage::rectMax(int tx0, int ty0, int tx1, int ty1) const {
  return tileSquaresOver(bound, kLevels, tiles_x, tx0, ty0, tx1, ty1, std::numeric_limits<int32_t>::min(), MaxOf());
}

void tileMaxImages(const ViewEvidence& evidence, int threads, std::vector<TileMaxImage>* out) {
  const int n = evidence.numViews();
  out->resize(size_t(n));
#pragma omp parallel for num_threads(resolveThreads(threads)) schedule(dynamic, 1)
  for (int c = 0; c < n; ++c) {
    const int w = evidence.width(c), h = evidence.height(c);
    (*out)[size_t(c)].set(evidence.likelihood(c), w, h, size_t(w), cv::Mat(),
                          evidence.hasInactivePixels(c) ? evidence.terms(c) : nullptr);
  }
}

void tileMaxImages(const std::vector<ViewImage>& views, int threads, std::vector<TileMaxImage>* out) {
  const int n = int(views.size());
  out->resize(size_t(n));
#pragma omp parallel for num_threads(resolveThreads(threads)) schedule(dynamic, 1)
  for (int c = 0; c < n; ++c) {
    const ViewImage& v = views[size_t(c)];
    cv::Mat bytes;
    if (v.likelihood.channels() == 1)
      bytes = v.likelihood.isContinuous() ? v.likelihood : v.likelihood.clone();
    else
      cv::extractChannel(v.likelihood, bytes, v.channel);
    (*out)[size_t(c)].set(bytes.data, bytes.cols, bytes.rows, bytes.step[0], v.active);
  }
}

double skippedChunks(const PsfsOptions& o, const ProjectionTable& table, EmptySkipCache* cache,
                     std::vector<uint8_t>* flags) {
  cache->bound.prepare(table);
  const PsfsRowParams p = psfsRowParams(o, table);
  cache->bound.skippableChunks(cache->tiles, p, o.occluded_views, o.skip_empty_below, o.threads, flags);
  const size_t chunks = size_t(p.chunks), rows = size_t(table.grid().numRows());
  const size_t floor_rows = std::min(rows, size_t(p.first_layer) * size_t(table.grid().dims.y()));
  std::fill(flags->begin(), flags->begin() + floor_rows * chunks, uint8_t(0));
  size_t n = 0;  // skipped voxels
  for (size_t r = floor_rows; r < rows; ++r)
    for (size_t a = 0; a < chunks; ++a)
      if ((*flags)[r * chunks + a])
        n += std::min<size_t>(size_t(p.nx), (a + 1) * ProjectionTable::kChunk) - a * ProjectionTable::kChunk;
  cache->last_fraction = rows == 0 ? 0.0 : double(n) / double(rows * size_t(p.nx));
  cache->absent = 0;
  for (size_t c = 0; c < cache->tiles.size(); ++c)
    if (cache->tiles[c].absent) cache->absent |= uint64_t(1) << c;
  // The fill: every observing camera's commonest byte, fused as a voxel would be (the same
  // finalise, so the same byte on every path), capped at the level's byte.
  int32_t sum = 0, views = 0;
  for (const TileMaxImage& t : cache->tiles)
    if (!t.absent) sum += logTermOfPair(2 * 256 * int32_t(t.mode)), ++views;
  PsfsRowParams fp = p;
  fp.exp_table = psfsExpTable();
  const uint8_t fused = views > 0 ? finalise(fp, sum, views, nullptr, 0) : uint8_t(0);
  cache->fill = std::min<uint8_t>(fused, uint8_t(std::floor(o.skip_empty_below * 255.0)));
  return cache->last_fraction;
}

void fillSkipped(const PsfsOptions& o, const ProjectionTable& table, EmptySkipCache* cache,
                 ProbabilityVolume* out) {
  std::vector<uint8_t> flags;
  skippedChunks(o, table, cache, &flags);
  const size_t nx = size_t(table.grid().dims.x()), chunks = size_t(table.chunksPerRow());
  for (size_t r = 0; r < table.grid().numRows(); ++r)
    cache->bound.fillChunks(r, &flags[r * chunks], cache->fill, o.min_views, cache->absent,
                            out->data.data() + r * nx);
}

void EmptySpaceBound::prepare(const ProjectionTable& table) {
  if (preparedFor(table)) return;
  if (!table.multiProjection())
    throw std::invalid_argument("psfs::EmptySpaceBound: needs a multi-projection table");
  const VoxelGrid& g = table.grid();
  nx_ = g.dims.x(), ny_ = g.dims.y(), nz_ = g.dims.z();
  cx_ = (nx_ + kCell - 1) / kCell, cy_ = (ny_ + kCell - 1) / kCell, cz_ = (nz_ + kCell - 1) / kCell;
  chunks_ = table.chunksPerRow();
  cameras_ = table.numCameras();
  if (cameras_ > kMaxBoundCameras)
    throw std::invalid_argument("psfs::EmptySpaceBound: more than 64 cameras");
  const size_t n_cells = size_t(cx_) * cy_ * cz_;
  const float inf = std::numeric_limits<float>::infinity();
  // Per (cell, camera): the sample box in pixels and the observed voxels.
  std::vector<float> box(n_cells * cameras_ * 4);
  std::vector<int> observed(n_cells * cameras_, 0), voxels(n_cells, 0);
  for (size_t i = 0; i < n_cells * cameras_; ++i) {
    box[4 * i + 0] = inf, box[4 * i + 1] = -inf, box[4 * i + 2] = inf, box[4 * i + 3] = -inf;
  }
  const int nxp = table.paddedRowLength(), chunks = table.chunksPerRow();
  std::vector<uint32_t> cs(table.centreScratchSize()), os(table.offsetScratchSize());
  seen_.assign(size_t(nx_) * ny_ * nz_, 0);
  auto grow = [&](size_t i, float u0, float u1, float v0, float v1) {
    float* b = &box[4 * i];
    b[0] = std::min(b[0], u0), b[1] = std::max(b[1], u1), b[2] = std::min(b[2], v0), b[3] = std::max(b[3], v1);
  };
  auto cellOf = [&](int x, int y, int z) {
    return size_t(x / kCell) + size_t(cx_) * (size_t(y / kCell) + size_t(cy_) * (z / kCell));
  };
  for (int z = 0; z < nz_; ++z)
    for (int y = 0; y < ny_; ++y) {
      const size_t row = size_t(y) + size_t(ny_) * z;
      const uint32_t* centres = table.rowCentres(row, cs.data());
      const uint32_t* offsets = table.rowOffsets(row, os.data());
      for (int x = 0; x < nx_; ++x) ++voxels[cellOf(x, y, z)];
      for (int c = 0; c < cameras_; ++c) {
        const uint32_t not_observed = PackedUV::notObserved(table.camera(c).height);
        for (int x = 0; x < nx_; ++x) {
          const uint32_t uv = centres[size_t(c) * nxp + x];
          if (uv == not_observed) continue;
          const size_t cell = cellOf(x, y, z), i = cell * cameras_ + c;
          ++observed[i];
          seen_[row * nx_ + x] |= uint64_t(1) << c;
          const float u = float(PackedUV::u(uv)), v = float(PackedUV::v(uv));
          const int next[3][3] = {{x + 1, y, z}, {x, y + 1, z}, {x, y, z + 1}};
          for (int a = 0; a < 3; ++a) {
            const uint32_t off = offsets[(size_t(c) * chunks + x / ProjectionTable::kChunk) * 3 + a];
            const float du = float(int16_t(off & 0xFFFFu)) / PackedUV::kOne;
            const float dv = float(int16_t(off >> 16)) / PackedUV::kOne;
            grow(i, u - std::abs(du), u + std::abs(du), v - std::abs(dv), v + std::abs(dv));
            // The face shared with the next voxel along this axis is sampled from this one (at
            // its centre + its offset) while this one is observed, and that voxel's cell reads
            // it too: with offsets clamped to kMaxSampleOffsetPx it is not that voxel's own
            // centre - offset.
            const int* q = next[a];
            if (q[0] < nx_ && q[1] < ny_ && q[2] < nz_) {
              const size_t j = cellOf(q[0], q[1], q[2]);
              if (j != cell) grow(j * cameras_ + c, u + du, u + du, v + dv, v + dv);
            }
          }
        }
      }
    }
  views_seen_.resize(seen_.size());
  for (size_t i = 0; i < seen_.size(); ++i) views_seen_[i] = uint8_t(std::bitset<64>(seen_[i]).count());
  chunk_views_.assign(size_t(ny_) * nz_ * chunks_, uint8_t(255));
  for (size_t row = 0; row < size_t(ny_) * nz_; ++row)
    for (int x = 0; x < nx_; ++x) {
      uint8_t& m = chunk_views_[row * chunks_ + size_t(x / kChunk)];
      m = std::min(m, views_seen_[row * nx_ + size_t(x)]);
    }
  cells_.assign(n_cells * cameras_, CellView{});
  summaries_.assign(n_cells, CellSummary{});
  for (size_t cell = 0; cell < n_cells; ++cell)
    for (int c = 0; c < cameras_; ++c) {
      const size_t i = cell * cameras_ + c;
      CellView& cv = cells_[i];
      if (observed[i] == 0) continue;  // kNone
      cv.status = observed[i] < voxels[cell] ? kMixed : kAll;
      ++(cv.status == kAll ? summaries_[cell].all : summaries_[cell].some);
      const int w = table.camera(c).width, h = table.camera(c).height;
      const float* b = &box[4 * i];
      const int u0 = std::clamp(int(std::floor(b[0])) - kMarginPx, 0, w - 1);
      const int u1 = std::clamp(int(std::floor(b[1])) + kMarginPx, 0, w - 1);
      const int v0 = std::clamp(int(std::floor(b[2])) - kMarginPx, 0, h - 1);
      const int v1 = std::clamp(int(std::floor(b[3])) + kMarginPx, 0, h - 1);
      cv.tx0 = uint16_t(u0 / TileMaxImage::kTile), cv.tx1 = uint16_t(u1 / TileMaxImage::kTile);
      cv.ty0 = uint16_t(v0 / TileMaxImage::kTile), cv.ty1 = uint16_t(v1 / TileMaxImage::kTile);
    }
  revision_ = table.revision();
}

bool EmptySpaceBound::cellBelow(int cell, const std::vector<TileMaxImage>& tiles, const PsfsRowParams& p,
                                int k, int32_t limit_per_view) const {
  const CellSummary& summary = summaries_[size_t(cell)];
  if (summary.all < p.min_views && summary.some == 0) return true;  // every voxel fuses to 0
  // Without occlusion tolerance and with no camera observing only part of the cell, the sum of
  // the bounds only falls as cameras are added: once below the limit it stays below.
  const bool monotone = k == 0 && summary.some == 0;
  const int64_t limit_sum = int64_t(summary.all) * limit_per_view;
  // Bounds of the cameras that observe every voxel of the cell (all) and some of them (some).
  int32_t all[kMaxBoundCameras], some[kMaxBoundCameras];
  int n_all = 0, n_some = 0;
  int64_t sum_all = 0;
  bool all_read = true;  // every camera of the cell's summary gave a bound
  for (int c = 0; c < cameras_; ++c) {
    const CellView& cv = cells_[size_t(cell) * cameras_ + c];
    if (cv.status == kNone) continue;
    if (tiles[c].absent) {  // gives no voxel evidence: the general rule below counts the rest
      all_read = false;
      continue;
    }
    const int32_t b = tiles[c].rectMax(cv.tx0, cv.ty0, cv.tx1, cv.ty1);
    if (b >= TileMaxImage::kInactive) return false;
    if (cv.status == kAll) {
      all[n_all++] = b;
      sum_all += b;
      // (an absent view only lowers the count, so the limit over the summary's count holds)
      if (monotone && sum_all < limit_sum) return true;
    } else {
      some[n_some++] = b;
    }
  }
  if (monotone && all_read) return false;
  return boundBelow(all, n_all, some, n_some, p, k, limit_per_view);
}

bool boundBelow(const int32_t* all, int n_all, int32_t* some, int n_some, const PsfsRowParams& p, int k,
                int32_t limit_per_view) {
  // A voxel's views are all of the first kind and some of the second; its mean is largest with
  // the second kind's largest bounds, so j of those, for every j. The sum of the n - k largest
  // of n bounds is their total less the k smallest (a selection, not a sort).
  std::sort(some, some + n_some, std::greater<int32_t>());
  int64_t sum_all = 0;
  for (int i = 0; i < n_all; ++i) sum_all += all[i];
  int32_t views[kMaxBoundCameras];
  int64_t sum = sum_all;  // all + the j largest of some
  for (int j = 0; j <= n_some; ++j) {
    if (j > 0) sum += some[j - 1];
    const int n = n_all + j;
    if (n < p.min_views) continue;  // such voxels fuse to 0
    const int dropped = std::min(k, n - 1), kept = n - dropped;
    int64_t kept_sum = sum;
    if (dropped > 0) {
      std::copy(all, all + n_all, views);
      std::copy(some, some + j, views + n_all);
      std::nth_element(views, views + (dropped - 1), views + n);
      for (int i = 0; i < dropped; ++i) kept_sum -= views[i];
    }
    if (kept_sum >= int64_t(kept) * limit_per_view) return false;
  }
  return true;
}

int32_t boundLimitPerView(const PsfsRowParams& p, double max_probability) {
  if (!(max_probability > 0.0) || !(max_probability < 1.0))
    throw std::invalid_argument("psfs: empty-space skipping level must be in (0, 1)");
  // mean + offset < ln(max_probability)  <=  sum < kept * floor(1024 (ln max - offset)).
  const double limit = std::floor((std::log(max_probability) - double(p.offset)) * kVoxLogScale);
  return int32_t(std::max(limit, -1e9));
}

void EmptySpaceBound::fillChunks(size_t row, const uint8_t* flags, uint8_t fill, int min_views, uint64_t absent,
                                 uint8_t* out) const {
  const size_t first = row * size_t(nx_);
  for (int a = 0; a < chunks_; ++a) {
    if (!flags[a]) continue;
    const int x1 = std::min(nx_, (a + 1) * kChunk);
    if (absent == 0 && chunk_views_[row * chunks_ + size_t(a)] >= min_views) {
      std::fill(out + a * kChunk, out + x1, fill);
    } else if (absent == 0) {
      for (int x = a * kChunk; x < x1; ++x) out[x] = views_seen_[first + size_t(x)] >= min_views ? fill : uint8_t(0);
    } else {
      for (int x = a * kChunk; x < x1; ++x)
        out[x] = __builtin_popcountll(seen_[first + size_t(x)] & ~absent) >= min_views ? fill : uint8_t(0);
    }
  }
}

size_t EmptySpaceBound::skippableChunks(const std::vector<TileMaxImage>& tiles, const PsfsRowParams& p, int k,
                                        double max_probability, int threads, std::vector<uint8_t>* flags) const {
  if (int(tiles.size()) != cameras_)
    throw std::invalid_argument("psfs::EmptySpaceBound: tile images for " + std::to_string(tiles.size()) +
                                " cameras, table has " + std::to_string(cameras_));
  const int32_t limit_per_view = boundLimitPerView(p, max_probability);
  flags->assign(size_t(ny_) * nz_ * chunks_, 0);
  constexpr int kCellsPerChunk = kChunk / kCell;
  size_t skipped = 0;
  // Layers of cells in parallel: each writes its own rows' flags.
#pragma omp parallel num_threads(resolveThreads(threads)) reduction(+ : skipped)
  {
    std::vector<uint8_t> chunk_below(static_cast<size_t>(chunks_), 0);
#pragma omp for schedule(dynamic, 1)
    for (int Z = 0; Z < cz_; ++Z)
      for (int Y = 0; Y < cy_; ++Y) {
        int n = 0;  // voxels of a row in skipped chunks
        for (int a = 0; a < chunks_; ++a) {
          bool all = true;  // a chunk's cells until one is not below
          for (int X = a * kCellsPerChunk; X < std::min(cx_, (a + 1) * kCellsPerChunk) && all; ++X)
            all = cellBelow(X + cx_ * (Y + cy_ * Z), tiles, p, k, limit_per_view);
          chunk_below[size_t(a)] = uint8_t(all);
          if (all) n += std::min(nx_, (a + 1) * kChunk) - a * kChunk;
        }
        if (n == 0) continue;
        for (int z = Z * kCell; z < std::min(nz_, (Z + 1) * kCell); ++z)
          for (int y = Y * kCell; y < std::min(ny_, (Y + 1) * kCell); ++y) {
            std::copy(chunk_below.begin(), chunk_below.end(),
                      flags->begin() + (size_t(y) + size_t(ny_) * z) * chunks_);
            skipped += size_t(n);
          }
      }
  }
  return skipped;
}

}  // namespace detail
}  // namespace psfs
