// Particle dynamics of the MPF (thesis 5.1.3): the head follows a random walk; a hand's
// particles are split in thirds that follow autoregressive models of order 1, 2 and 3
// (random walk, constant velocity, constant acceleration), each particle extrapolating its own
// position history (x_{t-1}, x_{t-2}, x_{t-3}).
#pragma once

#include <cstdint>

#include <Eigen/Core>

namespace hand_tracking {

enum class MotionModel : uint8_t { kAR1 = 1, kAR2 = 2, kAR3 = 3 };

// The hand model of the i-th particle of a component's pool (thirds interleaved so any prefix
// of the pool holds all three models).
inline MotionModel handModelOf(int i) { return static_cast<MotionModel>(1 + i % 3); }

struct ParticleHistory {
  Eigen::Vector3f x = Eigen::Vector3f::Zero();   // x_{t-1}
  Eigen::Vector3f x1 = Eigen::Vector3f::Zero();  // x_{t-2}
  Eigen::Vector3f x2 = Eigen::Vector3f::Zero();  // x_{t-3}
};

// The deterministic part of the prediction: x_{t-1} + r v + r^2 a with v, a the finite
// differences of the history (none for AR(1), v for AR(2), v and a for AR(3)) and r the ratio
// of this frame time to the previous one. The caller adds the noise and applies the speed limit.
inline Eigen::Vector3f extrapolate(MotionModel m, const ParticleHistory& h, float r) {
  switch (m) {
    case MotionModel::kAR1: return h.x;
    case MotionModel::kAR2: return h.x + r * (h.x - h.x1);
    case MotionModel::kAR3: {
      const Eigen::Vector3f v = h.x - h.x1;
      const Eigen::Vector3f a = v - (h.x1 - h.x2);
      return h.x + r * v + (r * r) * a;
    }
  }
  return h.x;
}

// Limits the step from `from` to `to` to max_step (m); returns the limited position.
inline Eigen::Vector3f limitStep(const Eigen::Vector3f& from, const Eigen::Vector3f& to,
                                 float max_step) {
  const Eigen::Vector3f d = to - from;
  const float n = d.norm();
  return n > max_step && n > 0.f ? Eigen::Vector3f(from + d * (max_step / n)) : to;
}

}  // namespace hand_tracking
