#include "desk_shadow.h"

#include <algorithm>

namespace tabletop_sim {
namespace detail {

using Eigen::Vector3d;

void planDeskShadow(const std::vector<Primitive>& person, const Scene& scene, double texel,
                    ShadowMap* sm) {
  sm->active = false;
  sm->feet.clear();
  const Vector3d L = scene.light().to_light;
  if (person.empty() || L.z() < 0.05) return;
  const DeskTop& desk = scene.desk();
  const double ts = texel;
  const int NX = static_cast<int>(std::ceil((desk.x_max - desk.x_min) / ts));
  const int NY = static_cast<int>(std::ceil((desk.y_max - desk.y_min) / ts));
  using Foot = ShadowMap::Footprint;
  std::vector<Foot>& feet = sm->feet;
  int ui0 = NX, uj0 = NY, ui1 = -1, uj1 = -1;
  for (size_t k = 0; k < person.size(); ++k) {
    const Eigen::AlignedBox3d b = person[k].bounds();
    if (b.max().z() <= 0.0) continue;  // entirely below the desk top
    double x0 = 1e9, y0 = 1e9, x1 = -1e9, y1 = -1e9;
    for (int corner = 0; corner < 8; ++corner) {
      Vector3d p = b.corner(static_cast<Eigen::AlignedBox3d::CornerType>(corner));
      p.z() = std::max(p.z(), 0.0);
      const Vector3d q = p - (p.z() / L.z()) * L;  // along the light onto z = 0
      x0 = std::min(x0, q.x());
      x1 = std::max(x1, q.x());
      y0 = std::min(y0, q.y());
      y1 = std::max(y1, q.y());
    }
    Foot f{static_cast<int>(k),
           std::max(0, static_cast<int>(std::floor((x0 - desk.x_min) / ts - 0.5)) - 1),
           std::max(0, static_cast<int>(std::floor((y0 - desk.y_min) / ts - 0.5)) - 1),
           std::min(NX - 1, static_cast<int>(std::ceil((x1 - desk.x_min) / ts - 0.5)) + 1),
           std::min(NY - 1, static_cast<int>(std::ceil((y1 - desk.y_min) / ts - 0.5)) + 1)};
    if (f.i0 > f.i1 || f.j0 > f.j1) continue;
    feet.push_back(f);
    ui0 = std::min(ui0, f.i0);
    uj0 = std::min(uj0, f.j0);
    ui1 = std::max(ui1, f.i1);
    uj1 = std::max(uj1, f.j1);
  }
  if (feet.empty()) return;
  sm->active = true;
  sm->x_min = desk.x_min;
  sm->y_min = desk.y_min;
  sm->texel = ts;
  sm->tx0 = ui0;
  sm->ty0 = uj0;
  sm->nx = ui1 - ui0 + 1;
  sm->ny = uj1 - uj0 + 1;
  sm->occ.assign(static_cast<size_t>(sm->nx) * sm->ny, 0.0f);
  sm->to_light = L;
}

void fillDeskShadowRow(const std::vector<Primitive>& person, int row, ShadowMap* sm) {
  const int j = sm->ty0 + row;
  float* occ = sm->occ.data() + static_cast<size_t>(row) * sm->nx - sm->tx0;  // indexed by i
  for (const ShadowMap::Footprint& f : sm->feet) {
    if (j < f.j0 || j > f.j1) continue;
    const Primitive& p = person[f.prim];
    for (int i = f.i0; i <= f.i1; ++i) {
      if (occ[i] > 0.0f) continue;
      const Vector3d origin(sm->x_min + (i + 0.5) * sm->texel, sm->y_min + (j + 0.5) * sm->texel,
                            0.0);
      double t;
      if (p.intersect(origin, sm->to_light, &t)) occ[i] = 1.0f;
    }
  }
}

}  // namespace detail
}  // namespace tabletop_sim
