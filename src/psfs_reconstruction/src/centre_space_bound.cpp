#include "centre_space_bound.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "cpu_dispatch.h"
#include "empty_space_bound.h"
#include "tile_squares.h"
#include "voxel_projection.h"

#include <Eigen/Core>

namespace psfs {
namespace detail {
namespace {

// Slack (1/16 px) around the box of a cell's projected corners, before the lens: without
// distortion the centres' images lie in the hull of the corners' images and truncation to
// 1/16 px is monotone, so 2 only covers float against float (the lattice's row constants and
// the voxels' differ in their last bits). The distortion's share is per box (lensSlack16).
constexpr int kSlack16 = 2;

// The pixels whose centres the positions [a16, b16] (PackedUV units: 16 (u + 1/2), truncated)
// can round to, widened by `slack` (1/16 px): floor((a16 - slack) / 16) .. floor((b16 + slack) / 16).
inline int pixelLow(int a16, int slack) {
  const int a = a16 - slack;
  return a >= 0 ? a >> 4 : -((15 - a) >> 4);
}
inline int pixelHigh(int b16, int slack) { return (b16 + slack) >> 4; }

// The distortion's shape over the image's normalised extent (the image corners undistorted,
// times 1.2, within the lens model's valid radius), from second and first differences on a grid
// of points along the axes and diagonals: c2, an upper bound of |D''[d, d]| over unit directions d
// (doubled for the points and directions between the samples), and s_min, a lower bound of the
// smallest singular value of the Jacobian (halved likewise): a box whose corners' images span a
// diameter L_d spans at most L_d / s_min before the lens, and its image lies within
// c2 (L_d / s_min)^2 / 2 of their hull (Taylor: q = sum l_i q_i, D(q_i) = D(q) + J (q_i - q) + R_i,
// |R_i| <= c2 |q_i - q|^2 / 2). No distortion: c2 = 0.
struct LensShape {
  double c2 = 0.0, s_min = 1.0;
};
LensShape lensShape(const tabletop_capture::CameraModel& m, float r2_max) {
  LensShape shape;
  if (!m.hasDistortion()) return shape;
  double xs = 0.0, ys = 0.0;
  for (double u : {0.0, double(m.width)})
    for (double v : {0.0, double(m.height)}) {
      const Eigen::Vector2d q = m.undistort(Eigen::Vector2d((u - m.cx) / m.fx, (v - m.cy) / m.fy));
      xs = std::max(xs, std::abs(q.x())), ys = std::max(ys, std::abs(q.y()));
    }
  xs *= 1.2, ys *= 1.2;
  const double r2 = std::isfinite(r2_max) ? double(r2_max) : std::numeric_limits<double>::infinity();
  constexpr int kSamples = 24;
  constexpr double h = 1e-3;
  const Eigen::Vector2d dirs[4] = {{1, 0}, {0, 1}, {M_SQRT1_2, M_SQRT1_2}, {M_SQRT1_2, -M_SQRT1_2}};
  double c2 = 0.0, s_min = std::numeric_limits<double>::infinity();
  for (int j = 0; j <= kSamples; ++j)
    for (int i = 0; i <= kSamples; ++i) {
      const Eigen::Vector2d q(xs * (2.0 * i / kSamples - 1.0), ys * (2.0 * j / kSamples - 1.0));
      if (q.squaredNorm() > r2) continue;
      const Eigen::Vector2d d0 = m.distort(q);
      for (const Eigen::Vector2d& d : dirs)
        c2 = std::max(c2, (m.distort(q + h * d) - 2.0 * d0 + m.distort(q - h * d)).norm() / (h * h));
      Eigen::Matrix2d jac;
      jac.col(0) = (m.distort(q + Eigen::Vector2d(h, 0)) - m.distort(q - Eigen::Vector2d(h, 0))) / (2 * h);
      jac.col(1) = (m.distort(q + Eigen::Vector2d(0, h)) - m.distort(q - Eigen::Vector2d(0, h))) / (2 * h);
      // The smallest singular value of a 2x2 matrix.
      const double a = jac.squaredNorm(), det = std::abs(jac.determinant());
      s_min = std::min(s_min, std::sqrt(std::max(0.0, 0.5 * (a - std::sqrt(std::max(0.0, a * a - 4.0 * det * det))))));
    }
  shape.c2 = 2.0 * c2;
  shape.s_min = std::isfinite(s_min) ? std::max(1e-3, 0.5 * s_min) : 1e-3;
  return shape;
}

}  // namespace

CentreSpaceBound::CornerSpan CentreSpaceBound::cornerSpan(int c, int X0, int Y0, int Z0, int X1, int Y1,
                                                          int Z1) const {
  const uint32_t none = PackedUV::notObserved(lattice_table_->camera(c).height);
  CornerSpan s;
  for (int i = 0; i < 8; ++i) {
    const uint32_t q = corner(c, i & 1 ? X1 : X0, i & 2 ? Y1 : Y0, i & 4 ? Z1 : Z0);
    if (q == none) {
      s.unknown = true;
      continue;
    }
    const int u = int(q & 0xFFFFu), v = int(q >> 16);
    s.u0 = std::min(s.u0, u), s.u1 = std::max(s.u1, u), s.v0 = std::min(s.v0, v), s.v1 = std::max(s.v1, v);
  }
  return s;
}

CentreSpaceBound::PixelBox CentreSpaceBound::boxPixels(int c, int X0, int Y0, int Z0, int X1, int Y1, int Z1) const {
  const CornerSpan s = cornerSpan(c, X0, Y0, Z0, X1, Y1, Z1);
  PixelBox b;
  b.unknown = s.unknown;
  if (b.unknown) return b;
  const int slack = kSlack16 + (lens_k_[size_t(c)] > 0.0 ? lensSlack16(c, s.u1 - s.u0, s.v1 - s.v0) : 0);
  b.u0 = pixelLow(s.u0, slack), b.u1 = pixelHigh(s.u1, slack);
  b.v0 = pixelLow(s.v0, slack), b.v1 = pixelHigh(s.v1, slack);
  return b;
}

int CentreSpaceBound::lensSlack16(int c, int du16, int dv16) const {
  // c2 L^2 / 2 in pixels (times f), L^2 before the lens from the distorted extent in 1/16 px:
  // (du^2 + dv^2) / (16 f s_min)^2 (lensShape).
  const double slack = lens_k_[size_t(c)] * (double(du16) * du16 + double(dv16) * dv16);
  return slack > 1e6 ? 1000000 : int(std::ceil(slack));
}


void TermTiles::set(const uint8_t* bytes, size_t stride, int step, int width, int height, const cv::Mat& active,
                    const int16_t* terms, int u0, int v0, int u1, int v1) {
  if (u1 < u0 || v1 < v0) {
    tiles_x = tiles_y = 0;
    return;
  }
  tx0 = u0 / kTile, ty0 = v0 / kTile;
  tiles_x = u1 / kTile - tx0 + 1, tiles_y = v1 / kTile - ty0 + 1;
  level_[0].resize(size_t(tiles_x) * tiles_y);  // the squares sized by buildTileSquares
  // Whole tiles (clipped to the image), so a rectangle's tiles hold every pixel of it.
  const int pu0 = tx0 * kTile, pu1 = std::min(width - 1, (tx0 + tiles_x) * kTile - 1);
  const int pv0 = ty0 * kTile, pv1 = std::min(height - 1, (ty0 + tiles_y) * kTile - 1);
  const int n = pu1 - pu0 + 1;
  std::vector<int16_t> col_max(static_cast<size_t>(n));
  std::vector<uint8_t> col_off(static_cast<size_t>(n));
  for (int ty = 0; ty < tiles_y; ++ty) {
    std::fill(col_max.begin(), col_max.end(), int16_t(-1));
    std::fill(col_off.begin(), col_off.end(), uint8_t(0));
    for (int v = pv0 + ty * kTile; v <= std::min(pv1, pv0 + ty * kTile + kTile - 1); ++v) {
      const uint8_t* row = bytes + size_t(v) * stride + size_t(pu0) * step;
      const uint8_t* a = active.empty() ? nullptr : active.ptr<uint8_t>(v) + pu0;
      const int16_t* t = terms ? terms + size_t(v) * width + pu0 : nullptr;
      int16_t* __restrict cm = col_max.data();
      uint8_t* __restrict co = col_off.data();
      if (step == 1 && !a && !t) {  // every pixel gives evidence (the common case)
        for (int i = 0; i < n; ++i) cm[i] = std::max(cm[i], int16_t(row[i]));
      } else if (step == 1 && t) {  // the evidence's switched-off pixels (known occlusions)
        for (int i = 0; i < n; ++i) {
          const bool off = t[i] > 0;
          cm[i] = std::max(cm[i], off ? int16_t(-1) : int16_t(row[i]));
          co[i] |= uint8_t(off);
        }
      } else {
        for (int i = 0; i < n; ++i) {
          const bool off = a ? a[i] == 0 : t ? t[i] > 0 : false;
          cm[i] = std::max(cm[i], off ? int16_t(-1) : int16_t(row[size_t(i) * step]));
          co[i] |= uint8_t(off);
        }
      }
    }
    for (int tx = 0; tx < tiles_x; ++tx) {
      int m = -1;
      uint8_t o = 0;
      for (int i = tx * kTile; i < std::min(n, (tx + 1) * kTile); ++i)
        m = std::max(m, int(col_max[size_t(i)])), o |= col_off[size_t(i)];
      level_[0][size_t(ty) * tiles_x + tx] = pack(m, o);
    }
  }
  // Every tile with evidence and none without (no mask, no known occlusion here: the common
  // case): the levels in one byte per tile, half the memory the cells' lookups walk.
  clean_ = true;
  for (const uint16_t t : level_[0]) clean_ = clean_ && (t & 0x8000) == 0 && (t & 0x1FF) > 0;
  if (clean_) {
    level8_[0].resize(level_[0].size());
    for (size_t i = 0; i < level_[0].size(); ++i) level8_[0][i] = uint8_t((level_[0][i] & 0x1FF) - 1);
    buildTileSquares(level8_, kLevels, tiles_x, tiles_y, MaxOf());
    return;
  }
  // Squares of 2^l x 2^l tiles (tile_squares.h): any rectangle of tiles is the union of a few.
  buildTileSquares(level_, kLevels, tiles_x, tiles_y, combine);
}

void TermTiles::rectMax(int u0, int v0, int u1, int v1, int* max_byte_out, bool* off_out) const {
  const int a0 = u0 / kTile - tx0, a1 = u1 / kTile - tx0, b0 = v0 / kTile - ty0, b1 = v1 / kTile - ty0;
  if (clean_) {
    *max_byte_out = tileSquaresOver(level8_, kLevels, tiles_x, a0, b0, a1, b1, uint8_t(0), MaxOf());
    *off_out = false;
    return;
  }
  const uint16_t r = tileSquaresOver(level_, kLevels, tiles_x, a0, b0, a1, b1, pack(-1, false), combine);
  *max_byte_out = int(r & 0x1FF) - 1;
  *off_out = (r & 0x8000) != 0;
}

void CentreSpaceBound::projectLattice(const ProjectionTable& table, int threads) {
  const VoxelGrid& g = table.grid();
  nx_ = g.dims.x(), ny_ = g.dims.y(), nz_ = g.dims.z();
  cx_ = (nx_ + kCell - 1) / kCell, cy_ = (ny_ + kCell - 1) / kCell, cz_ = (nz_ + kCell - 1) / kCell;
  cameras_ = table.numCameras();
  if (cameras_ > kMaxBoundCameras) throw std::invalid_argument("psfs::CentreSpaceBound: more than 64 cameras");
  // The cells' face corners, origin + kCell s (X, Y, Z), are the centres of a grid of voxels kCell
  // times as large, shifted by half of one: projected by the table's own code (a stored table,
  // built in parallel), at 1/16 px. The last corner along an axis may lie past the grid's end
  // (a larger box: still a bound).
  VoxelGrid lattice;
  lattice.origin = g.origin - Eigen::Vector3d::Constant(0.5 * kCell * g.voxel_size);
  lattice.voxel_size = kCell * g.voxel_size;
  lattice.dims = Eigen::Vector3i(cx_ + 1, cy_ + 1, cz_ + 1);
  std::vector<tabletop_capture::CameraModel> cameras;
  for (int c = 0; c < cameras_; ++c) cameras.push_back(table.camera(c));
  // The lens slack's factor per camera, derived again when a camera's intrinsics change.
  bool same = lens_cameras_.size() == cameras.size();
  for (size_t c = 0; same && c < cameras.size(); ++c) {
    const auto& a = lens_cameras_[c];
    const auto& b = cameras[c];
    same = a.width == b.width && a.height == b.height && a.fx == b.fx && a.fy == b.fy && a.cx == b.cx &&
           a.cy == b.cy && a.distortion == b.distortion;
  }
  if (!same) {
    lens_k_.assign(cameras.size(), 0.0);
    for (size_t c = 0; c < cameras.size(); ++c) {
      const auto& m = cameras[c];
      const double f_min = std::min(m.fx, m.fy), f_max = std::max(m.fx, m.fy);
      // 16 (1/16 px) * f_max * c2 / (2 (16 f_min s_min)^2) per (1/16 px)^2 of extent.
      const LensShape shape = lensShape(m, table.projectionCamera(int(c)).r2_max);
      lens_k_[c] = 16.0 * f_max * shape.c2 / (2.0 * 256.0 * f_min * f_min * shape.s_min * shape.s_min);
    }
    lens_cameras_ = cameras;
  }
  if (!lattice_table_) {
    ProjectionTableOptions o;
    o.storage = TableStorage::kPrecomputed;
    o.threads = threads;
    lattice_table_ = std::make_unique<ProjectionTable>(lattice, cameras, o);
  } else {
    lattice_table_->update(lattice, cameras);
  }
  lattice_packed_ = lattice_table_->rowCentres(0, nullptr);
  lattice_nxp_ = lattice_table_->paddedRowLength();
}

template <class SetTiles>
double CentreSpaceBound::flagChunks(const ProjectionTable& table, const SetTiles& set_tiles, const PsfsRowParams& p,
                                    int k, double max_probability, int threads, std::vector<uint8_t>* flags) {
  const int32_t limit_per_view = boundLimitPerView(p, max_probability);
  projectLattice(table, threads);
  const int px = cx_ + 1, py = cy_ + 1, pz = cz_ + 1;
  // Each camera's window: the pixels the projected corners can round to (derived again only
  // when the lattice's projections change: a grid that stays keeps its windows).
  const uint64_t lattice_revision = lattice_table_->revision();
  const bool windows_kept = windows_revision_ == lattice_revision && windows_.size() == size_t(cameras_) * 4;
  if (!windows_kept) windows_.assign(size_t(cameras_) * 4, 0);
  tiles_.resize(size_t(cameras_));
#pragma omp parallel for num_threads(resolveThreads(threads)) schedule(dynamic, 1)
  for (int c = 0; c < cameras_; ++c) {
    int* win = &windows_[size_t(c) * 4];
    if (!windows_kept) {
      const uint32_t none = PackedUV::notObserved(table.camera(c).height);
      int u0 = std::numeric_limits<int>::max(), u1 = -1, v0 = u0, v1 = -1;
      for (int Z = 0; Z < pz; ++Z)
        for (int Y = 0; Y < py; ++Y)
          for (int X = 0; X < px; ++X) {
            const uint32_t q = corner(c, X, Y, Z);
            if (q == none) continue;
            const int u = int(q & 0xFFFFu), v = int(q >> 16);
            u0 = std::min(u0, u), u1 = std::max(u1, u), v0 = std::min(v0, v), v1 = std::max(v1, v);
          }
      // The largest lens slack of any box (a block's, which holds its cells' boxes).
      int slack = kSlack16;
      if (lens_k_[size_t(c)] > 0.0)
        for (int Z = 0; Z < cz_; Z += 2)
          for (int Y = 0; Y < cy_; Y += 2)
            for (int X = 0; X < cx_; X += 2) {
              const CornerSpan b = cornerSpan(c, X, Y, Z, std::min(cx_, X + 2), std::min(cy_, Y + 2), std::min(cz_, Z + 2));
              if (b.u1 >= 0) slack = std::max(slack, kSlack16 + lensSlack16(c, b.u1 - b.u0, b.v1 - b.v0));
            }
      const int w = table.camera(c).width, h = table.camera(c).height;
      win[0] = std::max(0, pixelLow(u0, slack)), win[1] = std::max(0, pixelLow(v0, slack));
      win[2] = std::min(w - 1, pixelHigh(u1, slack)), win[3] = std::min(h - 1, pixelHigh(v1, slack));
    }
    set_tiles(c, &tiles_[size_t(c)], win[0], win[1], win[2], win[3]);
  }
  windows_revision_ = lattice_revision;
  const size_t n_cells = size_t(cx_) * cy_ * cz_;
  below_.assign(n_cells, 0);
  const int first_layer = std::clamp(p.first_layer, 0, nz_);
  // Without occlusion tolerance a cell is below as soon as the bounds of the cameras that see
  // all of it sum below C limit: no voxel has more than C views, every further term is <= 0,
  // and a voxel with fewer views than min_views fuses to 0 (limit <= 0: a level reachable at all).
  int32_t terms[256];  // the log term of each byte (ViewEvidence::logTerm)
  for (int v = 0; v < 256; ++v) terms[v] = ViewEvidence::logTerm(v);
  const bool early = k == 0 && limit_per_view <= 0;
  const int64_t early_sum = int64_t(cameras_) * limit_per_view;
  // Whether every voxel of the box of cells [X0, X1) x [Y0, Y1) x [Z0, Z1) fuses below the level:
  // its image in each camera lies in the box of its 8 corners' images (a convex hull).
  // A grid that stays where it was (the workspace's) keeps its boxes from its second frame on;
  // one that moves (a hand's cube) derives the boxes it needs as it goes.
  const int bx = (cx_ + 1) / 2, by = (cy_ + 1) / 2, bz = (cz_ + 1) / 2;  // blocks of 2 x 2 x 2 cells
  const uint64_t revision = lattice_table_->revision();
  if (revision == last_revision_ && boxes_revision_ != revision) {
    cell_boxes_.resize(n_cells * cameras_);
    block_boxes_.resize(size_t(bx) * by * bz * cameras_);
#pragma omp parallel for num_threads(resolveThreads(threads)) schedule(static)
    for (int Z = 0; Z < cz_; ++Z)
      for (int Y = 0; Y < cy_; ++Y)
        for (int X = 0; X < cx_; ++X)
          for (int c = 0; c < cameras_; ++c) {
            cell_boxes_[((size_t(Z) * cy_ + Y) * cx_ + X) * cameras_ + c] = boxPixels(c, X, Y, Z, X + 1, Y + 1, Z + 1);
            if (X % 2 == 0 && Y % 2 == 0 && Z % 2 == 0)
              block_boxes_[((size_t(Z / 2) * by + Y / 2) * bx + X / 2) * cameras_ + c] =
                  boxPixels(c, X, Y, Z, std::min(cx_, X + 2), std::min(cy_, Y + 2), std::min(cz_, Z + 2));
          }
    boxes_revision_ = revision;
  }
  last_revision_ = revision;
  const bool cached = boxes_revision_ == revision;
  // cache: the box's entries of cell_boxes_ / block_boxes_ when cached, else nullptr.
  auto boxBelow = [&](int X0, int Y0, int Z0, int X1, int Y1, int Z1, const PixelBox* cache) {
    int32_t all[kMaxBoundCameras], some[kMaxBoundCameras];
    int n_all = 0, n_some = 0;
    int64_t sum_all = 0;
    for (int c = 0; c < cameras_; ++c) {
      const PixelBox box = cache ? cache[c] : boxPixels(c, X0, Y0, Z0, X1, Y1, Z1);
      // A corner outside the image or the lens model's range: where the cell's voxels land
      // is not known, so the camera may give any of them any evidence (a term <= 0).
      if (box.unknown) {
        some[n_some++] = 0;
        continue;
      }
      const int w = table.camera(c).width, h = table.camera(c).height;
      const int ru0 = box.u0, ru1 = box.u1, rv0 = box.v0, rv1 = box.v1;
      if (ru1 < 0 || ru0 > w - 1 || rv1 < 0 || rv0 > h - 1) continue;  // no voxel in the image
      const bool inside = ru0 >= 0 && ru1 <= w - 1 && rv0 >= 0 && rv1 <= h - 1;
      const int cu0 = std::max(ru0, 0), cv0 = std::max(rv0, 0), cu1 = std::min(ru1, w - 1), cv1 = std::min(rv1, h - 1);
      // A box wider than the camera's window (its slack above the window's; not seen on the
      // rigs measured) has no tiles there: the camera may give any term.
      const int* win = &windows_[size_t(c) * 4];
      if (cu0 < win[0] || cv0 < win[1] || cu1 > win[2] || cv1 > win[3]) {
        some[n_some++] = 0;
        continue;
      }
      int m;
      bool off;
      tiles_[size_t(c)].rectMax(cu0, cv0, cu1, cv1, &m, &off);
      if (m < 0) continue;  // no pixel there gives evidence
      const int32_t b = terms[m];
      if (inside && !off) {
        all[n_all++] = b;
        sum_all += b;
        if (early && sum_all < early_sum) return true;
      } else {
        some[n_some++] = b;
      }
    }
    return boundBelow(all, n_all, some, n_some, p, k, limit_per_view);
  };
  // Blocks first: far from the hand a block is below as a whole (a looser box, an eighth of
  // the work), the cells of the others one by one.
#pragma omp parallel for num_threads(resolveThreads(threads)) schedule(dynamic, 1)
  for (int BZ = 0; BZ < bz; ++BZ)
    for (int BY = 0; BY < by; ++BY)
      for (int BX = 0; BX < bx; ++BX) {
        const int X0 = 2 * BX, Y0 = 2 * BY, Z0 = 2 * BZ;
        const int X1 = std::min(cx_, X0 + 2), Y1 = std::min(cy_, Y0 + 2), Z1 = std::min(cz_, Z0 + 2);
        const PixelBox* block_cache = cached ? &block_boxes_[((size_t(BZ) * by + BY) * bx + BX) * cameras_] : nullptr;
        if (Z1 * kCell <= first_layer || boxBelow(X0, Y0, Z0, X1, Y1, Z1, block_cache)) {  // (under the floor: 0)
          for (int Z = Z0; Z < Z1; ++Z)
            for (int Y = Y0; Y < Y1; ++Y)
              for (int X = X0; X < X1; ++X) below_[(size_t(Z) * cy_ + Y) * cx_ + X] = 1;
          continue;
        }
        for (int Z = Z0; Z < Z1; ++Z)
          for (int Y = Y0; Y < Y1; ++Y)
            for (int X = X0; X < X1; ++X)
              below_[(size_t(Z) * cy_ + Y) * cx_ + X] =
                  uint8_t((Z + 1) * kCell <= first_layer ||
                          boxBelow(X, Y, Z, X + 1, Y + 1, Z + 1,
                                   cached ? &cell_boxes_[((size_t(Z) * cy_ + Y) * cx_ + X) * cameras_] : nullptr));
      }
  // The margin: a chunk of a row is skipped when the cells of the voxels within 2 of its voxels
  // along each axis (voxels 8a - 2 .. 8a + 9 of rows y - 2 .. y + 2 in layers z - 2 .. z + 2) are
  // all below; marching cubes reads a crossed edge's voxels and, for the normals, their
  // central differences, so no voxel it reads near a voxel above the level is skipped. First
  // per cell row and chunk the cells along x, then per grid row the one or two cell rows along
  // y and z those voxels lie in (outside the grid counts as below).
  const int chunks = table.chunksPerRow();
  auto cellOf = [](int v) { return v < 0 ? -1 : v / kCell; };
  x_below_.assign(size_t(cy_) * cz_ * chunks, 0);
  for (int Z = 0; Z < cz_; ++Z)
    for (int Y = 0; Y < cy_; ++Y) {
      const uint8_t* b = &below_[(size_t(Z) * cy_ + Y) * cx_];
      for (int a = 0; a < chunks; ++a) {
        bool all = true;
        for (int X = std::max(0, cellOf(a * kChunk - 2)); X <= std::min(cx_ - 1, cellOf(a * kChunk + kChunk + 1)); ++X)
          all = all && b[X];
        x_below_[(size_t(Z) * cy_ + Y) * chunks + a] = uint8_t(all);
      }
    }
  flags->assign(size_t(ny_) * nz_ * chunks, 0);
  size_t skipped = 0;
  for (int z = first_layer; z < nz_; ++z) {
    const int z0 = std::max(0, cellOf(z - 2)), z1 = std::min(cz_ - 1, cellOf(z + 2));
    int y0_prev = -1, y1_prev = -1;
    size_t n_prev = 0;
    for (int y = 0; y < ny_; ++y) {
      uint8_t* f = flags->data() + (size_t(y) + size_t(ny_) * z) * chunks;
      const int y0 = std::max(0, cellOf(y - 2)), y1 = std::min(cy_ - 1, cellOf(y + 2));
      if (y0 == y0_prev && y1 == y1_prev) {  // the same cells as the row before (most rows)
        std::copy(f - chunks, f, f);
        skipped += n_prev;
        continue;
      }
      y0_prev = y0, y1_prev = y1;
      std::fill(f, f + chunks, uint8_t(1));
      for (int Z = z0; Z <= z1; ++Z)
        for (int Y = y0; Y <= y1; ++Y) {
          const uint8_t* xb = &x_below_[(size_t(Z) * cy_ + Y) * chunks];
          for (int a = 0; a < chunks; ++a) f[a] &= xb[a];
        }
      n_prev = 0;
      for (int a = 0; a < chunks; ++a)
        if (f[a]) n_prev += size_t(std::min(nx_, (a + 1) * kChunk) - a * kChunk);
      skipped += n_prev;
    }
  }
  const size_t voxels = size_t(nx_) * ny_ * nz_;
  return voxels == 0 ? 0.0 : double(skipped) / double(voxels);
}

double CentreSpaceBound::skippableChunks(const ProjectionTable& table, const ViewEvidence& evidence,
                                         const PsfsRowParams& p, int k, double max_probability, int threads,
                                         std::vector<uint8_t>* flags) {
  if (evidence.numViews() != table.numCameras())
    throw std::invalid_argument("psfs::CentreSpaceBound: evidence for " + std::to_string(evidence.numViews()) +
                                " cameras, table has " + std::to_string(table.numCameras()));
  for (int c = 0; c < table.numCameras(); ++c)
    if (evidence.width(c) != table.camera(c).width || evidence.height(c) != table.camera(c).height)
      throw std::invalid_argument("psfs::CentreSpaceBound: evidence view " + std::to_string(c) +
                                  " is not of its camera's size");
  return flagChunks(
      table,
      [&](int c, TermTiles* t, int u0, int v0, int u1, int v1) {
        const int w = evidence.width(c), h = evidence.height(c);
        t->set(evidence.likelihood(c), size_t(w), 1, w, h, cv::Mat(),
               evidence.hasInactivePixels(c) ? evidence.terms(c) : nullptr, u0, v0, u1, v1);
      },
      p, k, max_probability, threads, flags);
}

double CentreSpaceBound::skippableChunks(const ProjectionTable& table, const std::vector<ViewImage>& views,
                                         const PsfsRowParams& p, int k, double max_probability, int threads,
                                         std::vector<uint8_t>* flags) {
  if (int(views.size()) != table.numCameras())
    throw std::invalid_argument("psfs::CentreSpaceBound: " + std::to_string(views.size()) + " views, table has " +
                                std::to_string(table.numCameras()) + " cameras");
  for (int c = 0; c < table.numCameras(); ++c) {
    const cv::Mat& l = views[size_t(c)].likelihood;
    if (l.depth() != CV_8U || l.cols != table.camera(c).width || l.rows != table.camera(c).height ||
        views[size_t(c)].channel < 0 || views[size_t(c)].channel >= l.channels() ||
        (!views[size_t(c)].active.empty() && (views[size_t(c)].active.type() != CV_8UC1 ||
                                              views[size_t(c)].active.size() != l.size())))
      throw std::invalid_argument("psfs::CentreSpaceBound: view " + std::to_string(c) +
                                  " is not an 8-bit image of its camera's size (or its channel or mask is wrong)");
  }
  return flagChunks(
      table,
      [&](int c, TermTiles* t, int u0, int v0, int u1, int v1) {
        const ViewImage& v = views[size_t(c)];
        t->set(v.likelihood.ptr<uint8_t>(0) + v.channel, v.likelihood.step[0], v.likelihood.channels(),
               v.likelihood.cols, v.likelihood.rows, v.active, nullptr, u0, v0, u1, v1);
      },
      p, k, max_probability, threads, flags);
}

void zeroChunks(const ProjectionTable& table, const std::vector<uint8_t>& flags, ProbabilityVolume* out) {
  const int nx = table.grid().dims.x(), chunks = table.chunksPerRow();
  for (size_t r = 0; r < table.grid().numRows(); ++r)
    for (int a = 0; a < chunks; ++a)
      if (flags[r * chunks + a])
        std::fill(out->data.begin() + r * nx + a * kVoxChunk, out->data.begin() + r * nx + std::min(nx, (a + 1) * kVoxChunk),
                  uint8_t(0));
}

}  // namespace detail
}  // namespace psfs
