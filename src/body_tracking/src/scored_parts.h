// Private: which parts score which PAPF partition, and a particle's parts built for scoring, as
// Papf::scoreState and the GPU particle weights (gpu_particle_weights.h) both need them.
#pragma once

#include <array>

#include "body_tracking/body_parts.h"
#include "body_tracking/volume_observation.h"

namespace body_tracking {

constexpr int kPapfPartitions = 3;

// A partition: its first state index, its size, and the parts that score it.
// The most state coordinates one partition holds (the trunk's 8: torso, spine, head).
constexpr int kMaxPartitionDims = 8;

struct PartitionSpec {
  int first, count;  // state coordinates [first, first + count), count <= kMaxPartitionDims
  std::array<Part, 3> parts;
};
extern const PartitionSpec kPartitionSpecs[kPapfPartitions];

// The parts whose scores sum to a particle's score for `partition` (< 0: all nine, in Part
// order): their number, written to out[0..n).
int scoredParts(int partition, Part out[kNumParts]);

// Builds the parts of state `s` that scoring `partition` reads (and for an arm partition, or
// all parts, those its self-collision test needs) into *parts. Returns true when the pose
// self-collides (part_collision.h), which scores 0: an arm's pose is checked against the trunk
// and the other arm as they stand; the trunk chain cannot collide with itself.
bool buildScoredParts(const BodyProfile& profile, const BodyState& s, int partition, BodyParts* parts);

// A state's score for `partition` (< 0: all parts) as the filter weighs it: its parts' scores
// summed, 0 for a self-colliding pose (Papf::scoreState, arm_length.h).
double scorePartition(const VolumeObservation& obs, const BodyProfile& profile, const BodyState& s,
                      int partition);

}  // namespace body_tracking
