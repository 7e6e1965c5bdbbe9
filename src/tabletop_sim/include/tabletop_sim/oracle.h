// Ground-truth queries on one frame's person: occupancy (inside the person, inside visible
// skin), the hand and head centroids, and visibility from a camera. Built from the very
// primitives the renderer draws, so truth and pictures agree.
#pragma once

#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

#include <Eigen/Core>

#include "tabletop_capture/camera_model.h"
#include "tabletop_sim/body_model.h"
#include "tabletop_sim/primitives.h"
#include "tabletop_sim/scene.h"

namespace tabletop_sim {

class Oracle {
 public:
  // No person (empty frame): nothing is inside, centroids are NaN.
  Oracle() = default;
  // `head_centre` is the head ellipsoid's centre (BodyModel::headCentre); `scene` (may be
  // null) makes static objects count as occluders in occluded().
  Oracle(std::vector<Primitive> person, const Eigen::Vector3d& head_centre,
         std::shared_ptr<const Scene> scene);

  bool personPresent() const { return !person_.empty(); }
  const std::vector<Primitive>& primitives() const { return person_; }

  bool insidePerson(const Eigen::Vector3d& p) const;
  // Inside a skin primitive and inside no non-skin one (hair over the scalp, a sleeve over
  // the wrist): exactly the solid whose visible surface the renderer draws in skin colour.
  bool insideSkin(const Eigen::Vector3d& p) const;
  bool insidePart(const Eigen::Vector3d& p, BodyPart part) const;

  // insidePerson / insideSkin at the voxel centres of a regular grid: origin = min corner,
  // cubic voxels of voxel_size, dims voxels, index x fastest then y then z (the VoxelVolume
  // layout). Each output (null = not wanted) gets one byte per voxel, 1 = inside. Voxels
  // outside the person's bounding box are skipped, so a workspace grid costs a few ms.
  // OpenMP over z-slices with `threads` (<= 0: OpenMP default).
  void sampleGrid(const Eigen::Vector3d& origin, double voxel_size, const Eigen::Vector3i& dims,
                  std::vector<uint8_t>* person, std::vector<uint8_t>* skin, int threads = 0) const;

  Eigen::Vector3d handCentroid(Side side) const;  // see body_model.h for the definition
  Eigen::Vector3d headCentroid() const { return head_; }

  // True if, looking from `camera` towards p, the first surface before p (person or static
  // scene) is not part `part`. A point inside that part and seen through its own surface is
  // not occluded; a point nothing lies in front of is not occluded either.
  bool occluded(const tabletop_capture::CameraModel& camera, const Eigen::Vector3d& p, BodyPart part) const;

 private:
  std::vector<Primitive> person_;
  std::vector<Eigen::Vector4d> spheres_;  // bounding spheres (centre, radius^2) for culling
  Eigen::Vector3d head_ = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  std::shared_ptr<const Scene> scene_;
};

}  // namespace tabletop_sim
