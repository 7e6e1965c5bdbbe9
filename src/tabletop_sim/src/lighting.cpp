#include "tabletop_sim/lighting.h"

#include <algorithm>
#include <cmath>

namespace tabletop_sim {

Eigen::Vector3d LightingScript::gain(double t) const {
  double g = intensity;
  if (flicker_amplitude != 0.0)
    g *= 1.0 + flicker_amplitude * std::sin(2.0 * M_PI * flicker_beat_hz * t + flicker_phase);
  g *= std::max(0.05, 1.0 + drift_per_minute * t / 60.0);
  if (sudden_time >= 0.0 && t >= sudden_time) g *= sudden_gain;
  return g * tint;
}

bool LightingScript::isConstant() const {
  return flicker_amplitude == 0.0 && drift_per_minute == 0.0 &&
         (sudden_time < 0.0 || sudden_gain == 1.0);
}

namespace {

// Tanner Helland's fit of blackbody colour to sRGB (8-bit values, converted to linear).
Eigen::Vector3d blackbody(double kelvin) {
  const double t = std::clamp(kelvin, 1000.0, 40000.0) / 100.0;
  double r, g, b;
  if (t <= 66) {
    r = 255;
    g = 99.4708025861 * std::log(t) - 161.1195681661;
  } else {
    r = 329.698727446 * std::pow(t - 60, -0.1332047592);
    g = 288.1221695283 * std::pow(t - 60, -0.0755148492);
  }
  if (t >= 66)
    b = 255;
  else if (t <= 19)
    b = 0;
  else
    b = 138.5177312231 * std::log(t - 10) - 305.0447927307;
  auto lin = [](double v) {
    const double c = std::clamp(v, 0.0, 255.0) / 255.0;
    return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4);
  };
  return {lin(r), lin(g), lin(b)};
}

}  // namespace

Eigen::Vector3d colourTemperatureTint(double kelvin) {
  const Eigen::Vector3d c = blackbody(kelvin), ref = blackbody(5000.0);
  Eigen::Vector3d tint = c.cwiseQuotient(ref);
  return tint / tint.y();
}

}  // namespace tabletop_sim
