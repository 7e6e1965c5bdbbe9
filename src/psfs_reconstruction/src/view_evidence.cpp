#include "psfs_reconstruction/view_evidence.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>

#include "cpu_dispatch.h"
#include "footprint_filter.h"
#include "pixel_arithmetic.h"
#include "psfs_reconstruction/projection_table.h"

namespace psfs {
namespace {

// The GPU pixel stage writes the same arrays through pixel_arithmetic.h.
static_assert(ViewEvidence::kNoEvidence == pixel::kNoEvidenceTerm, "no-evidence term");
static_assert(ViewEvidence::kQuadPad == pixel::kPairPad, "pair border");

const std::array<int16_t, 256>& termTable() {
  static const std::array<int16_t, 256> table = [] {
    std::array<int16_t, 256> t{};
    for (int b = 0; b < 256; ++b)
      t[b] = static_cast<int16_t>(
          std::lround(ViewEvidence::kLogScale * std::log(b == 0 ? 0.5 / 255.0 : b / 255.0)));
    return t;
  }();
  return table;
}

[[noreturn]] void badView(size_t i, const std::string& why) {
  throw std::invalid_argument("psfs::ViewEvidence: view " + std::to_string(i) + ": " + why);
}

}  // namespace

int16_t ViewEvidence::logTerm(int byte) { return termTable()[std::clamp(byte, 0, 255)]; }

void ViewEvidence::set(const std::vector<ViewImage>& views, bool bilinear, int threads) {
  set(views, bilinear, threads, FootprintFilter());
}

void ViewEvidence::set(const std::vector<ViewImage>& views, bool bilinear, int threads,
                       const FootprintFilter& footprint) {
  if (views.empty()) throw std::invalid_argument("psfs::ViewEvidence: no views");
  const int L = footprint.levels;
  if (L != 0 && (L < 2 || L > ProjectionTable::kMaxFootprintLevels))
    throw std::invalid_argument("psfs::ViewEvidence: footprint levels must be 0 or in 2.." +
                                std::to_string(ProjectionTable::kMaxFootprintLevels));
  if (threads < 0) throw std::invalid_argument("psfs::ViewEvidence: threads < 0");
  for (size_t i = 0; i < views.size(); ++i) {
    const ViewImage& v = views[i];
    if (v.likelihood.empty()) badView(i, "empty likelihood image");
    if (v.likelihood.depth() != CV_8U) badView(i, "likelihood image must be 8-bit (CV_8U)");
    if (v.channel < 0 || v.channel >= v.likelihood.channels())
      badView(i, "channel " + std::to_string(v.channel) + " out of range (image has " +
                     std::to_string(v.likelihood.channels()) + ")");
    if (v.likelihood.dims != 2 || v.likelihood.cols > PackedUV::kMaxImageSide ||
        v.likelihood.rows > PackedUV::kMaxImageSide)
      badView(i, "image must be 2-D with sides <= " + std::to_string(PackedUV::kMaxImageSide));
    if (!v.active.empty() && (v.active.type() != CV_8UC1 || v.active.size() != v.likelihood.size()))
      badView(i, "active mask must be CV_8UC1 of the likelihood image's size");
    if ((v.likelihood.rows + 1) * L > (0xFFFF >> PackedUV::kFracBits))
      badView(i, "image too high for " + std::to_string(L) + " footprint levels");
  }
  bilinear_ = bilinear;
  footprint_ = footprint;
  views_.resize(views.size());
  const auto& lut = termTable();
  const int n = static_cast<int>(views.size());
#pragma omp parallel for schedule(dynamic, 1) num_threads(resolveThreads(threads))
  for (int i = 0; i < n; ++i) {
    const ViewImage& in = views[i];
    View& out = views_[i];
    const int W = in.likelihood.cols, H = in.likelihood.rows, ch = in.likelihood.channels();
    out.width = W;
    out.height = H;
    const size_t np = size_t(W) * H;
    const size_t level_size = size_t(W) * (H + 1);  // a level and its guard row
    const int levels = std::max(L, 1);
    out.terms.resize(level_size * (levels - 1) + np + pixel::kTermGuard);
    out.likelihood.resize(np + 4);
    out.inactive_pixels = in.active.empty() ? 0 : np - static_cast<size_t>(cv::countNonZero(in.active));
    for (int v = 0; v < H; ++v) {
      const uint8_t* src = in.likelihood.ptr<uint8_t>(v) + in.channel;
      uint8_t* lk = &out.likelihood[size_t(v) * W];
      int16_t* tm = &out.terms[size_t(v) * W];
      if (ch == 1)
        std::memcpy(lk, src, size_t(W));
      else
        for (int u = 0; u < W; ++u) lk[u] = src[size_t(u) * ch];
      for (int u = 0; u < W; ++u) tm[u] = lut[lk[u]];
    }
    std::fill(out.likelihood.begin() + np, out.likelihood.end(), 0);
    // Footprint levels from the unmasked level 0, then the mask on every level.
    thread_local detail::FootprintScratch scratch;
    for (int l = 1; l < levels; ++l) {
      int16_t* dst = &out.terms[level_size * l];
      if (footprint.statistic == FootprintStatistic::kMedian)
        detail::medianFilterTerms(out.terms.data(), W, H, l, dst, &scratch);
      else
        detail::meanFilterTerms(out.likelihood.data(), W, H, l, lut.data(), dst, &scratch);
    }
    for (int l = 0; l < levels; ++l) {
      int16_t* level = &out.terms[level_size * l];
      if (!in.active.empty())
        for (int v = 0; v < H; ++v) {
          const uint8_t* act = in.active.ptr<uint8_t>(v);
          int16_t* tm = level + size_t(v) * W;
          for (int u = 0; u < W; ++u) tm[u] = pixel::maskedTerm(tm[u], act[u]);
        }
      // Guard row (the last level's guard is the plain layout's guard pixel plus 3 entries).
      std::fill(level + np, level + (l + 1 < levels ? level_size : np + pixel::kTermGuard),
                kNoEvidence);
    }
    if (!bilinear) {
      out.pairs.clear();
      continue;
    }
    // Pair (u, v) of the padded image holds L(u, v) and L(u, v + 1) with coordinates clamped to
    // the image (replicated border), u, v from -kQuadPad.
    const int QS = W + 2 * kQuadPad, QH = H + 2 * kQuadPad;
    out.pairs.resize(size_t(QS) * QH + pixel::kPairGuard);
    for (int vv = 0; vv < QH; ++vv) {
      const uint8_t* r0 = &out.likelihood[size_t(std::clamp(vv - kQuadPad, 0, H - 1)) * W];
      const uint8_t* r1 = &out.likelihood[size_t(std::clamp(vv - kQuadPad + 1, 0, H - 1)) * W];
      uint16_t* q = &out.pairs[size_t(vv) * QS];
      const uint16_t left = pixel::evidencePair(r0[0], r1[0]);
      const uint16_t right = pixel::evidencePair(r0[W - 1], r1[W - 1]);
      for (int uu = 0; uu < kQuadPad; ++uu) q[uu] = left, q[QS - 1 - uu] = right;
      uint16_t* qi = q + kQuadPad;
      for (int u = 0; u < W; ++u) qi[u] = pixel::evidencePair(r0[u], r1[u]);  // vectorised
    }
    out.pairs[size_t(QS) * QH] = out.pairs[size_t(QS) * QH + 1] = 0;
  }
}

}  // namespace psfs
