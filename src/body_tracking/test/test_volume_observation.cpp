// The PAPF's observation: the O(rows) evaluation (row prefix sums and the closed-form interval
// of each row) against a plain voxel-by-voxel loop, including parts that leave the grid and the
// trunk parts' shells, the shape of the score on a volume drawn from a known pose (its maximum
// at that pose), and what the shell is for: a trunk sunk in a larger blob scores below the one
// on the blob's trunk boundary. The CPU's rows a SIMD vector at a time (part_spans.h) give the
// reference's bytes (part_score::scorePart, which the GPU runs) on every instruction set.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>

#include "body_tracking/body_parts.h"
#include "body_tracking/volume_observation.h"
#include "drawn_body.h"
#include "part_spans.h"
#include "plain_part.h"

namespace body_tracking {
namespace {

using Eigen::Vector3d;

// The definition: weighted mean over the voxel centres inside the part, lattice extended past
// the grid reading the nearest grid voxel (clamp to edge) or the unknown likelihood; for a
// trunk cylinder (extrapolate) less shell_weight times the plain mean over the voxels inside
// the cylinder grown sideways by shell_width and not inside the part (x within the grid, rows
// outside it clamped).
double bruteForce(const psfs::VoxelGrid& g, const std::vector<float>& y, double unknown,
                  bool extrapolate, const TruncatedQuadric& part, double shell_width,
                  double shell_weight) {
  const double h = g.voxel_size;
  const Vector3d lo = (part.bounds.min() - g.origin) / h, hi = (part.bounds.max() - g.origin) / h;
  double sw = 0, swy = 0;
  for (int z = static_cast<int>(std::floor(lo.z())); z <= static_cast<int>(std::floor(hi.z())); ++z)
    for (int yy = static_cast<int>(std::floor(lo.y())); yy <= static_cast<int>(std::floor(hi.y())); ++yy)
      for (int x = static_cast<int>(std::floor(lo.x())); x <= static_cast<int>(std::floor(hi.x())); ++x) {
        const Vector3d c = g.origin + h * Vector3d(x + 0.5, yy + 0.5, z + 0.5);
        if (!part.contains(c)) continue;
        const double w = 1.0 + part.algebraic(c);
        const bool in = x >= 0 && yy >= 0 && z >= 0 && x < g.dims.x() && yy < g.dims.y() && z < g.dims.z();
        sw += w;
        if (in || extrapolate)
          swy += w * y[g.index(std::clamp(x, 0, g.dims.x() - 1), std::clamp(yy, 0, g.dims.y() - 1),
                               std::clamp(z, 0, g.dims.z() - 1))];
        else
          swy += w * unknown;
      }
  const double mean = sw > 1e-12 ? swy / sw : unknown;
  if (!extrapolate || shell_weight <= 0 || part.shape != TruncatedQuadric::Shape::CYLINDER) return mean;
  // The shell's lattice: the grown part's bounds, x within the grid, rows outside it reading
  // the nearest grid row (as the trunk's own voxels do).
  const TruncatedQuadric grown = TruncatedQuadric::cylinder(
      part.frame, part.length, part.semi.x() + shell_width, part.semi.z() + shell_width);
  const Vector3d glo = (grown.bounds.min() - g.origin) / h, ghi = (grown.bounds.max() - g.origin) / h;
  double sum = 0;
  int count = 0;
  for (int z = static_cast<int>(std::floor(glo.z())); z <= static_cast<int>(std::floor(ghi.z())); ++z)
    for (int yy = static_cast<int>(std::floor(glo.y())); yy <= static_cast<int>(std::floor(ghi.y())); ++yy)
      for (int x = std::max(0, static_cast<int>(std::floor(glo.x())));
           x <= std::min(g.dims.x() - 1, static_cast<int>(std::floor(ghi.x()))); ++x) {
        const Vector3d c = g.origin + h * Vector3d(x + 0.5, yy + 0.5, z + 0.5);
        if (!grown.contains(c) || part.contains(c)) continue;
        sum += y[g.index(x, std::clamp(yy, 0, g.dims.y() - 1), std::clamp(z, 0, g.dims.z() - 1))];
        ++count;
      }
  return count ? mean - shell_weight * sum / count : mean;
}

psfs::ProbabilityVolume randomVolume(std::mt19937* rng, const Eigen::Vector3i& dims, double h) {
  psfs::ProbabilityVolume v;
  v.grid.origin = Vector3d(-0.5, -0.5, 0.0);
  v.grid.voxel_size = h;
  v.grid.dims = dims;
  v.data.resize(v.grid.numVoxels());
  std::uniform_int_distribution<int> b(0, 255);
  for (auto& x : v.data) x = static_cast<uint8_t>(b(*rng));
  return v;
}

TEST(VolumeObservation, RowSumsMatchTheVoxelLoop) {
  std::mt19937 rng(21);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int ds : {1, 2}) {
    ObservationParams p;
    p.downsample = ds;
    p.unknown_likelihood = 0.3;
    p.trunk_shell_width = ds == 1 ? 0.03 : 0.05;
    p.trunk_shell_weight = ds == 1 ? 0.5 : 1.5;
    VolumeObservation obs(p);
    const psfs::ProbabilityVolume body = randomVolume(&rng, {64, 64, 48}, 1.0 / 64);
    obs.setVolumes(body, nullptr);
    int compared = 0;
    for (int k = 0; k < 300; ++k) {
      Eigen::Isometry3d f = Eigen::Isometry3d::Identity();
      f.linear() = Eigen::Quaterniond(u(rng), u(rng), u(rng), u(rng)).normalized().toRotationMatrix();
      // Centres up to 15 cm outside the grid, so parts cross its faces.
      f.translation() = Vector3d(0.65 * u(rng), 0.65 * u(rng), 0.375 + 0.52 * u(rng));
      const TruncatedQuadric q = k % 2
          ? TruncatedQuadric::cylinder(f, 0.3 + 0.1 * u(rng), 0.05 + 0.03 * u(rng), 0.04 + 0.02 * u(rng))
          : TruncatedQuadric::ellipsoid(f, Vector3d(0.08, 0.1, 0.12) + 0.03 * Vector3d(u(rng), u(rng), u(rng)));
      const bool ext = k % 4 < 2;
      const double fast = obs.partScore(q, false, ext);
      const double ref = bruteForce(obs.grid(), obs.bodyLikelihood(), 0.3, ext, q,
                                    p.trunk_shell_width, p.trunk_shell_weight);
      ASSERT_NEAR(fast, ref, 1e-6) << "part " << k << " downsample " << ds;
      ++compared;
    }
    EXPECT_EQ(compared, 300);
  }
}

TEST(VolumeObservation, EveryInstructionSetGivesTheReferenceBytes) {
  // Random parts across and beyond a random volume's faces: cylinders (with a shell when they
  // extrapolate, and some along the x axis, where a row's quadric is linear in x), ellipsoids,
  // thin parts that catch no voxel centre. Each compiled target's scores against the
  // reference's (part_score::scorePart, whose rows the GPU runs), bit for bit.
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  ObservationParams p;
  p.unknown_likelihood = 0.3;
  VolumeObservation obs(p);
  const psfs::ProbabilityVolume body = randomVolume(&rng, {64, 64, 48}, 1.0 / 64);
  obs.setVolumes(body, nullptr);
  const part_score::ObservationGrid g = plainGrid(obs.grid(), p.unknown_likelihood);
  const part_score::RowSumsView sums = rowSumsView(obs.rowSums(false));
  const std::vector<part_spans::Target> targets = part_spans::availableTargets();
  ASSERT_FALSE(targets.empty());
  part_spans::SpanRows rows;
  constexpr int kParts = 400, kGeneral = 300;
  int rows_seen = 0;
  // Every target's score of q against the reference's, bit for bit.
  const auto compare = [&](const part_score::PartQuadric& q, const char* what, int k) {
    const double ref = part_score::scorePart(q, g, sums);
    rows_seen += part_score::rowCount(part_score::setupPart(q, g));
    for (const part_spans::Target& target : targets) {
      const double got = part_spans::scorePart(q, g, sums, target.fn, &rows);
      EXPECT_EQ(std::memcmp(&got, &ref, sizeof got), 0)
          << target.name << ", " << what << " " << k << ": " << got << " against " << ref;
    }
  };
  for (int k = 0; k < kParts; ++k) {
    Eigen::Isometry3d f = Eigen::Isometry3d::Identity();
    if (k % 8 == 3)  // the axis along x: Q's x^2 coefficient is 0
      f.linear() = Eigen::AngleAxisd(M_PI / 2, Vector3d::UnitY()).toRotationMatrix();
    else
      f.linear() = Eigen::Quaterniond(u(rng), u(rng), u(rng), u(rng)).normalized().toRotationMatrix();
    f.translation() = Vector3d(0.65 * u(rng), 0.65 * u(rng), 0.375 + 0.52 * u(rng));
    const double thin = k % 16 == 5 ? 0.1 : 1.0;
    const TruncatedQuadric t = k % 2
        ? TruncatedQuadric::cylinder(f, 0.3 + 0.1 * u(rng), thin * (0.05 + 0.03 * u(rng)), 0.04 + 0.02 * u(rng))
        : TruncatedQuadric::ellipsoid(f, thin * (Vector3d(0.08, 0.1, 0.12) + 0.03 * Vector3d(u(rng), u(rng), u(rng))));
    compare(plainPart(t, false, k % 4 < 2, p), "part", k);
  }
  // Quadrics no body part makes, for the branches body parts barely reach: random symmetric Q
  // (ellipsoid-like, hyperboloid-like) and Q with no x^2 term (v^T Q v linear along a row: its
  // rising, falling and flat clips), random planes, over a random box.
  for (int k = 0; k < kGeneral; ++k) {
    part_score::PartQuadric q{};
    for (int i = 0; i < 4; ++i)
      for (int j = i; j < 4; ++j) q.Q[4 * j + i] = q.Q[4 * i + j] = (i == j && i < 3 ? 40.0 : 10.0) * u(rng);
    if (k % 3 == 0) q.Q[0] = 0.0;
    q.Q[15] = -1.0 + 0.5 * u(rng);
    q.num_planes = k % 3;
    for (int p = 0; p < 2; ++p)
      for (int i = 0; i < 4; ++i) q.planes[p][i] = p < q.num_planes ? (i == 3 ? 0.3 : 1.0) * u(rng) : 0.0;
    for (int i = 0; i < 3; ++i) {
      const double c = (i == 2 ? 0.375 : 0.0) + 0.6 * u(rng), e = 0.05 + 0.15 * std::abs(u(rng));
      q.lo[i] = c - e;
      q.hi[i] = c + e;
    }
    q.extrapolate = k % 2;
    q.shell_weight = k % 4 == 1 ? 0.5 : 0.0;
    for (int i = 0; i < 16; ++i) q.shell_Q[i] = 0.8 * q.Q[i];
    q.shell_Q[15] = q.Q[15];
    compare(q, "general quadric", k);
  }
  EXPECT_GT(rows_seen, kParts * 20) << "the parts should cover many rows";
  std::printf("compared %d parts and %d general quadrics (%d rows) on %zu targets:", kParts, kGeneral,
              rows_seen, targets.size());
  for (const part_spans::Target& target : targets) std::printf(" %s", target.name);
  std::printf("\n");
}

TEST(VolumeObservation, ScorePeaksAtThePoseTheVolumeWasDrawnFrom) {
  // A volume that is 1 inside the model at a known pose and 0 elsewhere: every part inside the
  // grid scores 1, and moving a joint lowers the sum.
  const BodyProfile profile;
  BodyState s{};
  s[dof::TORSO_Y] = -0.40;
  s[dof::TORSO_Z] = -0.12;
  s[dof::SPINE_BEND] = 0.1;
  for (Side side : {Side::LEFT, Side::RIGHT}) {
    s[armDof(side, 0)] = -1.2;
    s[armDof(side, 1)] = side == Side::LEFT ? 0.3 : -0.3;
    s[armDof(side, 3)] = 1.3;
  }
  const BodyParts parts = buildParts(profile, s);
  const psfs::ProbabilityVolume body = test::drawnVolume(parts);
  ObservationParams op;
  op.downsample = 1;
  VolumeObservation obs(op);
  obs.setVolumes(body, &body);
  std::array<double, kNumParts> per;
  const double best = obs.score(parts, &per);
  for (int i = 0; i < kNumParts; ++i) {
    const TruncatedQuadric& q = parts[i];
    const bool inside = q.bounds.min().z() > 0.01 && q.bounds.min().y() > -0.49;
    if (inside) {
      EXPECT_NEAR(per[i], 1.0, 1e-9) << partName(static_cast<Part>(i));
    }
  }
  for (int j : {dof::TORSO_X, dof::L_SWING_1, dof::L_SWING_2, dof::L_FLEX, dof::R_SWING_1,
                dof::R_FLEX, dof::HEAD_YAW}) {
    for (double step : {-0.15, 0.15}) {
      BodyState t = s;
      t[j] += step;
      EXPECT_LT(obs.score(buildParts(profile, t)), best - 0.02) << dofName(j) << " " << step;
    }
  }
}

TEST(VolumeObservation, WithItsShellATrunkSunkInALargerBlobScoresBelowTheOneOnItsBoundary) {
  // The person's trunk: an upright elliptic cylinder (15 x 10 cm half axes, the profile's
  // abdomen) in the middle of the grid, and in front of it a 6 cm slab of occupied voxels as
  // wide as the trunk (forearms and halo in front of the belly). A model trunk of the same size
  // 3 cm further forward, still inside the occupied blob, reads ~1 inside just as the true one
  // does, or better: the mean alone cannot choose (the trunk wandered so in test_papf_sim). With the shell,
  // the true trunk's shell is empty behind and beside it, the forward one's shell reads the
  // trunk's own back: the true pose wins by about the weight times the occupied share it adds.
  psfs::ProbabilityVolume body;
  body.grid.origin = Vector3d(-0.5, -0.5, 0.0);
  body.grid.voxel_size = 1.0 / 64;
  body.grid.dims = Eigen::Vector3i(64, 64, 48);
  body.data.assign(body.grid.numVoxels(), 0);
  const Eigen::Isometry3d up(Eigen::AngleAxisd(M_PI / 2, Vector3d::UnitX()));
  const auto trunkAt = [&](double y) {
    return TruncatedQuadric::cylinder(Eigen::Translation3d(0, y, 0.1) * up, 0.4, 0.15, 0.10);
  };
  const TruncatedQuadric truth = trunkAt(0.0), forward = trunkAt(-0.03);
  for (size_t i = 0; i < body.data.size(); ++i) {
    const Vector3d c = body.grid.centre(i);
    const bool slab = std::abs(c.x()) < 0.15 && c.y() < 0.0 && c.y() > -0.16 && c.z() > 0.1 && c.z() < 0.5;
    if (truth.contains(c) || slab) body.data[i] = 255;
  }
  for (int ds : {1, 2}) {
    ObservationParams without;
    without.downsample = ds;
    without.trunk_shell_weight = 0.0;
    VolumeObservation plain(without);
    plain.setVolumes(body, nullptr);
    // The mean alone does not prefer the truth (at 31 mm voxels it prefers the sunk trunk:
    // the true boundary's voxels are partly empty).
    EXPECT_GE(plain.partScore(forward, false, true), plain.partScore(truth, false, true) - 0.01)
        << "downsample " << ds;
    ObservationParams with = without;
    with.trunk_shell_weight = 0.5;
    with.trunk_shell_width = 0.03;
    VolumeObservation shell(with);
    shell.setVolumes(body, nullptr);
    EXPECT_GT(shell.partScore(truth, false, true), shell.partScore(forward, false, true) + 0.05)
        << "downsample " << ds;
    // Limbs and the head have no shell.
    EXPECT_EQ(shell.partScore(truth, false, false), plain.partScore(truth, false, false));
    // partMean (what judges a lost track) is the mean alone, the shell's term left out.
    EXPECT_EQ(shell.partMean(truth, false, true), plain.partScore(truth, false, true));
    EXPECT_EQ(shell.partMean(forward, false, true), plain.partScore(forward, false, true));
    EXPECT_LT(shell.partScore(truth, false, true), shell.partMean(truth, false, true));
  }
}

TEST(VolumeObservation, RejectsMismatchedVolumes) {
  std::mt19937 rng(1);
  const psfs::ProbabilityVolume a = randomVolume(&rng, {16, 16, 12}, 1.0 / 16);
  psfs::ProbabilityVolume b = randomVolume(&rng, {16, 16, 8}, 1.0 / 16);
  VolumeObservation obs;
  EXPECT_THROW(obs.setVolumes(a, &b), std::invalid_argument);
  b = a;
  b.data.pop_back();
  EXPECT_THROW(obs.setVolumes(b, nullptr), std::invalid_argument);
  ObservationParams bad;
  bad.downsample = 0;
  EXPECT_THROW(VolumeObservation{bad}, std::invalid_argument);
  ObservationParams no_shell;
  no_shell.trunk_shell_width = 0.0;
  EXPECT_THROW(VolumeObservation{no_shell}, std::invalid_argument);
  no_shell.trunk_shell_width = 0.03;
  no_shell.trunk_shell_weight = -1.0;
  EXPECT_THROW(VolumeObservation{no_shell}, std::invalid_argument);
}

}  // namespace
}  // namespace body_tracking
