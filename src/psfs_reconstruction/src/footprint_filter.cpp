#include "footprint_filter.h"

#include <algorithm>
#include <stdexcept>

#include "classifier_kernels.h"  // PSFS_TARGET_CLONES, PSFS_ALWAYS_INLINE

namespace psfs {
namespace detail {
namespace {

template <class T>
PSFS_ALWAYS_INLINE T med3(T a, T b, T c) {
  return std::max(std::min(a, b), std::min(std::max(a, b), c));
}

// Median of 5: of a..d the middle two are max(min(a, b), min(c, d)) and
// min(max(a, b), max(c, d)); the median of all 5 is the median of those two and e.
template <class T>
PSFS_ALWAYS_INLINE T med5(T a, T b, T c, T d, T e) {
  const T f = std::max(std::min(a, b), std::min(c, d));
  const T g = std::min(std::max(a, b), std::max(c, d));
  return med3(e, f, g);
}

// Row medians of a padded row p (R entries of border on each side) into out[0, W).
PSFS_TARGET_CLONES void rowMedians(const int16_t* __restrict p, int W, int R, int16_t* __restrict out) {
  if (R == 1) {
    for (int u = 0; u < W; ++u) out[u] = med3(p[u], p[u + 1], p[u + 2]);
  } else {
    for (int u = 0; u < W; ++u) out[u] = med5(p[u], p[u + 1], p[u + 2], p[u + 3], p[u + 4]);
  }
}

// Column medians of 2R + 1 rows r[0..2R] into out[0, W).
PSFS_TARGET_CLONES void columnMedians(const int16_t* const* r, int W, int R, int16_t* __restrict out) {
  const int16_t* __restrict a = r[0];
  const int16_t* __restrict b = r[1];
  const int16_t* __restrict c = r[2];
  if (R == 1) {
    for (int u = 0; u < W; ++u) out[u] = med3(a[u], b[u], c[u]);
  } else {
    const int16_t* __restrict d = r[3];
    const int16_t* __restrict e = r[4];
    for (int u = 0; u < W; ++u) out[u] = med5(a[u], b[u], c[u], d[u], e[u]);
  }
}

// Horizontal box sums of a padded byte row p (R border entries each side).
PSFS_TARGET_CLONES void rowSums(const uint8_t* __restrict p, int W, int R, uint16_t* __restrict out) {
  if (R == 1) {
    for (int u = 0; u < W; ++u) out[u] = uint16_t(p[u] + p[u + 1] + p[u + 2]);
  } else {
    for (int u = 0; u < W; ++u) out[u] = uint16_t(p[u] + p[u + 1] + p[u + 2] + p[u + 3] + p[u + 4]);
  }
}

// Rounded means of the column sums of 2R + 1 rows of row sums: (sum + n / 2) / n as
// ((sum + n / 2) * m) >> 20 with m = ceil(2^20 / n), exact for sums below n * 256 and n <= 49
// (the excess of m is < 1, so the error is < 12800 / 2^20 < 1 / 49).
PSFS_TARGET_CLONES void columnMeans(const uint16_t* const* r, int W, int R, uint8_t* __restrict out) {
  const int n = (2 * R + 1) * (2 * R + 1);
  const uint32_t m = ((1u << 20) + n - 1) / n, half = static_cast<uint32_t>(n / 2);
  const uint16_t* __restrict a = r[0];
  const uint16_t* __restrict b = r[1];
  const uint16_t* __restrict c = r[2];
  if (R == 1) {
    for (int u = 0; u < W; ++u) out[u] = uint8_t(((uint32_t(a[u]) + b[u] + c[u] + half) * m) >> 20);
  } else {
    const uint16_t* __restrict d = r[3];
    const uint16_t* __restrict e = r[4];
    for (int u = 0; u < W; ++u)
      out[u] = uint8_t(((uint32_t(a[u]) + b[u] + c[u] + d[u] + e[u] + half) * m) >> 20);
  }
}

// out = lut[in] (a gather GCC leaves scalar; restrict keeps the loads out of the stores' way).
void lookupRow(const uint8_t* __restrict in, const int16_t* __restrict lut, int W, int16_t* __restrict out) {
  for (int u = 0; u < W; ++u) out[u] = lut[in[u]];
}

void checkRadius(int R) {
  if (R != 1 && R != 2) throw std::invalid_argument("psfs: footprint filter radius must be 1 or 2");
}

template <class T>
void padRow(const T* row, int W, int R, T* p) {
  for (int k = 0; k < R; ++k) p[k] = row[0], p[R + W + k] = row[W - 1];
  std::copy(row, row + W, p + R);
}

}  // namespace

void medianFilterTerms(const int16_t* src, int W, int H, int R, int16_t* dst, FootprintScratch* s) {
  checkRadius(R);
  // Row medians of every row, then column medians with clamped row indices.
  s->rows.resize(size_t(W) * H + W + 2 * R);
  int16_t* med = s->rows.data();
  int16_t* pad = med + size_t(W) * H;
  for (int v = 0; v < H; ++v) {
    padRow(src + size_t(v) * W, W, R, pad);
    rowMedians(pad, W, R, med + size_t(v) * W);
  }
  const int16_t* r[5];
  for (int v = 0; v < H; ++v) {
    for (int k = -R; k <= R; ++k) r[k + R] = med + size_t(std::clamp(v + k, 0, H - 1)) * W;
    columnMedians(r, W, R, dst + size_t(v) * W);
  }
}

void meanFilterTerms(const uint8_t* src, int W, int H, int R, const int16_t* lut, int16_t* dst,
                     FootprintScratch* s) {
  checkRadius(R);
  s->sums.resize(size_t(W) * H);
  s->bytes.resize(size_t(2) * W + 2 * R);
  uint16_t* sums = s->sums.data();
  uint8_t* pad = s->bytes.data();
  uint8_t* means = pad + W + 2 * R;
  for (int v = 0; v < H; ++v) {
    padRow(src + size_t(v) * W, W, R, pad);
    rowSums(pad, W, R, sums + size_t(v) * W);
  }
  const uint16_t* r[5];
  for (int v = 0; v < H; ++v) {
    for (int k = -R; k <= R; ++k) r[k + R] = sums + size_t(std::clamp(v + k, 0, H - 1)) * W;
    columnMeans(r, W, R, means);
    lookupRow(means, lut, W, dst + size_t(v) * W);
  }
}

int16_t separableMedianAt(const int16_t* src, int W, int H, int R, int u, int v) {
  std::vector<int16_t> col;
  for (int dv = -R; dv <= R; ++dv) {
    std::vector<int16_t> row;
    const int vv = std::clamp(v + dv, 0, H - 1);
    for (int du = -R; du <= R; ++du) row.push_back(src[size_t(vv) * W + std::clamp(u + du, 0, W - 1)]);
    std::sort(row.begin(), row.end());
    col.push_back(row[R]);
  }
  std::sort(col.begin(), col.end());
  return col[R];
}

uint8_t boxMeanAt(const uint8_t* src, int W, int H, int R, int u, int v) {
  int sum = 0, n = 0;
  for (int dv = -R; dv <= R; ++dv)
    for (int du = -R; du <= R; ++du, ++n)
      sum += src[size_t(std::clamp(v + dv, 0, H - 1)) * W + std::clamp(u + du, 0, W - 1)];
  return static_cast<uint8_t>((sum + n / 2) / n);
}

}  // namespace detail
}  // namespace psfs
