// How the light of a scenario changes over time: a colour (temperature), an intensity, 50 Hz
// mains flicker, slow drift and one sudden change (a lamp switched on). The scene's shading
// uses the static DirectionalLight; these changes scale every pixel of every camera, which is
// what a change of the room light does to a Lambertian scene (the renderer applies the gain
// before the sensor noise, so noise does not scale with it).
#pragma once

#include <Eigen/Core>

#include "tabletop_sim/scene.h"

namespace tabletop_sim {

struct LightingScript {
  DirectionalLight light;                            // direction and ambient/direct split
  Eigen::Vector3d tint = Eigen::Vector3d::Ones();    // per-channel colour of the light (R, G, B)
  double intensity = 1.0;                            // overall gain
  // Mains flicker: lamps ripple at 100 Hz (50 Hz mains), and a shutter not locked to the
  // mains samples the ripple at a slowly moving phase, so frame brightness beats at a low
  // frequency. The frame gain is 1 + amplitude * sin(2 pi beat_hz t + phase).
  double flicker_amplitude = 0.0;
  double flicker_beat_hz = 0.0;
  double flicker_phase = 0.0;
  double drift_per_minute = 0.0;  // relative gain change per minute (linear in time)
  double sudden_time = -1.0;      // s; from then on the gain is multiplied by sudden_gain (< 0: never)
  double sudden_gain = 1.0;

  // Per-channel gain of the light at time t (s).
  Eigen::Vector3d gain(double t) const;
  bool isConstant() const;
};

// Per-channel gain of a light of colour temperature `kelvin` relative to the default light
// (about 5000 K), normalised so that green is 1: warm light (3000 K) is redder, daylight
// (6500 K) bluer. A smooth fit to the Planckian locus through sRGB primaries; valid
// 2500-10000 K.
Eigen::Vector3d colourTemperatureTint(double kelvin);

}  // namespace tabletop_sim
