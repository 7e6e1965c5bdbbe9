// Private: squares of 2^l x 2^l tiles over an image of tiles, for the skipping bounds' "largest
// value over a rectangle of tiles" (TileMaxImage in empty_space_bound.h, TermTiles in
// centre_space_bound.h). Level 0 holds each tile's figure; level l, at the index of its top-left
// tile (tx, ty), the figures of the tiles [tx, tx + 2^l) x [ty, ty + 2^l) combined (clamped at
// the image's last row and column). Any rectangle of tiles is then covered by a few squares of
// the largest level that fits in it (overlapping where they must: the combination is a max).
#pragma once

#include <algorithm>
#include <cstddef>
#include <vector>

namespace psfs {
namespace detail {

// The level of the squares a rectangle of `side` tiles (its shorter side) is walked with: the
// largest 2^l <= side, at most num_levels - 1.
inline int tileSquareLevel(int side, int num_levels) {
  int l = 0;
  while (l + 1 < num_levels && (2 << l) <= side) ++l;
  return l;
}

// The combination of figures that are upper bounds: the larger.
struct MaxOf {
  template <class T>
  T operator()(T a, T b) const { return a > b ? a : b; }
};

// levels[1 .. num_levels - 1] from levels[0] (tiles_x * tiles_y figures, row by row);
// combine(a, b): the figure of the union (commutative, associative, idempotent: e.g. max).
template <class T, class Combine>
void buildTileSquares(std::vector<T>* levels, int num_levels, int tiles_x, int tiles_y, Combine combine) {
  for (int l = 1; l < num_levels; ++l) {
    levels[l].resize(levels[0].size());
    const int h = 1 << (l - 1);  // the squares of level l - 1 that make one of level l
    for (int ty = 0; ty < tiles_y; ++ty) {
      const T* __restrict s0 = &levels[l - 1][size_t(ty) * tiles_x];
      const T* __restrict s1 = &levels[l - 1][size_t(std::min(ty + h, tiles_y - 1)) * tiles_x];
      T* __restrict d = &levels[l][size_t(ty) * tiles_x];
      auto four = [&](int tx, int tx2) { return combine(combine(s0[tx], s0[tx2]), combine(s1[tx], s1[tx2])); };
      int tx = 0;
      for (; tx + h < tiles_x; ++tx) d[tx] = four(tx, tx + h);  // no clamp here: vectorises
      for (; tx < tiles_x; ++tx) d[tx] = four(tx, tiles_x - 1);
    }
  }
}

// The figures of the tiles [a0, a1] x [b0, b1] (inclusive, inside the image) combined, starting
// from `init` (the combination's neutral figure).
template <class T, class Combine>
T tileSquaresOver(const std::vector<T>* levels, int num_levels, int tiles_x, int a0, int b0, int a1, int b1,
                  T init, Combine combine) {
  const int l = tileSquareLevel(std::min(a1 - a0, b1 - b0) + 1, num_levels);
  const int step = 1 << l;
  const int a_last = a1 - step + 1, b_last = b1 - step + 1;  // the last squares' top-left tiles
  const T* t = levels[l].data();
  T r = init;
  for (int b = b0;; b += step) {
    const T* row = t + size_t(std::min(b, b_last)) * tiles_x;
    for (int a = a0;; a += step) {
      r = combine(r, row[std::min(a, a_last)]);
      if (a >= a_last) break;
    }
    if (b >= b_last) break;
  }
  return r;
}

}  // namespace detail
}  // namespace psfs
