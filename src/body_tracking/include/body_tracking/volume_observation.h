// The PAPF's observation (thesis 5.2.3, DESIGN.md section 4): for each body part, the mean
// voxel likelihood inside its truncated quadric, each voxel weighted by 1 + v^T Q v (largest
// near the surface, which gives the sharpest maximum), summed over the parts so that each part
// counts the same whatever its volume. The likelihood is the body (general foreground) volume;
// for the mostly-skin parts (head, hands) it is blended with the skin volume. The grid covers
// the workspace only, and the seated person's trunk crosses its back face and the desk plane:
// there the trunk's voxels read the nearest grid voxel (clamp to edge), i.e. a trunk that
// crosses a face of the grid is taken to go on straight beyond it. A fixed value there would
// pull the trunk into the grid (the trunk rose 1-2 cm that way) or push it out. Head and limbs
// belong inside the workspace: their voxels outside it read `unknown_likelihood`, low enough
// that an arm does not leave the grid to escape the evidence (extrapolated, an arm behind the
// back face would read the trunk's section there as its own).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "body_tracking/body_parts.h"
#include "psfs_reconstruction/probability_volume.h"

namespace body_tracking {

struct ObservationParams {
  // Average the volumes over blocks of downsample^3 voxels first (2: the 64x64x48 pipeline
  // volume becomes the thesis' 32x32x24 at ~31 mm). 1 keeps the input resolution.
  int downsample = 2;
  double skin_weight = 0.5;         // head and hands: (1 - k) body + k skin
  double unknown_likelihood = 0.3;  // head and limb voxels outside the grid
  // The trunk parts' shell (part_score.h): each trunk cylinder's score is less
  // trunk_shell_weight times the mean likelihood between it and the cylinder grown sideways by
  // trunk_shell_width (m), rows beyond the grid read like the trunk's own (nearest grid row).
  // The mean inside alone is ~0.9 for any trunk sunk in the blob of
  // trunk, arms and halo, and the trunk wandered in it (test_papf_sim: yaw 5 deg, bend 8 deg,
  // 13 mm forward, which put the shoulders 3 cm off and the arms with them); an empty shell
  // holds it to the real boundary. 0 = the thesis' observation.
  double trunk_shell_width = 0.03;
  double trunk_shell_weight = 0.5;
};

class VolumeObservation {
 public:
  explicit VolumeObservation(const ObservationParams& params = ObservationParams());
  const ObservationParams& params() const { return params_; }

  // Takes this frame's volumes (skin may be null: then the body volume alone). The grids must
  // match; throws std::invalid_argument otherwise.
  // threads: OpenMP threads for the downsampling (the result does not depend on it).
  void setVolumes(const psfs::ProbabilityVolume& body, const psfs::ProbabilityVolume* skin,
                  int threads = 1);
  bool ready() const { return !body_.empty(); }
  const psfs::VoxelGrid& grid() const { return grid_; }

  // Sum over parts of the weighted mean likelihood (the trunk parts less their shell's term), in
  // [-2 trunk_shell_weight, kNumParts]. per_part (optional) receives each part's score.
  double score(const BodyParts& parts, std::array<double, kNumParts>* per_part = nullptr) const;
  double partScore(const TruncatedQuadric& part, bool skin_part, bool extrapolate) const;
  // The part's weighted mean likelihood alone, without the trunk's shell term: how much of the
  // part the volume fills (what judges a lost track; the shell's halo term varies with the
  // volume's quality).
  double partMean(const TruncatedQuadric& part, bool skin_part, bool extrapolate) const;

  // Number of voxels above p = 0.5 in the (downsampled) body volume, and their bounds.
  int occupiedVoxels() const { return occupied_; }
  // Likelihoods at the working resolution, x fastest (for the initialisation).
  const std::vector<float>& bodyLikelihood() const { return body_; }
  const std::vector<float>& skinLikelihood() const { return skin_; }

  // Per row (fixed y, z) prefix sums of y, x y and x^2 y (x = voxel index): the part's voxels
  // in a row form one interval, and its weight 1 + v^T Q v is quadratic in x, so a row's
  // weighted sum is three lookups. Each particle then costs O(rows), not O(voxels).
  struct RowSums {
    std::vector<double> s0, s1, s2;  // (dims.x + 1) entries per row, row y + dims.y * z
  };
  // The sums the parts read: the blended likelihood's for the skin parts, else the body's (what
  // the GPU particle weights upload each frame).
  const RowSums& rowSums(bool skin_part) const { return skin_part ? blended_sums_ : body_sums_; }

 private:
  static void buildRowSums(const psfs::VoxelGrid& g, const std::vector<float>& y, int threads,
                           RowSums* out);

  ObservationParams params_;
  psfs::VoxelGrid grid_;
  std::vector<float> body_, skin_, blended_;  // blended_: the skin parts' likelihood
  RowSums body_sums_, blended_sums_;
  int occupied_ = 0;
};

}  // namespace body_tracking
