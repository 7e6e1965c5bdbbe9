// The MPF's spatial reclustering (thesis 5.1.2): a k-means analysis (k <= 3) whose means carry a
// target type. Points are assigned to the nearest mean whatever their type; a mean moves to the
// weighted centre of the assigned points of ITS type only, so points that settle on a mean of a
// foreign type can be found afterwards (and deactivated by the tracker). Seeded with the
// mixture components' modes it usually stops after one iteration; max_iterations is the hard
// limit the thesis sets (50), after which the last assignment stands.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "hand_tracking/target.h"

namespace hand_tracking {

struct ClusterPoint {
  Eigen::Vector3f position = Eigen::Vector3f::Zero();
  float weight = 0.f;  // >= 0; weight of the point in its mean's update
  Target::Type type = Target::kHand;
  bool active = false;  // inactive points are not assigned (assignment -1)
};

struct ClusterMean {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Target::Type type = Target::kHand;
};

struct KMeansResult {
  int iterations = 0;      // assignment passes run
  bool converged = false;  // the last pass changed no assignment
};

// Assigns every active point to its nearest mean (ties: lowest index) and iterates. With no
// means every assignment is -1. A mean that receives no weight of its type stays where it is.
KMeansResult typedKMeans(const std::vector<ClusterPoint>& points, std::vector<ClusterMean>* means,
                         int max_iterations, std::vector<int>* assignment);

}  // namespace hand_tracking
