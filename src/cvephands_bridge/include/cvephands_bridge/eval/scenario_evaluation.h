// One scenario of the simulated rig through the whole per-frame pipeline, scored against its
// ground truth (issue 15, the scenario suite; DESIGN.md sections 5 and 6): in one process and
// deterministic (same options, same figures), as hand_tracking's track_eval does it:
//
//   render -> psfs::Reconstructor -> hand_tracking::MpfTracker -> two TrackingEvaluators
//                    |                                        (visible skin / palm + fingers)
//                    +-> body and skin volumes vs the occupancy oracle on the same grid
//                    +-> (every mesh_every-th person frame) hand sub-volumes around the TRUE
//                        hands -> marching cubes -> mesh vs the true skin surface
//                    +-> (options.body) body_tracking::Papf on the same body and skin volumes
//                        -> hands, head, elbows, shoulders vs the truth (issue 16 item 4)
//
// Frames: the rig's first empty frame sets go into the background model (as many as the pSfS
// configuration learns from, BackgroundModelParams::learning_frames, 25; no volumes yet); then
// `empty_frames` more empty sets are reconstructed and tracked: the "empty scene", where any
// active target is a false target; then `frames` sets with the person.
//
// Volumes: a voxel is "in" when its byte > psfs::thresholdByte(occupancy_threshold) (0.5: byte
// >= 128, i.e. p >= 0.5 on the byte scale; the fusion's own in-hull test is p > 0.75), the truth at
// the voxel centre (Oracle::sampleGrid); IoU is psfs::volumeIoU, precision = |rec & truth| /
// |rec|, recall = |rec & truth| / |truth|, per person frame.
// Hands: the MPF's hand target is the centroid of the hand's visible skin (DESIGN.md section 5,
// GroundTruth::*_hand_skin); the same tracked points are also scored against the palm + fingers
// centroid (the body model's hand) for comparison. Head: the head ellipsoid's centre, absolute
// and with the mean offset removed (TargetReport::alignedErrorMeanMm, the thesis' protocol).
// Meshes: the hand sub-volumes are centred on the true hands (palm + fingers centroid), as in
// hand_mesh_evaluation.h: this scores reconstruction + meshing, not tracking. Asking for the
// sub-volumes changes nothing else (the workspace volumes, the background update and so the
// tracking are the same whatever mesh_every is).
// Upper body (PAPF): run on every reconstructed set (empty ones too: a track there is a false
// start), seeded with `seed`, scored as body_tracking's test_papf_sim scores it: on the person
// frames where the PAPF reports a pose, hands = the estimate's (refined) hands against the palm +
// fingers centroid (GroundTruth::left_hand / right_hand), head = head_centre against the head
// ellipsoid's centre, elbows and shoulders against GroundTruth::elbow / shoulder, both sides
// pooled, Euclidean, mm; and the arms' joint angles (armAngleErrors: upper-arm and forearm
// directions, elbow flexion, degrees) against the truth's shoulders, elbows and wrists. A hand
// or the head is scored where it is in the workspace, the joints where the truth is finite.
// Timings are recorded for information only; nothing here or in the suite judges speed.
//
// Part of cvephands_eval (simulator, reconstruction, tracker and meshing cores; no ROS).
#pragma once

#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "cvephands_bridge/eval/hand_mesh_evaluation.h"
#include "tabletop_common/running_stats.h"
#include "tabletop_sim/tracking_evaluator.h"

namespace cvephands {

struct ScenarioEvalOptions {
  // tabletop_sim::SimOptions::scenario, passed through as it is: "default", a preset name or
  // "random-<seed>". A name the simulator does not know makes evaluateScenario throw
  // std::invalid_argument (the simulator's message).
  std::string scenario = "default";
  std::string script = "all";  // motion script (tabletop_sim::MotionScript::names())
  int empty_frames = 10;       // empty sets after those, reconstructed and tracked (false targets)
  int frames = 0;              // person sets after the empty ones (0 = the whole script)
  uint64_t seed = 1;           // sensor noise of the rig and the tracker's random generator
  int mesh_every = 10;         // score the hand meshes on every n-th person set (0 = off)
  double occupancy_threshold = 0.5;  // p at and above which a voxel counts as occupied (IoU)
  // The stage configurations: psfs_reconstruction/config/psfs.yaml and hand_tracking/config/
  // mpf.yaml style files ("" = the parameter structs' defaults, which the shipped files equal).
  std::string psfs_config, mpf_config;
  // The upper-body tracker: run it (default) or not, and its configuration (body_tracking/
  // config/papf.yaml style; "" = PapfParams' defaults and the default BodyProfile). Its seed is
  // always `seed` above (the file's seed is overridden), its threads the file's (default 2).
  bool body = true;
  std::string papf_config;
  // psfs_reconstruction/config/skin_gmm.yaml; "" = the skin model psfs_config names (then
  // psfs_config is required).
  std::string skin_model;
  // The meshing and mesh scoring fields (iso, spacing, border_voxels, min_component_triangles,
  // keep_radius; the seed is `seed` above). The hand cubes are the pSfS configuration's (hand_roi_edge,
  // hand_roi_voxels: 30 cm, 83^3 by default).
  HandMeshEvalOptions mesh;
  // The scenario's description for the report (e.g. tabletop_sim's Scenario::describe());
  // unset: describeScenario() below.
  std::function<std::string(const std::string& scenario)> describe;
  // Called after every frame set (progress output): frame sets done and in all.
  std::function<void(int done, int total)> progress;
};

// One scored frame set (empty-scene and person frames; the learning frames are not scored).
struct ScenarioFrame {
  int frame = 0;          // rig frame index (the learning frames included)
  double time = 0;        // s
  bool person = false;    // false: an empty-scene frame
  // Volumes vs the oracle (person frames; NaN in empty frames, where the truth is empty).
  double body_iou = 0, body_precision = 0, body_recall = 0;
  double skin_iou = 0, skin_precision = 0, skin_recall = 0;
  size_t body_voxels = 0, skin_voxels = 0;  // reconstructed voxels (at the threshold)
  int active_targets = 0;                   // tracker targets active after this frame
  double psfs_ms = 0, mpf_ms = 0;           // pSfS total (incl. hand sub-volumes), MPF update
  // The PAPF (ScenarioEvalOptions::body): whether it reports a pose after this frame, and its
  // errors in this frame (NaN where not tracked, not scored or the body is off; hands and the
  // joints: mean of both sides scored).
  bool body_tracking = false, body_started = false;
  double body_hand_mm = std::numeric_limits<double>::quiet_NaN(),
         body_head_mm = std::numeric_limits<double>::quiet_NaN(),
         body_elbow_mm = std::numeric_limits<double>::quiet_NaN(),
         body_shoulder_mm = std::numeric_limits<double>::quiet_NaN();
  // Arm angle errors (armAngleErrors, degrees), mean of both sides scored.
  double body_upper_arm_deg = std::numeric_limits<double>::quiet_NaN(),
         body_forearm_deg = std::numeric_limits<double>::quiet_NaN(),
         body_elbow_flex_deg = std::numeric_limits<double>::quiet_NaN();
  // The body volume the body tracker publishes (body/volume: the pSfS body volume with the
  // tracked model as a prior, body_tracking/model_prior.h; the pSfS volume itself where no
  // pose is tracked) vs the oracle, as body_iou; NaN in empty frames or with the body off.
  double body_volume_iou = std::numeric_limits<double>::quiet_NaN(),
         body_volume_precision = std::numeric_limits<double>::quiet_NaN(),
         body_volume_recall = std::numeric_limits<double>::quiet_NaN();
  double papf_ms = 0;
};

// The PAPF's figures over one scenario (see the header comment for what is scored).
// The joint-angle errors of one arm (degrees), from joint positions, so that any body model's
// parametrisation compares with the simulated person's: the upper arm's direction (shoulder ->
// elbow) and the forearm's (elbow -> wrist) against the truth's, and the elbow flexion (the
// angle between those two bones, 0 = straight) against the truth's. NaN where a joint of the
// truth is not finite or a bone has no length.
struct ArmAngleErrors {
  double upper_arm_deg, forearm_deg, elbow_flex_deg;
};
ArmAngleErrors armAngleErrors(const Eigen::Vector3d& shoulder, const Eigen::Vector3d& elbow,
                              const Eigen::Vector3d& wrist, const Eigen::Vector3d& true_shoulder,
                              const Eigen::Vector3d& true_elbow, const Eigen::Vector3d& true_wrist);

struct BodyTrackingFigures {
  bool ran = false;          // ScenarioEvalOptions::body was on
  int person_frames = 0;     // scored frames with the person present
  int tracked_frames = 0;    // ... of which the PAPF reported a pose
  int starts = 0;            // frames that (re)started the track (empty frames included)
  int losses = 0;            // tracked -> not tracked while the person is present
  int empty_tracked_frames = 0;  // empty-scene frames with a pose reported (false starts)
  // Per-sample errors (mm): hands and joints both sides pooled.
  tabletop_common::RunningStats hand_mm, head_mm, elbow_mm, shoulder_mm;
  // Per-sample arm angle errors (degrees, armAngleErrors), both sides pooled.
  tabletop_common::RunningStats upper_arm_deg, forearm_deg, elbow_flex_deg;
  tabletop_common::RunningStats papf_ms;  // per update, all scored frames
  // ScenarioFrame::body_volume_* over the person frames.
  tabletop_common::RunningStats volume_iou, volume_precision, volume_recall;

  // Person frames without a pose reported (the track not started yet, or lost).
  int untrackedFrames() const { return person_frames - tracked_frames; }
  int restarts() const { return starts > 0 ? starts - 1 : 0; }
  double trackedFraction() const;  // NaN without person frames
  // Mean error of one of hand_mm, head_mm, ..., upper_arm_deg, ...: NaN when not run or no person frame; +inf when
  // the person was there for a second or more and nothing was ever scored (never tracked).
  double meanError(const tabletop_common::RunningStats& s) const;
};

struct ScenarioEvalResult {
  std::string scenario, script, description;
  uint64_t seed = 0;
  double occupancy_threshold = 0.5;
  std::string grid;  // the workspace volumes' grid (VoxelGrid::describe())
  std::vector<ScenarioFrame> frames;  // the per-frame series (plots)
  int empty_frames = 0, person_frames = 0;
  // Over the person frames.
  tabletop_common::RunningStats body_iou, skin_iou, body_precision, body_recall, skin_precision,
      skin_recall;
  // Largest reconstructed body volume (voxels) in an empty-scene frame.
  size_t empty_max_body_voxels = 0;
  // The same tracked points against the two hand definitions (the head is the same truth in
  // both). tracking_skin is the one the MPF is judged by (losses, switches, false targets).
  tabletop_sim::TrackingEvaluator tracking_skin, tracking_palm;
  int false_target_frames_empty = 0;   // empty-scene frames with an active target
  int false_target_frames_person = 0;  // person frames with a target near no true target
  // Probabilistic hand meshes (HandMeshSample::probabilistic per scored hand).
  std::vector<HandMeshSample> meshes;
  tabletop_common::RunningStats mesh_to_truth_mm, truth_to_mesh_mm;  // per-hand means
  tabletop_common::RunningStats psfs_ms, mpf_ms, mesh_score_ms;
  BodyTrackingFigures body;  // the PAPF (body.ran false when ScenarioEvalOptions::body is off)
  double wall_s = 0;

  // Both hands pooled (frames where each is visible and tracked), against one definition:
  // 0 visible skin, 1 palm + fingers. NaN when no hand was ever visible; +inf when one was
  // visible but never tracked (a failure, sorted worst by the suite).
  double handErrorMeanMm(int definition) const;
  double handErrorMaxMm(int definition) const;
  double headErrorMeanMm() const;         // NaN / +inf as above
  double headErrorMaxMm() const;
  double headAlignedErrorMeanMm() const;  // NaN / +inf as above
  int losses() const;                     // all three targets (tracking_skin)
  int identitySwitches() const;
  double trackedFraction() const;  // tracked / visible frames, all three targets (NaN if none)
  std::string summary() const;     // a few lines for the console (bodySummary() included)
  std::string bodySummary() const;  // the PAPF's line ("  PAPF: off" when it did not run)
};

// Throws std::invalid_argument for bad options or a scenario/script the simulator rejects,
// std::runtime_error for an unreadable configuration or skin model.
ScenarioEvalResult evaluateScenario(const ScenarioEvalOptions& options);

// The description of a scenario when no ScenarioEvalOptions::describe is given.
std::string describeScenario(const std::string& scenario);

}  // namespace cvephands
