// Binary shape from silhouette: the baseline pSfS is compared with (thesis 7.3, DESIGN.md 6).
// Silhouettes are the likelihood images thresholded at one value for all views; a voxel is in
// the hull iff its centre projects into the silhouette in every view that observes it (AND over
// views, early exit at the first miss), using the same per-rig pixel lookup table (the
// ProjectionTable) and the same rules as pSfS for unobserved voxels and switched-off pixels:
// no evidence, and at least `min_views` observing cameras.
#pragma once

#include <cstdint>
#include <vector>

#include "psfs_reconstruction/probability_volume.h"
#include "psfs_reconstruction/projection_table.h"
#include "psfs_reconstruction/view_evidence.h"

namespace psfs {

struct BinarySfsOptions {
  double threshold = 0.5;  // silhouette pixel iff likelihood > threshold (in [0, 1))
  int min_views = 2;
  int threads = 0;         // OpenMP threads (0 = OpenMP default)
};

class BinarySfs {
 public:
  explicit BinarySfs(const BinarySfsOptions& options = BinarySfsOptions());
  const BinarySfsOptions& options() const { return options_; }

  // Per frame: thresholds the views into silhouettes (the image half of the algorithm).
  void setSilhouettes(const ViewEvidence& evidence);
  // The volume half: 255 in the hull, 0 outside. Throws std::invalid_argument if the
  // silhouettes do not match the table's cameras.
  void carve(const ProjectionTable& table, ProbabilityVolume* out) const;
  // Both in one call.
  void fuse(const ProjectionTable& table, const ViewEvidence& evidence, ProbabilityVolume* out) {
    setSilhouettes(evidence);
    carve(table, out);
  }

 private:
  struct Silhouette {
    int width = 0, height = 0;
    std::vector<uint8_t> code;  // 0 background, 1 silhouette, 2 no evidence (+ guard)
  };
  BinarySfsOptions options_;
  std::vector<Silhouette> silhouettes_;
};

}  // namespace psfs
