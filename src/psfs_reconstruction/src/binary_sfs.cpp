#include "psfs_reconstruction/binary_sfs.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include "cpu_dispatch.h"
#include "fusion_common.h"

namespace psfs {

BinarySfs::BinarySfs(const BinarySfsOptions& o) : options_(o) {
  if (!std::isfinite(o.threshold) || o.threshold < 0.0 || !(o.threshold < 1.0))
    throw std::invalid_argument("psfs::BinarySfsOptions: threshold must be in [0, 1)");
  if (o.min_views < 1) throw std::invalid_argument("psfs::BinarySfsOptions: min_views must be >= 1");
  if (o.threads < 0) throw std::invalid_argument("psfs::BinarySfsOptions: threads must be >= 0");
}

void BinarySfs::setSilhouettes(const ViewEvidence& e) {
  const int tb = thresholdByte(options_.threshold);
  const int n = e.numViews();
  silhouettes_.resize(n);
#pragma omp parallel for schedule(dynamic, 1) num_threads(resolveThreads(options_.threads))
  for (int c = 0; c < n; ++c) {
    Silhouette& s = silhouettes_[c];
    s.width = e.width(c);
    s.height = e.height(c);
    const size_t np = size_t(s.width) * s.height;
    s.code.resize(np + 1);
    const uint8_t* lk = e.likelihood(c);
    const int16_t* tm = e.terms(c);
    for (size_t i = 0; i < np; ++i) s.code[i] = tm[i] > 0 ? 2 : (lk[i] > tb ? 1 : 0);
    s.code[np] = 2;
  }
}

void BinarySfs::carve(const ProjectionTable& table, ProbabilityVolume* out) const {
  if (!out) throw std::invalid_argument("psfs::BinarySfs::carve: null output");
  const int C = table.numCameras();
  if (table.footprintLevels() > 0)
    throw std::invalid_argument("psfs::BinarySfs::carve: the table has footprint levels");
  if (static_cast<int>(silhouettes_.size()) != C)
    throw std::invalid_argument("psfs::BinarySfs::carve: " + std::to_string(silhouettes_.size()) +
                                " silhouettes for " + std::to_string(C) + " cameras");
  std::vector<const uint8_t*> codes(C);
  std::vector<int> widths(C);
  for (int c = 0; c < C; ++c) {
    if (silhouettes_[c].width != table.camera(c).width || silhouettes_[c].height != table.camera(c).height)
      throw std::invalid_argument("psfs::BinarySfs::carve: silhouette " + std::to_string(c) +
                                  " does not match camera '" + table.camera(c).name + "' in size");
    codes[c] = silhouettes_[c].code.data();
    widths[c] = silhouettes_[c].width;
  }
  out->grid = table.grid();
  out->data.resize(table.grid().numVoxels());
  const int nx = table.grid().dims.x(), nxp = table.paddedRowLength();
  const int min_views = options_.min_views;
  uint8_t* dst = out->data.data();
  detail::forEachRow(table, options_.threads, 8, [&](size_t r, const uint32_t* centres) {
    // Same cache policy as the pSfS kernel: the table streams past without evicting the
    // silhouette codes (a 128x128x96 table is larger than the last-level cache).
    for (int i = 0; i < C * nxp; i += 16) __builtin_prefetch(centres + i, 0, 0);
    uint8_t* o = dst + r * nx;
    for (int x = 0; x < nx; ++x) {
      int seen = 0;
      bool in = true;
      for (int c = 0; c < C; ++c) {
        const uint8_t k = codes[c][PackedUV::pixelIndex(centres[c * nxp + x], widths[c])];
        if (k == 0) {
          in = false;
          break;
        }
        seen += k == 1;
      }
      o[x] = (in && seen >= min_views) ? 255 : 0;
    }
  });
}

}  // namespace psfs
