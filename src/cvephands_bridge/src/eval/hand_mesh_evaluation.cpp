#include "cvephands_bridge/eval/hand_mesh_evaluation.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "cvephands_bridge/eval/sim_hand_volumes.h"
#include "cvephands_bridge/mesh/mesh_components.h"
#include "tabletop_sim/surface_samples.h"

namespace cvephands {
namespace {

namespace sim = tabletop_sim;

double msSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

ProbabilityGridView viewOf(const psfs::ProbabilityVolume& v) {
  ProbabilityGridView g;
  g.data = v.data.data();
  g.dims = v.grid.dims;
  g.origin = v.grid.origin;
  g.voxel_size = v.grid.voxel_size;
  return g;
}

// The triangles whose three vertices lie inside `inner` (vertices kept as they are).
TriangleMesh insidePart(const TriangleMesh& m, const Eigen::AlignedBox3d& inner) {
  TriangleMesh out;
  out.vertices = m.vertices;
  for (size_t t = 0; t + 2 < m.triangles.size(); t += 3) {
    bool in = true;
    for (int k = 0; k < 3; ++k) in = in && inner.contains(m.vertices[m.triangles[t + k]].cast<double>());
    if (in) out.triangles.insert(out.triangles.end(), m.triangles.begin() + t, m.triangles.begin() + t + 3);
  }
  return out;
}

// mesh -> truth from the mesh's inner part against all samples; truth -> mesh from the inner
// samples against the whole mesh (so neither side is penalised for the other's cut).
MeshAccuracy scoreMesh(const TriangleMesh& mesh, const sim::SurfaceSamples& truth,
                   const Eigen::AlignedBox3d& inner) {
  std::vector<Eigen::Vector3f> inner_truth;
  for (const Eigen::Vector3f& p : truth.points)
    if (inner.contains(p.cast<double>())) inner_truth.push_back(p);
  MeshAccuracy a;
  a.mesh_to_truth = meshAccuracy(insidePart(mesh, inner), truth.points).mesh_to_truth;
  a.truth_to_mesh = meshAccuracy(mesh, inner_truth).truth_to_mesh;
  return a;
}

void addStats(const MeshAccuracy& a, tabletop_common::RunningStats* m2t,
              tabletop_common::RunningStats* t2m, tabletop_common::RunningStats* p95m2t,
              tabletop_common::RunningStats* p95t2m) {
  if (a.mesh_to_truth.count) m2t->add(a.mesh_to_truth.mean_mm), p95m2t->add(a.mesh_to_truth.p95_mm);
  if (a.truth_to_mesh.count) t2m->add(a.truth_to_mesh.mean_mm), p95t2m->add(a.truth_to_mesh.p95_mm);
}

}  // namespace

namespace {

void validate(const HandMeshEvalOptions& o) {
  if (o.every < 1) throw std::invalid_argument("evaluateHandMeshes: every must be >= 1");
  if (o.frames < 0) throw std::invalid_argument("evaluateHandMeshes: frames must be >= 0");
  if (!(o.iso > 0.0 && o.iso < 1.0)) throw std::invalid_argument("evaluateHandMeshes: iso in (0, 1)");
  if (!(o.border_voxels >= 0.0)) throw std::invalid_argument("evaluateHandMeshes: border_voxels < 0");
  if (!(o.keep_radius >= 0.0)) throw std::invalid_argument("evaluateHandMeshes: keep_radius < 0");
}

MarchingCubesOptions meshingOptions(const HandMeshEvalOptions& o, MeshingMode mode) {
  validate(o);
  MarchingCubesOptions mo;
  mo.iso = static_cast<float>(std::floor(255.0 * o.iso) + 0.5);
  mo.threads = 1;
  mo.mode = mode;
  return mo;
}

}  // namespace

HandMeshScorer::HandMeshScorer(const HandMeshEvalOptions& o)
    : options_(o),
      probabilistic_(meshingOptions(o, MeshingMode::kProbabilistic)),
      binary_(meshingOptions(o, MeshingMode::kBinary)) {}

HandMeshSample HandMeshScorer::score(const psfs::ProbabilityVolume& vol,
                                     const std::vector<sim::Primitive>& person, int frame,
                                     int side, bool with_binary, TriangleMesh* probabilistic_mesh,
                                     TriangleMesh* binary_mesh) {
  const HandMeshEvalOptions& o = options_;
  sim::SurfaceSampleOptions sso;
  sso.spacing = o.spacing;
  sso.seed = static_cast<uint32_t>(o.seed);
  // The skin hull ends where the sleeve begins: that cuff face is part of what the mesh should
  // show (the box cuts are handled by the border band instead).
  sso.clothing_interface = true;
  const ProbabilityGridView g = viewOf(vol);
  const size_t min_triangles = size_t(std::max(0, o.min_component_triangles));
  HandMeshSample s;
  s.frame = frame;
  s.side = side;
  TriangleMesh pm, bm;
  auto t0 = std::chrono::steady_clock::now();
  const Eigen::Vector3f centre = g.boxCentre().cast<float>();
  const float keep_radius = float(o.keep_radius);
  probabilistic_.extract(g, &pm);
  keepHandComponents(&pm, centre, min_triangles, keep_radius);
  s.mesh_ms_probabilistic = msSince(t0);
  s.triangles_probabilistic = pm.numTriangles();
  if (with_binary) {
    t0 = std::chrono::steady_clock::now();
    binary_.extract(g, &bm);
    keepHandComponents(&bm, centre, min_triangles, keep_radius);
    s.mesh_ms_binary = msSince(t0);
    s.triangles_binary = bm.numTriangles();
  }
  const Eigen::AlignedBox3d box(vol.grid.origin, vol.grid.maxCorner());
  const Eigen::Vector3d band = Eigen::Vector3d::Constant(o.border_voxels * vol.grid.voxel_size);
  const Eigen::AlignedBox3d inner(box.min() + band, box.max() - band);
  const sim::SurfaceSamples truth = sim::sampleSkinSurface(person, box, sso);
  s.truth_area_m2 = truth.area;
  s.probabilistic = scoreMesh(pm, truth, inner);
  if (with_binary) s.binary = scoreMesh(bm, truth, inner);
  if (probabilistic_mesh) *probabilistic_mesh = std::move(pm);
  if (binary_mesh) *binary_mesh = std::move(bm);
  return s;
}

HandMeshEvalResult evaluateHandMeshes(const HandMeshEvalOptions& o) {
  validate(o);
  HandMeshScorer scorer(o);
  SimHandVolumeOptions so;
  so.scenario = o.scenario;
  so.script = o.script;
  so.frames = o.frames;
  so.every = o.every;
  so.seed = o.seed;
  so.cameras = o.cameras;
  so.skin_model = o.skin_model;
  so.hand_edge = o.hand_edge;
  so.hand_voxels = o.hand_voxels;
  so.clip_floor = o.clip_floor;
  HandMeshEvalResult r;
  std::vector<int> both_frames;
  std::vector<std::array<TriangleMesh, 4>> both_meshes;  // kept only for the picture
  visitSimHandFrames(so, [&](const SimHandFrame& frame) {
    const int f = frame.rig_frame;
    const std::vector<int>& sides = frame.sides;
    ++r.frames_scored;
    const std::vector<sim::Primitive> person = frame.rig->person(f);
    TriangleMesh meshes[2][2];  // [mode][side]
    bool meshed[2] = {false, false};
    for (size_t h = 0; h < sides.size(); ++h) {
      const int side = sides[h];
      const HandMeshSample s = scorer.score(frame.result->hands[h], person, f, side, true,
                                            &meshes[0][side], &meshes[1][side]);
      meshed[side] = !meshes[0][side].empty();
      addStats(s.probabilistic, &r.prob_mesh_to_truth, &r.prob_truth_to_mesh,
               &r.prob_p95_mesh_to_truth, &r.prob_p95_truth_to_mesh);
      addStats(s.binary, &r.bin_mesh_to_truth, &r.bin_truth_to_mesh, &r.bin_p95_mesh_to_truth,
               &r.bin_p95_truth_to_mesh);
      r.prob_triangles.add(double(s.triangles_probabilistic));
      r.bin_triangles.add(double(s.triangles_binary));
      r.prob_ms.add(s.mesh_ms_probabilistic);
      r.bin_ms.add(s.mesh_ms_binary);
      r.samples.push_back(s);
    }
    if (sides.size() == 2) {
      ++r.frames_both_hands;
      r.frames_both_meshed += meshed[0] && meshed[1];
      if (meshed[0] && meshed[1]) {
        both_frames.push_back(f);
        both_meshes.push_back({meshes[0][0], meshes[0][1], meshes[1][0], meshes[1][1]});
      }
    }
    if (o.progress) o.progress(r.frames_scored, frame.count);
  });
  if (!both_frames.empty()) {
    const size_t mid = both_frames.size() / 2;
    r.picture_frame = both_frames[mid];
    r.picture[0][0] = both_meshes[mid][0];
    r.picture[0][1] = both_meshes[mid][1];
    r.picture[1][0] = both_meshes[mid][2];
    r.picture[1][1] = both_meshes[mid][3];
  }
  return r;
}

std::string HandMeshEvalResult::summary() const {
  char buf[512];
  std::string s;
  std::snprintf(buf, sizeof(buf),
                "%d frames scored, %zu hand meshes; both hands in %d frames, both meshed in %d\n",
                frames_scored, samples.size(), frames_both_hands, frames_both_meshed);
  s += buf;
  s += "  variant        | mesh->truth mean / p95 (mm) | truth->mesh mean / p95 (mm) | triangles | ms per hand\n";
  std::snprintf(buf, sizeof(buf),
                "  probabilistic  | %6.2f / %6.2f             | %6.2f / %6.2f             | %9.0f | %.3f\n",
                prob_mesh_to_truth.mean(), prob_p95_mesh_to_truth.mean(), prob_truth_to_mesh.mean(),
                prob_p95_truth_to_mesh.mean(), prob_triangles.mean(), prob_ms.mean());
  s += buf;
  std::snprintf(buf, sizeof(buf),
                "  binary         | %6.2f / %6.2f             | %6.2f / %6.2f             | %9.0f | %.3f\n",
                bin_mesh_to_truth.mean(), bin_p95_mesh_to_truth.mean(), bin_truth_to_mesh.mean(),
                bin_p95_truth_to_mesh.mean(), bin_triangles.mean(), bin_ms.mean());
  s += buf;
  s += "  (means over hands of each hand's mean and 95th percentile; mesh->truth: vertex to the\n"
       "   nearest true-surface sample, truth->mesh: sample to the nearest mesh point)\n";
  return s;
}

}  // namespace cvephands
