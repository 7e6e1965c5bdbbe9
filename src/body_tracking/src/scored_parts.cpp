#include "scored_parts.h"

#include "body_tracking/part_collision.h"
#include "part_score.h"

namespace body_tracking {

const PartitionSpec kPartitionSpecs[kPapfPartitions] = {
    {dof::TORSO_X, 8, {Part::ABDOMEN, Part::CHEST, Part::HEAD}},
    {dof::L_SWING_1, 5, {Part::LEFT_UPPER_ARM, Part::LEFT_FOREARM, Part::LEFT_HAND}},
    {dof::R_SWING_1, 5, {Part::RIGHT_UPPER_ARM, Part::RIGHT_FOREARM, Part::RIGHT_HAND}}};

int scoredParts(int partition, Part out[kNumParts]) {
  if (partition < 0) {
    for (int k = 0; k < kNumParts; ++k) out[k] = static_cast<Part>(k);
    return kNumParts;
  }
  const PartitionSpec& ps = kPartitionSpecs[partition];
  for (int k = 0; k < 3; ++k) out[k] = ps.parts[k];
  return 3;
}

bool buildScoredParts(const BodyProfile& profile, const BodyState& s, int partition, BodyParts* parts) {
  const BodyFrames f = forwardKinematics(profile, s);
  if (partition < 0) {
    *parts = buildParts(profile, f);
    return bodyCollides(profile, f, *parts);
  }
  for (Part p : kPartitionSpecs[partition].parts) (*parts)[static_cast<int>(p)] = buildPart(profile, f, p);
  if (partition == 0) return false;
  for (Part p : {Part::ABDOMEN, Part::CHEST, Part::HEAD})
    (*parts)[static_cast<int>(p)] = buildPart(profile, f, p);
  return bodyCollides(profile, f, *parts);
}

double scorePartition(const VolumeObservation& obs, const BodyProfile& profile, const BodyState& s,
                      int partition) {
  BodyParts parts;
  const bool collides = buildScoredParts(profile, s, partition, &parts);
  Part scored[kNumParts];
  const int n = scoredParts(partition, scored);
  double part_scores[kNumParts];
  for (int k = 0; k < n && !collides; ++k)
    part_scores[k] = obs.partScore(parts[static_cast<int>(scored[k])], isSkinPart(scored[k]),
                                   isTrunkPart(scored[k]));
  return part_score::particleScore(part_scores, n, collides);
}

}  // namespace body_tracking
