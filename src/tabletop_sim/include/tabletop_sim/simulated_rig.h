// The simulated rig as one object: cameras (the default ring or any rig), the office scene, a
// scripted seated person, the renderer and the ground truth. What the ROS nodelet and the bag
// writer use; everything is a pure function of (options, frame index).
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "tabletop_capture/rig_description.h"
#include "tabletop_sim/body_model.h"
#include "tabletop_sim/motion_script.h"
#include "tabletop_sim/oracle.h"
#include "tabletop_sim/renderer.h"
#include "tabletop_sim/scenario.h"
#include "tabletop_sim/scene.h"

namespace tabletop_sim {

struct SimOptions {
  // The world and sensors: "default" (the office, person and 8-camera ring of DESIGN.md), a
  // preset name, or "random-<seed>" (scenario.h). Any other than "default" replaces the
  // camera count and size, noise_sigma and short_sleeves below; script, fps, empty_frames,
  // seed, bayer, threads and masks still apply. A rig given to the constructor keeps its
  // cameras.
  std::string scenario = "default";
  // Default rig only (ignored when a rig is given): camera count 1..16, image size >= 16.
  int num_cameras = 8, width = 320, height = 240;
  bool distortion = true;
  double fps = 25;             // frame i is at time i / fps
  std::string script = "all";  // see MotionScript::names()
  int empty_frames = 25;       // frames without the person at the start (background learning)
  uint64_t seed = 1;           // sensor noise
  double noise_sigma = 2.0;    // grey levels
  std::string bayer = "none";  // or bayer_rggb8, bayer_bggr8, bayer_gbrg8, bayer_grbg8
  bool short_sleeves = false;
  bool shadows = true;
  int threads = 0;            // 0 = OpenMP default
  bool render_masks = false;  // also fill SimFrame::person_masks / skin_masks
  // Workspace box for the *_in_workspace flags (DESIGN.md section 3 default).
  Eigen::Vector3d workspace_min = Eigen::Vector3d(-0.5, -0.5, 0.0);
  Eigen::Vector3d workspace_size = Eigen::Vector3d(1.0, 1.0, 0.75);
};

struct GroundTruth {
  bool person_present = false;
  // Hand centroids (palm + fingers, the body model's hand) and head centre (world, m;
  // definitions in body_model.h). NaN when no person is present.
  Eigen::Vector3d left_hand, right_hand, head;
  // The MPF's hand target (DESIGN.md section 5): the centroid of the hand's VISIBLE skin, the
  // palm and finger solid not covered by a sleeve or cuff. NaN when none of it is visible.
  Eigen::Vector3d left_hand_skin, right_hand_skin;
  bool left_hand_in_workspace = false, right_hand_in_workspace = false, head_in_workspace = false;
  std::array<double, 18> body_state{};  // tabletop_msgs/BodyPose.state order; NaN if absent
  // Joints implied by body_state (body_model.h), by Side; NaN if absent.
  std::array<Eigen::Vector3d, 2> shoulder, elbow, wrist;
  std::array<HandShape, 2> hand_shapes{{HandShape::OPEN, HandShape::OPEN}};  // by Side
};

struct SimFrame {
  int index = 0;
  double time = 0;                    // index / fps (s)
  std::vector<cv::Mat> images;        // rgb8 (CV_8UC3), or CV_8UC1 mosaic if bayer != "none"
  std::vector<cv::Mat> person_masks;  // CV_8UC1, 255 = person (if render_masks)
  std::vector<cv::Mat> skin_masks;    // CV_8UC1, 255 = visible skin (if render_masks)
  GroundTruth truth;
};

class SimulatedRig {
 public:
  // Throws std::invalid_argument with a clear message for invalid options.
  explicit SimulatedRig(const SimOptions& options);  // uses tabletop_capture::makeDefaultRig
  SimulatedRig(const SimOptions& options, const tabletop_capture::RigDescription& rig);
  ~SimulatedRig();

  const tabletop_capture::RigDescription& rig() const { return rig_; }
  const SimOptions& options() const { return options_; }
  const BodyModel& body() const { return body_; }
  const MotionScript& script() const { return *script_; }
  const Renderer& renderer() const { return *renderer_; }
  const std::shared_ptr<const Scene>& scene() const { return scene_; }
  const Scenario& scenario() const { return scenario_; }

  // Frames in one pass: empty frames + the script's frames. Later frames loop the script
  // (the empty frames are not repeated).
  int scriptFrames() const { return options_.empty_frames + person_frames_; }
  // Script time of a frame (s), or a negative value for an empty frame.
  double scriptTime(int frame) const;
  bool personPresent(int frame) const { return scriptTime(frame) >= 0.0; }
  BodyPose pose(int frame) const;                  // requires personPresent(frame)
  std::vector<Primitive> person(int frame) const;  // empty for an empty frame

  GroundTruth truth(int frame) const;  // cheap, no rendering
  Oracle oracle(int frame) const;
  SimFrame render(int frame) const;  // thread-safe to call from one thread at a time

 private:
  void init();
  SimOptions options_;
  bool rig_given_ = false;
  Scenario scenario_;
  tabletop_capture::RigDescription rig_;
  BodyModel body_;
  std::unique_ptr<MotionScript> script_;
  std::shared_ptr<const Scene> scene_;
  std::unique_ptr<Renderer> renderer_;
  int person_frames_ = 0;
};

}  // namespace tabletop_sim
