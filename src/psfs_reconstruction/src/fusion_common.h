// Private: input checks and kernel views shared by the fusion variants.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include "psfs_kernels.h"
#include "psfs_reconstruction/projection_table.h"
#include "psfs_reconstruction/view_evidence.h"

namespace psfs {
namespace detail {

// Throws std::invalid_argument (prefixed with `who`) unless the evidence fits the table.
inline void checkInputs(const ProjectionTable& table, const ViewEvidence& evidence, bool multi,
                        const std::string& who) {
  if (table.numCameras() == 0) throw std::invalid_argument(who + ": empty projection table");
  if (evidence.numViews() != table.numCameras())
    throw std::invalid_argument(who + ": " + std::to_string(evidence.numViews()) +
                                " views for " + std::to_string(table.numCameras()) + " cameras");
  for (int c = 0; c < table.numCameras(); ++c)
    if (evidence.width(c) != table.camera(c).width || evidence.height(c) != table.camera(c).height)
      throw std::invalid_argument(who + ": view " + std::to_string(c) + " is " +
                                  std::to_string(evidence.width(c)) + "x" +
                                  std::to_string(evidence.height(c)) + " but camera '" +
                                  table.camera(c).name + "' is " +
                                  std::to_string(table.camera(c).width) + "x" +
                                  std::to_string(table.camera(c).height));
  if (multi && !table.multiProjection())
    throw std::invalid_argument(who + ": multi-projection needs a table built with multi_projection");
  if (multi && !evidence.bilinear())
    throw std::invalid_argument(who + ": multi-projection needs evidence set with bilinear = true");
}

inline std::vector<KernelView> kernelViews(const ViewEvidence& e) {
  std::vector<KernelView> v(e.numViews());
  for (int c = 0; c < e.numViews(); ++c)
    v[c] = KernelView{e.terms(c), e.bilinear() ? e.pairs(c) : nullptr, e.width(c), e.quadStride(c),
                      e.hasInactivePixels(c), PackedUV::notObserved(e.height(c))};
  return v;
}

}  // namespace detail
}  // namespace psfs
