#include "psfs_reconstruction/all_classes_fusion.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include "cpu_dispatch.h"
#include "fusion_common.h"
#include "psfs_kernels.h"

namespace psfs {

AllClassesFusion::AllClassesFusion(const AllClassesOptions& o) : options_(o) {
  auto prob = [](double p, const char* name) {
    if (!std::isfinite(p) || p < 0.0 || !(p < 1.0))
      throw std::invalid_argument(std::string("psfs::AllClassesOptions: ") + name + " must be in [0, 1)");
  };
  prob(o.hull_prior, "hull_prior");
  prob(o.view_prior, "view_prior");
  prob(o.threshold, "threshold");
  if (o.occluded_views < 0) throw std::invalid_argument("psfs::AllClassesOptions: occluded_views < 0");
  if (o.min_views < 1) throw std::invalid_argument("psfs::AllClassesOptions: min_views must be >= 1");
  if (o.threads < 0) throw std::invalid_argument("psfs::AllClassesOptions: threads must be >= 0");
}

void AllClassesFusion::fuse(const ProjectionTable& table, const ViewEvidence& evidence,
                            ProbabilityVolume* out) const {
  if (!out) throw std::invalid_argument("psfs::AllClassesFusion::fuse: null output");
  detail::checkInputs(table, evidence, options_.multi_projection, "psfs::AllClassesFusion::fuse");
  detail::checkFootprint(table, evidence, false, "psfs::AllClassesFusion::fuse");
  const int C = table.numCameras();
  if (C > 16) throw std::invalid_argument("psfs::AllClassesFusion::fuse: more than 16 cameras");
  const std::vector<detail::KernelView> views = detail::kernelViews(evidence);
  // Per-view priors: p = share of the hull prior (phi in P(G_n)), q = the images' prior.
  double p = 0.0, q = 0.0;
  if (options_.hull_prior > 0.0) p = std::pow(options_.hull_prior, 1.0 / C);
  q = options_.view_prior > 0.0 ? options_.view_prior : p;
  if (p == 0.0) p = q;
  const bool priors = p > 0.0 && q > 0.0;
  const double lphi = priors ? std::log(p) - std::log(q) : 0.0;
  const double lbeta = priors ? std::log(1.0 - p) - std::log(1.0 - q) : 0.0;

  out->grid = table.grid();
  out->data.assign(table.grid().numVoxels(), 0);
  const int nx = table.grid().dims.x(), nxp = table.paddedRowLength();
  const int k = options_.occluded_views;
  // One row; pairs = the multi-projection median pairs of the row ([c * nxp + x]) or nullptr.
  auto fuseRow = [&](size_t r, const uint32_t* centres, const int32_t* pairs) {
    thread_local std::vector<double> sphi, sbeta, scores;
    sphi.resize(C);
    sbeta.resize(C);
    for (int x = 0; x < nx; ++x) {
      int A = 0;  // observing views
      for (int c = 0; c < C; ++c) {
        int b = detail::observeByte(views[c], evidence.likelihood(c), centres[c * nxp + x]);
        if (b >= 0 && pairs) b = detail::medianPairByte(pairs[size_t(c) * nxp + x]);
        if (b < 0) continue;
        // Same reading of a byte as the log terms: 0 is half a step; 255 likewise from above.
        const double P = b == 0 ? 0.5 / 255.0 : (b == 255 ? 254.5 / 255.0 : b / 255.0);
        sphi[A] = std::log(P) + lphi;
        sbeta[A] = std::log(1.0 - P) + lbeta;
        ++A;
      }
      if (A < options_.min_views) continue;
      // Enumerate all 2^A super classes; bit c set = camera c sees beta.
      double best = -std::numeric_limits<double>::infinity();
      int best_mask = 0;
      double all_max = -std::numeric_limits<double>::infinity();
      scores.resize(size_t(1) << A);
      for (uint32_t m = 0; m < (1u << A); ++m) {
        double s = 0.0;
        for (int c = 0; c < A; ++c) s += (m >> c & 1u) ? sbeta[c] : sphi[c];
        scores[m] = s;
        if (s > best) best = s, best_mask = static_cast<int>(m);
        all_max = std::max(all_max, s);
      }
      bool in = __builtin_popcount(static_cast<unsigned>(best_mask)) <= k;
      if (in && options_.threshold > 0.0) {
        double hull = 0.0, all = 0.0;  // log-sum-exp
        for (uint32_t m = 0; m < (1u << A); ++m) {
          all += std::exp(scores[m] - all_max);
          if (__builtin_popcount(m) <= k) hull += std::exp(scores[m] - all_max);
        }
        const double log_post = std::log(hull) - std::log(all);
        in = log_post / A > std::log(options_.threshold);
      }
      if (in) out->data[r * nx + x] = 255;
    }
  };
  if (options_.multi_projection) {
    detail::forEachFaceRow(table, views, options_.threads,
                           [&](size_t r, const uint32_t* centres, const uint32_t* offsets,
                               uint16_t* yface, uint16_t* zface) {
                             thread_local std::vector<int32_t> pairs;
                             pairs.resize(size_t(C) * nxp);
                             detail::medianPairsOfRow(views.data(), C, nxp, centres, offsets,
                                                      yface, zface, pairs.data());
                             fuseRow(r, centres, pairs.data());
                           });
    return;
  }
  detail::forEachRow(table, options_.threads, 4,
                     [&](size_t r, const uint32_t* centres) { fuseRow(r, centres, nullptr); });
}

}  // namespace psfs
