#include "tabletop_sim/body_model.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace tabletop_sim {

using Eigen::Isometry3d;
using Eigen::Matrix3d;
using Eigen::Vector3d;

const char* handShapeName(HandShape s) {
  switch (s) {
    case HandShape::OPEN:
      return "open";
    case HandShape::FIST:
      return "fist";
    case HandShape::POINT:
      return "point";
  }
  return "?";
}

HandPose HandPose::preset(HandShape s) {
  HandPose h;
  h.shape = s;
  switch (s) {
    case HandShape::OPEN:
      h.curl = {{0.0, 0.1, 0.05, 0.1, 0.15}};
      break;
    case HandShape::FIST:
      h.curl = {{1.0, 1.0, 1.0, 1.0, 1.0}};
      break;
    case HandShape::POINT:
      h.curl = {{0.9, 0.0, 1.0, 1.0, 1.0}};
      break;
  }
  return h;
}

HandPose blend(const HandPose& a, const HandPose& b, double s) {
  HandPose h = s < 0.5 ? a : b;
  for (int i = 0; i < 5; ++i) h.curl[i] = a.curl[i] + s * (b.curl[i] - a.curl[i]);
  h.roll = a.roll + s * (b.roll - a.roll);
  h.flex = a.flex + s * (b.flex - a.flex);
  h.deviation = a.deviation + s * (b.deviation - a.deviation);
  return h;
}

namespace {

Matrix3d rotX(double a) { return Eigen::AngleAxisd(a, Vector3d::UnitX()).toRotationMatrix(); }
Matrix3d rotY(double a) { return Eigen::AngleAxisd(a, Vector3d::UnitY()).toRotationMatrix(); }
Matrix3d rotZ(double a) { return Eigen::AngleAxisd(a, Vector3d::UnitZ()).toRotationMatrix(); }

Isometry3d make(const Matrix3d& r, const Vector3d& t) {
  Isometry3d T = Isometry3d::Identity();
  T.linear() = r;
  T.translation() = t;
  return T;
}
Isometry3d trans(double x, double y, double z) { return make(Matrix3d::Identity(), {x, y, z}); }
Isometry3d rot(const Matrix3d& r) { return make(r, Vector3d::Zero()); }

// Left arm sits on -x (x is the person's right).
double sideSign(Side s) { return s == Side::LEFT ? -1.0 : 1.0; }
int idx(Side s) { return static_cast<int>(s); }

// Head geometry in the head (neck pivot) frame.
const Vector3d kHeadCentre(0.0, 0.025, 0.15);
const Vector3d kHeadSemi(0.075, 0.095, 0.115);

// Finger layout in the palm frame; x is given for the thumb side = +1 and mirrored per hand.
struct FingerSpec {
  double knuckle_x, knuckle_y, spread, len1, len2, radius;
};
const FingerSpec kFingers[4] = {
    {0.026, 0.044, 0.08, 0.046, 0.040, 0.0088},    // index
    {0.008, 0.047, 0.0, 0.051, 0.045, 0.0092},     // middle
    {-0.010, 0.045, -0.07, 0.048, 0.041, 0.0086},  // ring
    {-0.027, 0.039, -0.16, 0.038, 0.033, 0.0076},  // little
};
const Vector3d kPalmSemi(0.041, 0.048, 0.0155);

// The head grows half as much as the body.
double headScale(const BodyOptions& o) { return 1.0 + 0.5 * (o.size - 1.0); }

}  // namespace

const char* sleevesName(Sleeves s) {
  switch (s) {
    case Sleeves::LONG: return "long";
    case Sleeves::ROLLED: return "rolled";
    case Sleeves::SHORT: return "short";
    case Sleeves::CUFF: return "cuff";
  }
  return "?";
}

const char* hairName(Hair h) {
  switch (h) {
    case Hair::SHORT: return "short";
    case Hair::LONG: return "long";
    case Hair::NONE: return "none";
  }
  return "?";
}

BodyModel::BodyModel(const BodyOptions& options) : options_(options) {
  auto check = [](double v, double lo, double hi, const char* name) {
    if (!(v >= lo && v <= hi))
      throw std::invalid_argument(std::string("BodyModel: ") + name + " must be in [" +
                                  std::to_string(lo) + ", " + std::to_string(hi) + "]");
  };
  check(options.size, 0.8, 1.2, "size");
  check(options.arm_length, 0.85, 1.15, "arm_length");
  check(options.girth, 0.8, 1.4, "girth");
  check(options.hand_size, 0.75, 1.25, "hand_size");
  check(options.cuff_cover, 0.0, 0.8, "cuff_cover");
}

BodyFrames BodyModel::forward(const BodyPose& pose) const {
  const auto& q = pose.state;
  BodyFrames f;
  const Matrix3d r_torso =
      rotZ(q[dof::TORSO_YAW]) * rotY(q[dof::TORSO_PITCH]) * rotX(q[dof::TORSO_ROLL]);
  f.pelvis = make(r_torso, Vector3d(q[dof::TORSO_X], q[dof::TORSO_Y], q[dof::TORSO_Z]));
  const double sz = options_.size;
  f.chest = f.pelvis * trans(0, 0, kSpineHeight * sz) * rot(rotX(-q[dof::SPINE_BEND]));
  f.head = f.chest * trans(0, 0, kNeckHeight * sz) * rot(rotZ(q[dof::HEAD_YAW]));
  for (Side side : {Side::LEFT, Side::RIGHT}) {
    const int i = idx(side);
    const double sx = sideSign(side);
    const double shift = q[dof::arm(side, 2)];
    f.upper_arm[i] = f.chest * trans(sx * (kShoulderHalfWidth * sz + shift), 0, kShoulderHeight * sz) *
                     rot(rotX(q[dof::arm(side, 0)]) * rotZ(q[dof::arm(side, 1)]));
    f.shoulder[i] = f.upper_arm[i].translation();
    f.elbow[i] = f.upper_arm[i] * Vector3d(0, upperArm(), 0);
    f.forearm[i] =
        make(f.upper_arm[i].linear() * rotY(q[dof::arm(side, 4)]) * rotX(q[dof::arm(side, 3)]),
             f.elbow[i]);
    f.wrist[i] = f.forearm[i] * Vector3d(0, forearm(), 0);
    const HandPose& h = pose.hands[i];
    f.palm[i] = f.forearm[i] * trans(0, forearm(), 0) *
                rot(rotY(h.roll) * rotX(-h.flex) * rotZ(h.deviation)) * trans(0, wristToPalm(), 0);
  }
  return f;
}

Vector3d BodyModel::palmCentre(const BodyPose& pose, Side side) const {
  return forward(pose).palm[idx(side)].translation();
}

Vector3d BodyModel::headCentre(const BodyPose& pose) const {
  return forward(pose).head * (headScale(options_) * kHeadCentre);
}

Vector3d BodyModel::shoulder(const BodyPose& pose, Side side) const {
  return forward(pose).shoulder[idx(side)];
}

std::vector<Primitive> BodyModel::build(const BodyPose& pose) const {
  std::vector<Primitive> out;
  build(pose, &out);
  return out;
}

void BodyModel::build(const BodyPose& pose, std::vector<Primitive>* out) const {
  using M = Material;
  using P = BodyPart;
  out->clear();
  const BodyFrames f = forward(pose);
  const double sz = options_.size, gr = options_.girth, hs = options_.hand_size;
  const double hd = headScale(options_);
  auto ell = [&](const Isometry3d& T, const Vector3d& c, const Vector3d& semi, M m, P p) {
    out->push_back(Primitive::ellipsoid(T * c, T.linear(), semi, m, p));
  };
  auto cap = [&](const Vector3d& a, const Vector3d& b, double r, M m, P p) {
    out->push_back(Primitive::capsule(a, b, r, m, p));
  };
  // Trunk sizes: positions scale with the body, widths and depths also with the girth.
  const Vector3d trunk(sz * gr, sz * gr, sz);

  // Trunk. Legs follow the torso position but not its rotation (the chair holds them).
  ell(f.pelvis, {0, 0, 0}, trunk.cwiseProduct(Vector3d(0.17, 0.13, 0.10)), M::TROUSERS, P::TORSO);
  ell(f.pelvis, {0, 0, 0.14 * sz}, trunk.cwiseProduct(Vector3d(0.155, 0.11, 0.16)), M::SHIRT,
      P::TORSO);
  ell(f.chest, {0, 0, 0.15 * sz}, trunk.cwiseProduct(Vector3d(0.165, 0.105, 0.17)), M::SHIRT,
      P::TORSO);
  cap(f.chest * Vector3d(-0.15 * sz, 0, 0.27 * sz), f.chest * Vector3d(0.15 * sz, 0, 0.27 * sz),
      0.055 * gr, M::SHIRT, P::TORSO);
  const Isometry3d legs =
      trans(f.pelvis.translation().x(), f.pelvis.translation().y(), f.pelvis.translation().z());
  for (double sx : {-1.0, 1.0}) {
    const Vector3d hip = legs * Vector3d(sx * 0.09 * sz, 0.0, -0.02);
    const Vector3d knee = legs * Vector3d(sx * 0.10 * sz, 0.44, -0.02);
    const Vector3d ankle = legs * Vector3d(sx * 0.10 * sz, 0.47, -0.50);
    cap(hip, knee, 0.075 * gr, M::TROUSERS, P::LEGS);
    cap(knee, ankle, 0.052 * gr, M::TROUSERS, P::LEGS);
    ell(legs, {sx * 0.10 * sz, 0.53, -0.54}, {0.05, 0.12, 0.04}, M::SHOES, P::LEGS);
  }

  // Neck and head. The hair ellipsoid sits back and up so the face and ears stay skin.
  const Vector3d hc = hd * kHeadCentre;
  cap(f.chest * Vector3d(0, 0.0, 0.27 * sz), f.head * Vector3d(0, 0.005 * hd, 0.07 * hd),
      0.05 * gr, M::SKIN, P::NECK);
  ell(f.head, hc, hd * kHeadSemi, M::SKIN, P::HEAD);
  if (options_.hair != Hair::NONE)
    ell(f.head, hc + hd * Vector3d(0, -0.025, 0.03), hd * Vector3d(0.082, 0.092, 0.11), M::HAIR,
        P::HEAD);
  if (options_.hair == Hair::LONG)  // falls behind the neck to the shoulders
    ell(f.head, hc + hd * Vector3d(0, -0.06, -0.09), hd * Vector3d(0.085, 0.06, 0.15), M::HAIR,
        P::HEAD);
  ell(f.head, hc + hd * Vector3d(0, 0.09, -0.005), hd * Vector3d(0.013, 0.02, 0.024), M::SKIN,
      P::HEAD);
  for (double sx : {-1.0, 1.0}) {
    out->push_back(Primitive::sphere(f.head * (hc + hd * Vector3d(sx * 0.031, 0.079, 0.022)),
                                     0.0095 * hd, M::EYE, P::HEAD));
    ell(f.head, hc + hd * Vector3d(sx * 0.075, -0.005, 0.0), hd * Vector3d(0.012, 0.025, 0.032),
        M::SKIN, P::HEAD);
  }

  // Arms and hands.
  const Sleeves sleeves = options_.effectiveSleeves();
  for (Side side : {Side::LEFT, Side::RIGHT}) {
    const int i = idx(side);
    const bool left = side == Side::LEFT;
    const P upper = left ? P::LEFT_UPPER_ARM : P::RIGHT_UPPER_ARM;
    const P lower = left ? P::LEFT_FOREARM : P::RIGHT_FOREARM;
    const P hand = left ? P::LEFT_HAND : P::RIGHT_HAND;
    const Vector3d s = f.shoulder[i], e = f.elbow[i], w = f.wrist[i];
    const Vector3d fdir = (w - e).normalized();
    const double fl = forearm();
    out->push_back(Primitive::sphere(s, 0.056 * gr, M::SHIRT, upper));
    switch (sleeves) {
      case Sleeves::SHORT:
        cap(s, s + 0.55 * (e - s), 0.05 * gr, M::SLEEVE, upper);
        cap(s + 0.45 * (e - s), e, 0.042 * gr, M::SKIN, upper);
        cap(e, w, 0.035 * gr, M::SKIN, lower);
        break;
      case Sleeves::ROLLED:  // a thick roll of cloth ends 45 % down the forearm
        cap(s, e, 0.047 * gr, M::SLEEVE, upper);
        cap(e, e + 0.45 * (w - e), 0.044 * gr, M::SLEEVE, lower);
        cap(e + 0.4 * (w - e), w, 0.035 * gr, M::SKIN, lower);
        break;
      case Sleeves::LONG:
        cap(s, e, 0.047 * gr, M::SLEEVE, upper);
        // The cuff's rounded end stops ~1 cm before the wrist joint: a bare wrist shows.
        cap(e, w - 0.05 * sz * fdir, 0.04 * gr, M::SLEEVE, lower);
        cap(w - 0.07 * sz * fdir, w, 0.027 * gr, M::SKIN, lower);
        break;
      case Sleeves::CUFF: {
        // The sleeve goes on straight past the wrist, wide enough to swallow the palm's base:
        // its rounded end reaches cuff_cover of the palm's length beyond the palm's base.
        cap(s, e, 0.047 * gr, M::SLEEVE, upper);
        const double r = std::max(0.04 * gr, kPalmSemi.x() * hs + 0.004);
        const double reach = fl + wristToPalm() - kPalmSemi.y() * hs +
                             options_.cuff_cover * 2.0 * kPalmSemi.y() * hs;
        cap(e, e + std::max(0.5 * fl, reach - r) * fdir, r, M::SLEEVE, lower);
        break;
      }
    }

    // Hand: flattened ellipsoid palm + two capsules per finger, all skin.
    const Isometry3d& palm = f.palm[i];
    ell(palm, {0, 0, 0}, hs * kPalmSemi, M::SKIN, hand);
    const double ts = left ? 1.0 : -1.0;  // thumb side in palm x
    const HandPose& hp = pose.hands[i];
    for (int k = 0; k < 4; ++k) {
      const FingerSpec& fs = kFingers[k];
      const double c = std::clamp(hp.curl[k + 1], 0.0, 1.0);
      const double spread = ts * fs.spread * (1.0 - c);
      const Matrix3d base = palm.linear() * rotZ(spread);
      const double a1 = 1.45 * c, a2 = a1 + 1.85 * c;  // curl towards the palm side (-z)
      const Vector3d k0 = palm * Vector3d(ts * fs.knuckle_x * hs, fs.knuckle_y * hs, 0.0);
      const Vector3d k1 = k0 + fs.len1 * hs * (base * Vector3d(0, std::cos(a1), -std::sin(a1)));
      const Vector3d k2 = k1 + fs.len2 * hs * (base * Vector3d(0, std::cos(a2), -std::sin(a2)));
      cap(k0, k1, fs.radius * hs, M::SKIN, hand);
      cap(k1, k2, fs.radius * hs * 0.92, M::SKIN, hand);
    }
    // Thumb: from the base of the palm, out to the side when open, across the curled
    // fingers when closed.
    const double c = std::clamp(hp.curl[0], 0.0, 1.0);
    const Vector3d d1_open(ts * 0.70, 0.68, -0.22), d1_closed(ts * 0.25, 0.75, -0.62);
    const Vector3d d2_open(ts * 0.45, 0.88, -0.15), d2_closed(-ts * 0.75, 0.35, -0.55);
    const Vector3d d1 = (palm.linear() * (d1_open + c * (d1_closed - d1_open))).normalized();
    const Vector3d d2 = (palm.linear() * (d2_open + c * (d2_closed - d2_open))).normalized();
    const Vector3d t0 = palm * (hs * Vector3d(ts * 0.028, -0.022, -0.006));
    const Vector3d t1 = t0 + 0.046 * hs * d1;
    const Vector3d t2 = t1 + 0.036 * hs * d2;
    cap(t0, t1, 0.0105 * hs, M::SKIN, hand);
    cap(t1, t2, 0.0095 * hs, M::SKIN, hand);
  }
}

ArmSolution BodyModel::solveArm(const BodyPose& pose, Side side, const Vector3d& target,
                                const Vector3d& pole) const {
  const double l1 = upperArm(), l2 = forearm() + wristToPalm();
  BodyPose p = pose;
  Vector3d aim = target;
  ArmSolution sol;
  for (int iter = 0; iter < 6; ++iter) {
    const BodyFrames f = forward(p);
    const Vector3d s = f.shoulder[idx(side)];
    const Matrix3d rc = f.chest.linear();
    Vector3d v = aim - s;
    double d = v.norm();
    const Vector3d u = d > 1e-9 ? Vector3d(v / d) : Vector3d(rc * Vector3d(0, 1, 0));
    const double dmin = std::abs(l1 - l2) + 1e-4, dmax = l1 + l2 - 1e-4;
    sol.reachable = d >= dmin && d <= dmax;
    d = std::clamp(d, dmin, dmax);
    // Elbow on the circle of the two spheres, on the pole's side.
    const double a = (l1 * l1 - l2 * l2 + d * d) / (2.0 * d);
    const double h = std::sqrt(std::max(0.0, l1 * l1 - a * a));
    Vector3d n = (pole - s) - u * (pole - s).dot(u);
    if (n.norm() < 1e-9) n = (rc * Vector3d(0, 0, -1)) - u * (rc * Vector3d(0, 0, -1)).dot(u);
    if (n.norm() < 1e-9) n = u.unitOrthogonal();
    n.normalize();
    const Vector3d e = s + a * u + h * n;
    const Vector3d dc = rc.transpose() * ((e - s) / l1);
    sol.swing2 = std::asin(std::clamp(-dc.x(), -1.0, 1.0));
    sol.swing1 = std::atan2(dc.z(), dc.y());
    const double cos_in = std::clamp((l1 * l1 + l2 * l2 - d * d) / (2 * l1 * l2), -1.0, 1.0);
    sol.flex = std::min(M_PI - std::acos(cos_in), kMaxElbowFlex);
    const Vector3d fw = (s + d * u - e).normalized();
    const Matrix3d ru = rc * rotX(sol.swing1) * rotZ(sol.swing2);
    const Vector3d fu = ru.transpose() * fw;
    sol.twist = sol.flex > 1e-6 ? std::atan2(fu.x(), fu.z()) : p.state[dof::arm(side, 4)];
    applyArm(&p, side, sol);
    const Vector3d err = target - palmCentre(p, side);
    sol.residual = err.norm();
    if (sol.residual < 1e-6) break;
    aim += err;  // wrist flexion puts the palm off the forearm axis: shift the aim point
  }
  return sol;
}

void BodyModel::applyArm(BodyPose* pose, Side side, const ArmSolution& s) {
  pose->state[dof::arm(side, 0)] = s.swing1;
  pose->state[dof::arm(side, 1)] = s.swing2;
  pose->state[dof::arm(side, 3)] = s.flex;
  pose->state[dof::arm(side, 4)] = s.twist;
}

double BodyModel::rollForDorsal(const BodyPose& pose, Side side, const Vector3d& dorsal) const {
  // Rolling about the forearm axis k rotates the back-of-hand axis z0 (roll = 0) about k:
  // z(r).D = (A - C) cos r + B sin r + C, maximal at r = atan2(B, A - C).
  BodyPose p = pose;
  p.hands[idx(side)].roll = 0.0;
  const BodyFrames f = forward(p);
  const Vector3d k = f.forearm[idx(side)].linear().col(1);
  const Vector3d z0 = f.palm[idx(side)].linear().col(2);
  const Vector3d dn = dorsal.normalized();
  const double A = z0.dot(dn), B = k.cross(z0).dot(dn), C = k.dot(z0) * k.dot(dn);
  return std::atan2(B, A - C);
}

ArmSolution BodyModel::poseArm(BodyPose* pose, Side side, const Vector3d& target,
                               const Vector3d& pole, const Vector3d& dorsal,
                               double finger_elevation) const {
  // Alternate IK and wrist until the wrist stops changing, so the result does not depend on
  // the starting pose (scripts evaluated at any time agree with restPose()).
  ArmSolution sol;
  HandPose& h = pose->hands[idx(side)];
  for (int iter = 0; iter < 50; ++iter) {
    sol = solveArm(*pose, side, target, pole);
    applyArm(pose, side, sol);
    const double roll = rollForDorsal(*pose, side, dorsal);
    double change = std::abs(std::remainder(roll - h.roll, 2.0 * M_PI));
    h.roll = roll;
    if (!std::isnan(finger_elevation)) {
      const Vector3d fingers = forward(*pose).palm[idx(side)].linear().col(1);
      const double elev = std::asin(std::clamp(fingers.z(), -1.0, 1.0));
      const double flex = std::clamp(h.flex + (elev - finger_elevation), -1.2, 1.2);
      change = std::max(change, std::abs(flex - h.flex));
      h.flex = flex;
    }
    if (change < 1e-10) break;
  }
  sol = solveArm(*pose, side, target, pole);
  applyArm(pose, side, sol);
  return sol;
}

HandPose BodyModel::relaxedHand() {
  HandPose h = HandPose::preset(HandShape::OPEN);
  h.curl = {{0.0, 0.09, 0.08, 0.09, 0.12}};  // what a quarter-closed hand keeps on a flat desk
  return h;
}

BodyPose BodyModel::restPose() {
  BodyPose p;
  p.state[dof::TORSO_X] = 0.0;
  p.state[dof::TORSO_Y] = -0.48;
  p.state[dof::TORSO_Z] = -0.17;
  p.state[dof::SPINE_BEND] = 0.08;
  const BodyModel model;
  for (Side side : {Side::LEFT, Side::RIGHT}) {
    const double sx = sideSign(side);
    HandPose& h = p.hands[idx(side)];
    h = relaxedHand();
    const BodyFrames f = model.forward(p);
    const Vector3d s = f.shoulder[idx(side)];
    const Vector3d pole = s + f.chest.linear() * Vector3d(sx * 0.6, -0.3, -0.75);
    model.poseArm(&p, side, Vector3d(sx * 0.2, -0.25, kRestPalmHeight), pole, Vector3d::UnitZ(), 0.0);
  }
  return p;
}

Vector3d visibleSkinCentroid(const std::vector<Primitive>& prims, Side side, double spacing) {
  const BodyPart part = handPart(side);
  std::vector<const Primitive*> skin, covers;
  Eigen::AlignedBox3d box;
  for (const Primitive& p : prims)
    if (p.part == part && isSkin(p.material)) {
      skin.push_back(&p);
      box.extend(p.bounds());
    }
  const Vector3d none = Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  if (skin.empty()) return none;
  for (const Primitive& p : prims)
    if (!isSkin(p.material) && p.bounds().intersects(box)) covers.push_back(&p);
  // Each skin primitive walks the lattice cells in its own bounds and counts a cell only if
  // no earlier one holds it (the union, once) and nothing non-skin covers it. The lattice is
  // anchored at the world origin, so the answer does not jump with the bounds.
  Vector3d sum = Vector3d::Zero();
  long n = 0;
  for (size_t k = 0; k < skin.size(); ++k) {
    const Eigen::AlignedBox3d b = skin[k]->bounds();
    const Eigen::Vector3i lo = (b.min() / spacing).array().floor().cast<int>();
    const Eigen::Vector3i hi = (b.max() / spacing).array().floor().cast<int>();
    for (int z = lo.z(); z <= hi.z(); ++z)
      for (int y = lo.y(); y <= hi.y(); ++y)
        for (int x = lo.x(); x <= hi.x(); ++x) {
          const Vector3d q = spacing * Vector3d(x + 0.5, y + 0.5, z + 0.5);
          if (!skin[k]->contains(q)) continue;
          bool counted = false;
          for (size_t j = 0; j < k && !counted; ++j) counted = skin[j]->contains(q);
          for (size_t j = 0; j < covers.size() && !counted; ++j) counted = covers[j]->contains(q);
          if (counted) continue;
          sum += q;
          ++n;
        }
  }
  return n == 0 ? none : Vector3d(sum / static_cast<double>(n));
}

Vector3d handCentroid(const std::vector<Primitive>& prims, Side side) {
  const BodyPart part = handPart(side);
  Vector3d sum = Vector3d::Zero();
  double vol = 0.0;
  for (const Primitive& p : prims) {
    if (p.part != part || !isSkin(p.material)) continue;
    const double v = p.volume();
    sum += v * p.centroid();
    vol += v;
  }
  if (vol <= 0.0) return Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  return sum / vol;
}

}  // namespace tabletop_sim
