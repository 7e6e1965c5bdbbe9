// The GPU particle weights (gpu_particle_weights.h) against the CPU path, Papf::scoreState, on
// particle sets of a tracked simulated-rig scene (reach_targets, short sleeves, reconstructed
// by psfs::Reconstructor): the host emulation of the kernels in every build, the kernels
// themselves where a device is usable (they skip, saying why, elsewhere). Scores must be the
// same doubles, bit for bit: the kernels add in the CPU's order and round as it does.
#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <set>

#include "body_tracking/gpu_particle_weights.h"
#include "body_tracking/papf.h"
#include "body_tracking/part_collision.h"
#include "gpu_test_support.h"
#include "psfs_reconstruction/gaussian_mixture.h"
#include "psfs_reconstruction/reconstructor.h"
#include "tabletop_sim/simulated_rig.h"

namespace body_tracking {
namespace {

namespace sim = tabletop_sim;

// Three reconstructed frames mid-reach, a tracker started on the first and run on the second,
// and two particle sets around its estimate: the tracker's own 256 and 4096 spread widely (so
// that poses collide and parts leave the grid).
struct Scene {
  std::vector<psfs::ProbabilityVolume> body, skin;
  PapfParams params;
  std::unique_ptr<Papf> papf;
  std::vector<BodyState> tracked, wide;

  Scene() {
    constexpr int kLearn = 25, kFirst = kLearn + 60;
    sim::SimOptions o;
    o.script = "reach_targets";
    o.short_sleeves = true;
    o.empty_frames = kLearn;
    sim::SimulatedRig rig(o);
    psfs::ReconstructorParams rp;
    rp.threads = 2;
    psfs::Reconstructor rec(psfs::GaussianMixture2D::load(BODY_TRACKING_SKIN_MODEL), rp);
    for (int f = 0; f < kLearn; ++f) rec.process(rig.render(f).images, rig.rig().cameras);
    for (int f = kFirst; f < kFirst + 15; f += 5) {
      psfs::FrameResult r = rec.process(rig.render(f).images, rig.rig().cameras);
      body.push_back(std::move(r.body));
      skin.push_back(std::move(r.skin));
    }
    papf = std::make_unique<Papf>(BodyProfile(), params);
    papf->update(body[0], &skin[0]);
    papf->update(body[1], &skin[1]);
    tracked = papf->particles();
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const BodyState centre = papf->estimate().state;
    wide.resize(4096);
    for (BodyState& s : wide) {
      s = centre;
      for (int j = dof::TORSO_X; j <= dof::TORSO_Z; ++j) s[j] += 0.15 * u(rng);
      for (int j = dof::TORSO_ROLL; j <= dof::HEAD_YAW; ++j) s[j] += 0.3 * u(rng);
      for (int j = dof::L_SWING_1; j < dof::COUNT; ++j) s[j] += 1.5 * u(rng);
      papf->limits().enforce(&s);
    }
  }
};

const Scene& scene() {
  static const Scene s;
  return s;
}

// Particles whose scores differ from the CPU's in any bit.
int mismatches(const std::vector<double>& scores, const Papf& papf,
               const std::vector<BodyState>& particles, int partition) {
  int bad = 0;
  for (size_t i = 0; i < particles.size(); ++i) {
    const double cpu = papf.scoreState(particles[i], partition);
    if (std::memcmp(&cpu, &scores[i], sizeof(double)) != 0) ++bad;
  }
  return bad;
}

TEST(GpuParticleWeights, HostEmulationEqualsTheCpuScoresBitForBit) {
  const Scene& sc = scene();
  const Papf& papf = *sc.papf;
  const psfs::VoxelGrid& g = papf.observation().grid();
  const Eigen::AlignedBox3d grid_box(g.origin, g.origin + g.voxel_size * g.dims.cast<double>());
  for (const std::vector<BodyState>* set : {&sc.tracked, &sc.wide}) {
    // The set covers what the arithmetic branches on: self-collisions (score 0), trunks that
    // cross the grid's faces (clamped rows), head or limbs that do (the unknown likelihood).
    int colliding = 0, trunk_out = 0, limb_out = 0;
    for (const BodyState& s : *set) {
      const BodyFrames f = forwardKinematics(papf.profile(), s);
      const BodyParts parts = buildParts(papf.profile(), f);
      colliding += bodyCollides(papf.profile(), f, parts);
      bool trunk = false, limb = false;
      for (int p = 0; p < kNumParts; ++p)
        if (!grid_box.contains(parts[p].bounds)) (isTrunkPart(static_cast<Part>(p)) ? trunk : limb) = true;
      trunk_out += trunk;
      limb_out += limb;
    }
    const int n = static_cast<int>(set->size());
    std::printf("[ set      ] %d particles: %d self-colliding, %d with the trunk and %d with the head "
                "or a limb crossing the grid's faces\n", n, colliding, trunk_out, limb_out);
    EXPECT_GT(trunk_out, 0);
    if (set == &sc.wide) {
      EXPECT_GT(colliding, 0);
      EXPECT_GT(limb_out, 0);
    }
    for (int partition = -1; partition < Papf::kPartitions; ++partition) {
      std::vector<double> one, two;
      emulateGpuParticleWeights(papf.observation(), papf.profile(), *set, partition, 1, &one);
      emulateGpuParticleWeights(papf.observation(), papf.profile(), *set, partition, 2, &two);
      ASSERT_EQ(one.size(), set->size());
      EXPECT_EQ(one, two) << "the thread count changed the scores";
      EXPECT_EQ(mismatches(one, papf, *set, partition), 0) << n << " particles, partition " << partition;
      // The tracker's set holds many copies (resampling), most of all of the trunk.
      EXPECT_GT(std::set<double>(one.begin(), one.end()).size(), set == &sc.wide ? set->size() / 2 : 8u)
          << "too few distinct scores to mean anything";
    }
  }
}

TEST(GpuParticleWeights, WithoutADeviceItSaysWhyAndPapfScoresOnTheCpu) {
  const Scene& sc = scene();
  GpuParticleWeights w;
  if (!w.usable()) {
    EXPECT_FALSE(w.reason().empty());
    EXPECT_EQ(w.deviceAllocations(), 0u);
    EXPECT_THROW(w.setObservation(sc.papf->observation()), std::logic_error);
  } else {
    EXPECT_TRUE(w.reason().empty());
  }
  // Papf with gpu_weights: the same estimates and weights as without, on the GPU or not.
  PapfParams gp = sc.params;
  gp.gpu_weights = true;
  Papf cpu(BodyProfile(), sc.params), gpu(BodyProfile(), gp);
  EXPECT_EQ(gpu.gpuWeightsActive(), w.usable());
  if (w.usable()) {
    EXPECT_TRUE(gpu.gpuWarning().empty()) << gpu.gpuWarning();
  } else {
    EXPECT_NE(gpu.gpuWarning().find(w.reason()), std::string::npos) << gpu.gpuWarning();
  }
  EXPECT_TRUE(cpu.gpuWarning().empty());
  for (size_t k = 0; k < sc.body.size(); ++k) {
    const BodyEstimate& a = cpu.update(sc.body[k], &sc.skin[k]);
    const BodyEstimate& b = gpu.update(sc.body[k], &sc.skin[k]);
    EXPECT_EQ(a.state, b.state) << "frame " << k;
    EXPECT_EQ(a.score, b.score) << "frame " << k;
    EXPECT_EQ(cpu.weights(), gpu.weights()) << "frame " << k;
  }
  EXPECT_EQ(gpu.gpuWeightsActive(), w.usable()) << gpu.gpuWarning();
}

TEST(GpuParticleWeights, GpuScoresEqualTheCpuScoresBitForBit) {
  BODY_REQUIRE_GPU();
  const Scene& sc = scene();
  const Papf& papf = *sc.papf;
  GpuParticleWeights w;
  ASSERT_TRUE(w.usable()) << w.reason();
  std::vector<double> early;
  EXPECT_THROW(w.score(papf.profile(), sc.tracked, 0, 2, &early), std::logic_error)
      << "scoring before an observation";
  w.setObservation(papf.observation());
  for (const std::vector<BodyState>* set : {&sc.tracked, &sc.wide})
    for (int partition = -1; partition < Papf::kPartitions; ++partition) {
      std::vector<double> gpu, emulated;
      w.score(papf.profile(), *set, partition, 2, &gpu);
      emulateGpuParticleWeights(papf.observation(), papf.profile(), *set, partition, 2, &emulated);
      ASSERT_EQ(gpu.size(), set->size());
      EXPECT_EQ(mismatches(gpu, papf, *set, partition), 0)
          << set->size() << " particles, partition " << partition;
      EXPECT_EQ(gpu, emulated);
    }
}

TEST(GpuParticleWeights, NoDeviceAllocationPerFrame) {
  BODY_REQUIRE_GPU();
  const Scene& sc = scene();
  GpuParticleWeights w;
  ASSERT_TRUE(w.usable()) << w.reason();
  size_t after_first = 0;
  for (size_t k = 0; k < sc.body.size(); ++k) {
    VolumeObservation obs(sc.params.observation);
    obs.setVolumes(sc.body[k], &sc.skin[k]);
    w.setObservation(obs);
    for (int partition = 0; partition < Papf::kPartitions; ++partition) {
      std::vector<double> gpu, emulated;
      w.score(sc.papf->profile(), sc.tracked, partition, 2, &gpu);
      emulateGpuParticleWeights(obs, sc.papf->profile(), sc.tracked, partition, 2, &emulated);
      EXPECT_EQ(gpu, emulated) << "frame " << k << ", partition " << partition;
    }
    if (k == 0) after_first = w.deviceAllocations();
  }
  EXPECT_GT(after_first, 0u);
  EXPECT_EQ(w.deviceAllocations(), after_first) << "buffers were allocated again for same-size frames";
}

}  // namespace
}  // namespace body_tracking
