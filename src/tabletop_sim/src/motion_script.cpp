#include "tabletop_sim/motion_script.h"

#include "tabletop_sim/scene.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <stdexcept>

namespace tabletop_sim {

using Eigen::Vector3d;

double minJerk(double u) {
  u = std::clamp(u, 0.0, 1.0);
  return u * u * u * (10.0 + u * (-15.0 + 6.0 * u));
}

namespace {

constexpr int L = static_cast<int>(Side::LEFT);
constexpr int R = static_cast<int>(Side::RIGHT);
const double kNaN = std::numeric_limits<double>::quiet_NaN();

Vector3d mirror(const Vector3d& v) { return Vector3d(-v.x(), v.y(), v.z()); }

// ---- desk contact (see the header) ----
constexpr double kDeskClearance = 0.001;  // m between the lowest hand point and the desk top
constexpr double kClosedCurl = 0.5;       // digits curled at least this much lift the hand
constexpr int kCurlBisections = 10;       // curl resolution 1/1024 of the scripted curl
constexpr int kLiftIterations = 4;

double lowestOf(const std::vector<Primitive>& prims, size_t i) { return prims[i].bounds().min().z(); }

double digitLowest(const std::vector<Primitive>& prims, size_t palm, int digit) {
  return std::min(lowestOf(prims, palm + BodyModel::digitPrimitive(digit, 0)),
                  lowestOf(prims, palm + BodyModel::digitPrimitive(digit, 1)));
}

size_t palmIndex(const std::vector<Primitive>& prims, Side side) {
  for (size_t i = 0; i < prims.size(); ++i)
    if (prims[i].part == handPart(side)) return i;
  throw std::logic_error("MotionScript: body model built no hand");
}

bool overDesk(const Vector3d& palm) {
  const DeskTop desk;
  return palm.x() > desk.x_min && palm.x() < desk.x_max && palm.y() > desk.y_min &&
         palm.y() < desk.y_max && palm.z() > -0.02;
}

// Straightens the open digits of `side` that dip below the clearance plane (largest curl that
// clears it, by bisection), then returns the lowest point of the palm and all digits.
double straightenOpenDigits(const BodyModel& model, BodyPose* pose, Side side,
                            std::vector<Primitive>* prims) {
  model.build(*pose, prims);
  const size_t palm = palmIndex(*prims, side);
  HandPose& hand = pose->hand(side);
  for (int d = 0; d < 5; ++d) {
    if (hand.curl[d] >= kClosedCurl || digitLowest(*prims, palm, d) >= kDeskClearance) continue;
    double lo = 0.0, hi = hand.curl[d];
    for (int i = 0; i < kCurlBisections; ++i) {
      hand.curl[d] = 0.5 * (lo + hi);
      model.build(*pose, prims);
      (digitLowest(*prims, palm, d) >= kDeskClearance ? lo : hi) = hand.curl[d];
    }
    hand.curl[d] = lo;
    model.build(*pose, prims);
  }
  double low = lowestOf(*prims, palm);
  for (int d = 0; d < 5; ++d) low = std::min(low, digitLowest(*prims, palm, d));
  return low;
}


// Appends keyframes; each new key starts as a copy of the previous one.
struct Builder {
  std::vector<Keyframe> keys{MotionScript::restKey()};
  Keyframe& then(double dt) {
    Keyframe k = keys.back();
    k.time += dt;
    keys.push_back(k);
    return keys.back();
  }
  void hold(double dt) { then(dt); }
  void rest(double dt) {
    const double t = keys.back().time + dt;
    keys.push_back(MotionScript::restKey());
    keys.back().time = t;
  }
};

// Right hand waves at shoulder height, palm towards the screen, then the left hand briefly.
std::vector<Keyframe> wave() {
  Builder b;
  for (int side : {R, L}) {
    const double sx = side == R ? 1.0 : -1.0;
    const int cycles = side == R ? 6 : 4;
    Keyframe& up = b.then(1.0);
    ArmKey& a = up.arms[side];
    a.palm = Vector3d(sx * 0.30, -0.28, 0.50);
    a.pole = Vector3d(sx * 1.0, -0.2, -0.6);
    a.dorsal = Vector3d(0, -1, 0);
    a.finger_elevation = kNaN;
    a.hand = HandPose::preset(HandShape::OPEN);
    up.trunk[7] = sx * -0.15;  // look at the hand (positive yaw turns left)
    for (int i = 0; i < cycles; ++i) {
      Keyframe& k = b.then(0.35);
      const double dir = (i % 2 == 0) ? 1.0 : -1.0;
      k.arms[side].palm.x() = sx * (0.31 + dir * 0.07);
      k.arms[side].hand.deviation = dir * 0.25;
    }
    Keyframe& mid = b.then(0.3);
    mid.arms[side].palm.x() = sx * 0.31;
    mid.arms[side].hand.deviation = 0.0;
    b.rest(1.0);
  }
  return b.keys;
}

// Point with the index finger at things on the far side of the desk, right hand then left.
std::vector<Keyframe> point() {
  Builder b;
  Keyframe& k1 = b.then(1.0);
  ArmKey& r = k1.arms[R];
  r.palm = Vector3d(0.12, 0.0, 0.24);
  r.pole = Vector3d(0.8, -0.2, -0.8);
  r.finger_elevation = -0.25;
  r.hand = HandPose::preset(HandShape::POINT);
  k1.trunk[3] = -0.08;
  b.hold(0.8);
  Keyframe& k2 = b.then(0.8);
  k2.arms[R].palm = Vector3d(0.26, 0.02, 0.22);
  k2.trunk[7] = -0.2;
  b.hold(0.5);
  b.rest(1.0);
  Keyframe& k3 = b.then(1.0);
  ArmKey& l = k3.arms[L];
  l.palm = Vector3d(-0.15, 0.0, 0.26);
  l.pole = Vector3d(-0.8, -0.2, -0.8);
  l.finger_elevation = -0.2;
  l.hand = HandPose::preset(HandShape::POINT);
  k3.trunk[3] = -0.08;
  k3.trunk[7] = 0.2;
  b.hold(0.8);
  b.rest(1.0);
  return b.keys;
}

// Hands come together in front of the chest, palms facing, fingers interlocked; then apart.
std::vector<Keyframe> foldHands() {
  Builder b;
  auto setArms = [](Keyframe& k, double x, double y, double z, double curl, double thumb) {
    for (int side : {L, R}) {
      const double sx = side == R ? 1.0 : -1.0;
      ArmKey& a = k.arms[side];
      a.palm = Vector3d(sx * x, y, z);
      a.pole = Vector3d(sx * 0.4, -0.6, -0.8);
      a.dorsal = Vector3d(sx, 0.0, 0.15);
      a.finger_elevation = kNaN;
      a.hand = HandPose::preset(HandShape::OPEN);
      a.hand.flex = 0.0;
      for (int f = 1; f < 5; ++f) a.hand.curl[f] = curl;
      a.hand.curl[0] = thumb;
    }
  };
  setArms(b.then(1.0), 0.13, -0.08, 0.18, 0.1, 0.0);
  setArms(b.then(0.7), 0.021, -0.06, 0.19, 0.55, 0.3);
  setArms(b.then(1.2), 0.021, -0.05, 0.23, 0.6, 0.3);  // clasped hands drift up a little
  setArms(b.then(0.7), 0.15, -0.08, 0.18, 0.1, 0.0);
  b.rest(1.0);
  return b.keys;
}

// Each hand in turn reaches 8 targets on the desk, changing shape on the way: open palm flat
// on the target, fist resting on it, or the index finger touching it.
std::vector<Keyframe> reachTargets() {
  const Vector3d targets[8] = {{-0.38, -0.22, 0}, {-0.34, -0.04, 0}, {-0.22, 0.05, 0},
                               {-0.06, 0.06, 0},  {0.05, -0.06, 0},  {-0.08, -0.18, 0},
                               {-0.22, -0.10, 0}, {-0.42, 0.04, 0}};
  const HandShape shapes[3] = {HandShape::OPEN, HandShape::FIST, HandShape::POINT};
  Builder b;
  for (int side : {L, R}) {
    const double sx = side == R ? 1.0 : -1.0;
    for (int i = 0; i < 8; ++i) {
      const Vector3d t = side == L ? targets[i] : mirror(targets[i]);
      const HandShape shape = shapes[i % 3];
      ArmKey a;
      a.pole = Vector3d(sx * 0.7, -0.2, -0.7);
      a.hand = HandPose::preset(shape);
      a.dorsal = Vector3d::UnitZ();
      a.finger_elevation = 0.0;
      Vector3d palm = t;
      if (shape == HandShape::OPEN) {
        palm.z() = 0.026;
      } else if (shape == HandShape::FIST) {
        palm.z() = 0.062;
      } else {
        // Index tip on the target: the palm sits back along the reach and the hand tilts down.
        const Vector3d back = Vector3d(t.x() - sx * 0.17, t.y() + 0.45, 0).normalized();
        palm = t - 0.10 * back;
        palm.z() = 0.072;
        a.finger_elevation = -0.45;
      }
      a.palm = palm;
      // Lean forward (negative roll) and protract the shoulder for the far targets.
      const double lean = std::clamp(0.9 * (t.y() + 0.12), 0.0, 0.28);
      a.shoulder_shift = 0.1 * lean;
      Keyframe& hover = b.then(i == 0 ? 0.8 : 0.55);
      hover.arms[side] = a;
      hover.arms[side].palm.z() += 0.10;
      hover.trunk[3] = -lean;
      hover.trunk[7] =
          -sx * 0.25 * std::clamp(std::abs(t.x()) * 3.0, 0.0, 1.0) * (t.x() * sx > 0 ? 1.0 : -1.0);
      Keyframe& touch = b.then(0.3);
      touch.arms[side] = a;
      b.hold(0.3);
    }
    b.rest(0.9);
  }
  return b.keys;
}

// The right hand leaves the workspace far out to the side, then the left hand drops into the
// lap below the desk; each is outside the workspace box for about 1.6 s and comes back.
std::vector<Keyframe> leaveReenter() {
  Builder b;
  {
    Keyframe& k1 = b.then(0.8);
    k1.arms[R].palm = Vector3d(0.45, -0.30, 0.28);
    k1.arms[R].pole = Vector3d(0.5, -0.5, -0.8);
    k1.arms[R].hand = HandPose::preset(HandShape::OPEN);
    Keyframe& k2 = b.then(0.6);
    k2.arms[R].palm = Vector3d(0.70, -0.28, 0.24);
    k2.trunk[4] = 0.10;          // lean to the right (positive pitch)
    Keyframe& k3 = b.then(0.8);  // out of the box ~1.6 s in all, transitions included
    k3.arms[R].palm = Vector3d(0.72, -0.24, 0.22);
    Keyframe& k4 = b.then(0.6);
    k4.arms[R].palm = Vector3d(0.45, -0.30, 0.28);
    k4.trunk[4] = 0.0;
    b.rest(0.8);
  }
  {
    Keyframe& k1 = b.then(0.8);
    k1.arms[L].palm = Vector3d(-0.22, -0.44, 0.06);
    k1.arms[L].pole = Vector3d(-0.5, -0.6, -0.4);
    k1.arms[L].finger_elevation = -0.5;
    Keyframe& k2 = b.then(0.6);
    k2.arms[L].palm = Vector3d(-0.11, -0.38, -0.10);
    b.hold(0.8);
    Keyframe& k4 = b.then(0.6);
    k4.arms[L].palm = Vector3d(-0.22, -0.44, 0.06);
    b.rest(0.8);
  }
  return b.keys;
}

// Head turns left and right, then two nods (upper-spine bend).
std::vector<Keyframe> headTurn() {
  Builder b;
  b.then(0.9).trunk[7] = 0.6;
  b.hold(0.4);
  b.then(1.4).trunk[7] = -0.6;
  b.hold(0.4);
  b.then(0.9).trunk[7] = 0.0;
  for (int i = 0; i < 2; ++i) {
    b.then(0.5).trunk[6] = 0.22;
    b.then(0.5).trunk[6] = 0.08;
  }
  return b.keys;
}

std::vector<Keyframe> still() {
  Builder b;
  b.hold(3.0);
  return b.keys;
}

const std::vector<std::pair<std::string, std::function<std::vector<Keyframe>()>>>& generators() {
  static const std::vector<std::pair<std::string, std::function<std::vector<Keyframe>()>>> g = {
      {"wave", wave},
      {"point", point},
      {"fold_hands", foldHands},
      {"reach_targets", reachTargets},
      {"leave_reenter", leaveReenter},
      {"head_turn", headTurn},
      {"static", still}};
  return g;
}

}  // namespace

Keyframe MotionScript::restKey() {
  Keyframe k;
  k.trunk = {{0.0, -0.48, -0.17, 0.0, 0.0, 0.0, 0.08, 0.0}};
  for (int side : {L, R}) {
    const double sx = side == R ? 1.0 : -1.0;
    ArmKey& a = k.arms[side];
    a.palm = Vector3d(sx * 0.2, -0.25, BodyModel::kRestPalmHeight);
    a.pole = Vector3d(sx * 0.6, -0.3, -0.75);
    a.dorsal = Vector3d::UnitZ();
    a.finger_elevation = 0.0;
    a.hand = BodyModel::relaxedHand();
  }
  return k;
}

const std::vector<std::string>& MotionScript::names() {
  static const std::vector<std::string> n = [] {
    std::vector<std::string> v;
    for (const auto& g : generators()) v.push_back(g.first);
    v.push_back("all");
    return v;
  }();
  return n;
}

MotionScript MotionScript::create(const std::string& name, const BodyModel& model) {
  if (name == "all") {
    std::vector<Keyframe> keys;
    for (const auto& g : generators()) {
      std::vector<Keyframe> part = g.second();
      const double offset = keys.empty() ? 0.0 : keys.back().time;
      for (size_t i = keys.empty() ? 0 : 1; i < part.size(); ++i) {
        part[i].time += offset;
        keys.push_back(part[i]);
      }
    }
    return MotionScript("all", std::move(keys), model, true);
  }
  for (const auto& g : generators())
    if (g.first == name) return MotionScript(name, g.second(), model, name != "static");
  std::string valid;
  for (const auto& n : names()) valid += (valid.empty() ? "" : ", ") + n;
  throw std::invalid_argument("unknown motion script '" + name + "' (valid: " + valid + ")");
}

MotionScript::MotionScript(std::string name, std::vector<Keyframe> keys, const BodyModel& model,
                           bool idle_sway)
    : name_(std::move(name)), keys_(std::move(keys)), model_(model), idle_sway_(idle_sway) {
  if (keys_.size() < 2) throw std::invalid_argument("MotionScript: needs at least 2 keyframes");
  for (size_t i = 1; i < keys_.size(); ++i)
    if (!(keys_[i].time > keys_[i - 1].time))
      throw std::invalid_argument("MotionScript: keyframe times must increase");
  // Where a key fixes the finger elevation, store the wrist flexion that achieves it, so a
  // segment towards a key with a free wrist (NaN) starts from the same hand orientation.
  for (Keyframe& k : keys_) {
    bool any = false;
    for (const ArmKey& a : k.arms) any |= !std::isnan(a.finger_elevation);
    if (!any) continue;
    const BodyPose pose = poseFromKey(k);
    for (int side : {L, R})
      if (!std::isnan(k.arms[side].finger_elevation))
        k.arms[side].hand.flex = pose.hands[side].flex;
  }
}

Keyframe MotionScript::keyAt(double t) const {
  t = std::clamp(t, 0.0, duration());
  auto it = std::upper_bound(keys_.begin(), keys_.end(), t,
                             [](double v, const Keyframe& k) { return v < k.time; });
  if (it == keys_.end()) return keys_.back();
  if (it == keys_.begin()) return keys_.front();
  const Keyframe& a = *(it - 1);
  const Keyframe& b = *it;
  const double s = minJerk((t - a.time) / (b.time - a.time));
  Keyframe k;
  k.time = t;
  for (int i = 0; i < 8; ++i) k.trunk[i] = a.trunk[i] + s * (b.trunk[i] - a.trunk[i]);
  for (int side : {L, R}) {
    const ArmKey& x = a.arms[side];
    const ArmKey& y = b.arms[side];
    ArmKey& o = k.arms[side];
    o.palm = x.palm + s * (y.palm - x.palm);
    o.pole = x.pole + s * (y.pole - x.pole);
    o.dorsal = (x.dorsal + s * (y.dorsal - x.dorsal)).normalized();
    // NaN (free wrist) on either side makes the segment use the blended hand.flex.
    o.finger_elevation = x.finger_elevation + s * (y.finger_elevation - x.finger_elevation);
    o.shoulder_shift = x.shoulder_shift + s * (y.shoulder_shift - x.shoulder_shift);
    o.hand = blend(x.hand, y.hand, s);
  }
  return k;
}

BodyPose MotionScript::poseAt(double t) const { return poseFromKey(keyAt(t)); }

Vector3d MotionScript::palmTarget(double t, Side side) const {
  Vector3d targets[2];
  poseFromKey(keyAt(t), targets);
  return targets[static_cast<int>(side)];
}

BodyPose MotionScript::poseFromKey(const Keyframe& k, Vector3d* palm_targets) const {
  const double t = k.time;
  BodyPose pose;
  for (int i = 0; i < 8; ++i) pose.state[i] = k.trunk[i];
  if (idle_sway_) {
    // Breathing-like sway (a few mm), faded in and out so loops and joins stay smooth.
    const double w = minJerk(std::min(t, duration() - t) / 1.5);
    pose.state[dof::TORSO_X] += w * 0.004 * std::sin(2 * M_PI * 0.21 * t);
    pose.state[dof::TORSO_Z] += w * 0.003 * std::sin(2 * M_PI * 0.29 * t);
  }
  for (Side side : {Side::LEFT, Side::RIGHT}) {
    const ArmKey& a = k.arms[static_cast<int>(side)];
    pose.state[dof::arm(side, 2)] = a.shoulder_shift;
    pose.hand(side) = a.hand;
  }
  for (Side side : {Side::LEFT, Side::RIGHT}) {
    const ArmKey& a = k.arms[static_cast<int>(side)];
    const BodyFrames f = model_.forward(pose);
    const Vector3d s = f.shoulder[static_cast<int>(side)];
    const Vector3d pole = s + 0.5 * (f.chest.linear() * a.pole.normalized());
    Vector3d target = a.palm;
    model_.poseArm(&pose, side, target, pole, a.dorsal, a.finger_elevation);
    std::vector<Primitive> prims;
    for (int i = 0; i < kLiftIterations && overDesk(model_.palmCentre(pose, side)); ++i) {
      const double low = straightenOpenDigits(model_, &pose, side, &prims);
      if (low >= kDeskClearance - 1e-4) break;
      target.z() += kDeskClearance - low;
      model_.poseArm(&pose, side, target, pole, a.dorsal, a.finger_elevation);
    }
    if (palm_targets) palm_targets[static_cast<int>(side)] = target;
  }
  return pose;
}

}  // namespace tabletop_sim
