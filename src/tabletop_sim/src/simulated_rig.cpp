#include "tabletop_sim/simulated_rig.h"

#include <cmath>
#include <limits>
#include <stdexcept>

#include "tabletop_capture/default_rig.h"

namespace tabletop_sim {

namespace {

[[noreturn]] void bad(const std::string& what) {
  throw std::invalid_argument("SimulatedRig: " + what);
}

void validate(const SimOptions& o) {
  if (!(o.fps > 0.0) || !std::isfinite(o.fps)) bad("fps must be a finite value > 0");
  if (o.empty_frames < 0) bad("empty_frames must be >= 0");
  if (!(o.noise_sigma >= 0.0) || !std::isfinite(o.noise_sigma))
    bad("noise_sigma must be a finite value >= 0");
  if (o.threads < 0) bad("threads must be >= 0 (0 = OpenMP default)");
  if (o.bayer != "none" && o.bayer != "bayer_rggb8" && o.bayer != "bayer_bggr8" &&
      o.bayer != "bayer_gbrg8" && o.bayer != "bayer_grbg8")
    bad("bayer must be none, bayer_rggb8, bayer_bggr8, bayer_gbrg8 or bayer_grbg8 (got '" +
        o.bayer + "')");
  if (!o.workspace_min.allFinite() || !o.workspace_size.allFinite() ||
      !(o.workspace_size.minCoeff() > 0.0))
    bad("workspace_size must be positive and finite");
}

tabletop_capture::RigDescription defaultRig(const SimOptions& o) {
  validate(o);
  if (o.num_cameras < 1 || o.num_cameras > 16) bad("num_cameras must be in 1..16");
  if (o.width < 16 || o.height < 16) bad("width and height must be at least 16 pixels");
  tabletop_capture::DefaultRigOptions r;
  r.num_cameras = o.num_cameras;
  r.width = o.width;
  r.height = o.height;
  r.distortion = o.distortion;
  return tabletop_capture::makeDefaultRig(r);
}

}  // namespace

SimulatedRig::SimulatedRig(const SimOptions& options)
    : options_(options), rig_(defaultRig(options)) {
  init();
}

SimulatedRig::SimulatedRig(const SimOptions& options, const tabletop_capture::RigDescription& rig)
    : options_(options), rig_given_(true), rig_(rig) {
  init();
}

SimulatedRig::~SimulatedRig() = default;

void SimulatedRig::init() {
  validate(options_);
  try {
    scenario_ = scenarioByName(options_.scenario);
  } catch (const std::invalid_argument& e) {
    bad(e.what());
  }
  const bool custom = options_.scenario != "default";
  if (custom && !rig_given_ && !scenario_.rig.cameras.empty()) rig_ = scenario_.rig;
  if (rig_.cameras.empty()) bad("the rig has no cameras");
  for (size_t i = 0; i < rig_.cameras.size(); ++i) {
    try {
      tabletop_capture::validateCamera(rig_.cameras[i], "SimulatedRig rig", static_cast<int>(i));
    } catch (const tabletop_capture::RigError& e) {
      bad(e.what());
    }
  }
  BodyOptions bo = scenario_.body;
  bo.short_sleeves = bo.short_sleeves || options_.short_sleeves;
  try {
    body_ = BodyModel(bo);
  } catch (const std::invalid_argument& e) {
    bad(e.what());
  }
  script_.reset(new MotionScript(MotionScript::create(options_.script, body_)));
  person_frames_ = std::max(1, static_cast<int>(std::ceil(script_->duration() * options_.fps)));
  Scene scene = Scene::office(scenario_.lighting.light);
  for (const SceneObject& o : scenario_.extra_objects) scene.add(o);
  scene_ = std::make_shared<const Scene>(std::move(scene));
  RenderOptions ro;
  ro.noise_sigma = custom ? scenario_.noise_sigma : options_.noise_sigma;
  ro.albedo = scenario_.albedo;
  ro.vignetting = scenario_.effects.vignetting;
  ro.seed = options_.seed;
  ro.shadows = options_.shadows;
  ro.threads = options_.threads;
  renderer_.reset(new Renderer(rig_, ro, *scene_));
}

double SimulatedRig::scriptTime(int frame) const {
  if (frame < 0) bad("frame index must be >= 0 (got " + std::to_string(frame) + ")");
  if (frame < options_.empty_frames) return -1.0;
  return ((frame - options_.empty_frames) % person_frames_) / options_.fps;
}

BodyPose SimulatedRig::pose(int frame) const {
  const double t = scriptTime(frame);
  if (t < 0.0) bad("frame " + std::to_string(frame) + " is an empty frame (no person)");
  return script_->poseAt(t);
}

std::vector<Primitive> SimulatedRig::person(int frame) const {
  if (!personPresent(frame)) return {};
  return body_.build(pose(frame));
}

GroundTruth SimulatedRig::truth(int frame) const {
  GroundTruth g;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  if (!personPresent(frame)) {
    g.left_hand = g.right_hand = g.head = Eigen::Vector3d::Constant(nan);
    g.left_hand_skin = g.right_hand_skin = g.left_hand;
    g.body_state.fill(nan);
    g.shoulder.fill(Eigen::Vector3d::Constant(nan));
    g.elbow = g.wrist = g.shoulder;
    return g;
  }
  const BodyPose p = pose(frame);
  const std::vector<Primitive> prims = body_.build(p);
  g.person_present = true;
  g.left_hand = handCentroid(prims, Side::LEFT);
  g.right_hand = handCentroid(prims, Side::RIGHT);
  g.left_hand_skin = visibleSkinCentroid(prims, Side::LEFT);
  g.right_hand_skin = visibleSkinCentroid(prims, Side::RIGHT);
  g.head = body_.headCentre(p);
  const Eigen::AlignedBox3d ws(options_.workspace_min,
                               options_.workspace_min + options_.workspace_size);
  g.left_hand_in_workspace = ws.contains(g.left_hand);
  g.right_hand_in_workspace = ws.contains(g.right_hand);
  g.head_in_workspace = ws.contains(g.head);
  for (int i = 0; i < 18; ++i) g.body_state[i] = p.state[i];
  const BodyFrames bf = body_.forward(p);
  g.shoulder = bf.shoulder;
  g.elbow = bf.elbow;
  g.wrist = bf.wrist;
  g.hand_shapes = {{p.hands[0].shape, p.hands[1].shape}};
  return g;
}

Oracle SimulatedRig::oracle(int frame) const {
  if (!personPresent(frame)) return Oracle();
  const BodyPose p = pose(frame);
  return Oracle(body_.build(p), body_.headCentre(p), scene_);
}

SimFrame SimulatedRig::render(int frame) const {
  SimFrame f;
  f.index = frame;
  f.time = frame / options_.fps;
  f.truth = truth(frame);
  RenderOutput out;
  // The light's and each camera's exposure gain at this frame (none in a constant scenario).
  const int n = static_cast<int>(rig_.cameras.size());
  std::vector<Eigen::Vector3f> gains(n);
  bool unit = true;
  const Eigen::Vector3d light = scenario_.lighting.gain(f.time);
  for (int c = 0; c < n; ++c) {
    gains[c] = (light.cwiseProduct(scenario_.effects.whiteBalance(c)) *
                scenario_.effects.exposureGain(c, f.time))
                   .cast<float>();
    unit = unit && gains[c] == Eigen::Vector3f::Ones();
  }
  renderer_->render(person(frame), static_cast<uint64_t>(frame), options_.render_masks, &out,
                    unit ? nullptr : &gains);
  if (scenario_.effects.postProcessing())
    for (cv::Mat& image : out.images) applyPostProcessing(scenario_.effects, &image);
  if (options_.bayer == "none") {
    f.images = std::move(out.images);
  } else {
    for (const cv::Mat& rgb : out.images) f.images.push_back(mosaicBayer(rgb, options_.bayer));
  }
  f.person_masks = std::move(out.person_masks);
  f.skin_masks = std::move(out.skin_masks);
  return f;
}

}  // namespace tabletop_sim
