// The person's shadow on the desk top, shared by all cameras of a frame: the desk plane is
// sampled on a grid and each texel's ray towards the light is tested against the primitives
// whose light-space footprint covers it. Private to src/sim (not installed).
#pragma once

#include <cmath>
#include <vector>

#include "tabletop_sim/primitives.h"
#include "tabletop_sim/scene.h"

namespace tabletop_sim {
namespace detail {

// The person's shadow on the desk top: occupancy of texels (1 = the light is blocked) over the
// union of the primitives' footprints; bilinear lookups give a soft edge one texel wide.
struct ShadowMap {
  bool active = false;
  double x_min = 0, y_min = 0, texel = 0.004;
  int tx0 = 0, ty0 = 0, nx = 0, ny = 0;  // sub-grid actually stored
  std::vector<float> occ;
  // Plan: which primitive may shade which texels (grid indices, inclusive).
  struct Footprint {
    int prim, i0, j0, i1, j1;
  };
  std::vector<Footprint> feet;
  Eigen::Vector3d to_light = Eigen::Vector3d::UnitZ();

  float sample(double x, double y) const {
    const double fx = (x - x_min) / texel - 0.5 - tx0, fy = (y - y_min) / texel - 0.5 - ty0;
    const int i = static_cast<int>(std::floor(fx)), j = static_cast<int>(std::floor(fy));
    if (i < -1 || j < -1 || i >= nx || j >= ny) return 0.0f;
    const float ax = static_cast<float>(fx - i), ay = static_cast<float>(fy - j);
    auto at = [&](int u, int v) {
      return (u < 0 || v < 0 || u >= nx || v >= ny) ? 0.0f : occ[v * nx + u];
    };
    return (1 - ay) * ((1 - ax) * at(i, j) + ax * at(i + 1, j)) +
           ay * ((1 - ax) * at(i, j + 1) + ax * at(i + 1, j + 1));
  }
};

// Plans *sm for this frame's person: the primitives' footprints along the light and the
// sub-grid they cover, cleared (inactive when nothing can shade the desk). Serial and cheap.
void planDeskShadow(const std::vector<Primitive>& person, const Scene& scene, double texel,
                    ShadowMap* sm);
// Fills row j (0 .. sm->ny - 1) of a planned map; rows are independent (run them in parallel).
void fillDeskShadowRow(const std::vector<Primitive>& person, int j, ShadowMap* sm);

}  // namespace detail
}  // namespace tabletop_sim
