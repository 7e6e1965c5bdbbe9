// Fusion on the simulated rig: 8 distorted 320x240 cameras around a seated, waving person.
// Likelihood images come from the renderer's person and skin masks (the real pixel classifier
// is tested elsewhere), clean and with classifier-like noise, both bounded by the outlier
// model (test::classifierLikelihood). Volumes are compared with the occupancy oracle at the
// voxel centres. Body volumes use the defaults; skin volumes tolerate one occluded view
// (k = 1): the skin masks show *visible* skin, and a hand or the face is hidden from some
// camera in most frames, which an AND over views cannot survive.
#include <gtest/gtest.h>

#include <cstdio>
#include <map>

#include "fusion_test_utils.h"
#include "psfs_reconstruction/binary_sfs.h"
#include "psfs_reconstruction/psfs_fusion.h"
#include "tabletop_sim/simulated_rig.h"

namespace psfs {
namespace {

namespace sim = tabletop_sim;

struct Truth {
  std::vector<uint8_t> person, skin;
};

Truth oracleVolumes(const sim::Oracle& oracle, const VoxelGrid& g) {
  Truth t;
  oracle.sampleGrid(g.origin, g.voxel_size, g.dims, &t.person, &t.skin);
  return t;
}

// CV_8UC2 likelihood images as the classifier delivers them: channel 0 body, 1 skin.
cv::Mat likelihoods(const cv::Mat& person, const cv::Mat& skin, bool noise, uint32_t seed) {
  cv::Mat out;
  cv::merge(std::vector<cv::Mat>{test::classifierLikelihood(person, noise, seed),
                                 test::classifierLikelihood(skin, noise, seed + 7919)},
            out);
  return out;
}

TEST(FusionSim, VolumesAgainstTheOccupancyOracle) {
  sim::SimOptions so;
  so.script = "wave";
  so.empty_frames = 0;
  so.render_masks = true;
  so.short_sleeves = true;  // forearms are skin too: larger skin volumes
  sim::SimulatedRig rig(so);
  const int n = rig.scriptFrames();
  const std::vector<int> frames = {n / 5, n / 2, 4 * n / 5};

  struct Config {
    Resolution res;
    bool multi;
    std::unique_ptr<ProjectionTable> table;
  };
  std::vector<Config> configs;
  configs.push_back({Resolution::k16mm, true, nullptr});
  configs.push_back({Resolution::k8mm, false, nullptr});
  for (auto& c : configs) {
    ProjectionTableOptions to;
    to.multi_projection = c.multi;
    c.table = std::make_unique<ProjectionTable>(referenceGrid(c.res), rig.rig().cameras, to);
  }
  // Sums over frames of IoU, per (resolution, class, noise, method).
  std::map<std::string, double> sum;
  for (int f : frames) {
    const sim::SimFrame fr = rig.render(f);
    ASSERT_TRUE(fr.truth.person_present);
    const sim::Oracle oracle = rig.oracle(f);
    for (bool noise : {false, true}) {
      std::vector<ViewImage> body, skin;
      for (size_t c = 0; c < fr.person_masks.size(); ++c) {
        const cv::Mat l = likelihoods(fr.person_masks[c], fr.skin_masks[c], noise, 1000 * f + c);
        body.push_back(ViewImage{l, 0, cv::Mat()});
        skin.push_back(ViewImage{l, 1, cv::Mat()});
      }
      for (auto& cfg : configs) {
        const Truth truth = oracleVolumes(oracle, cfg.table->grid());
        for (int cls = 0; cls < 2; ++cls) {
          ViewEvidence ev;
          ev.set(cls == 0 ? body : skin, cfg.multi);
          PsfsOptions o;
          o.multi_projection = cfg.multi;
          o.occluded_views = cls == 1 ? 1 : 0;
          ProbabilityVolume p, b;
          PsfsFusion(o).fuse(*cfg.table, ev, &p);
          BinarySfs().fuse(*cfg.table, ev, &b);
          const auto& t = cls == 0 ? truth.person : truth.skin;
          const std::string key = std::string(cfg.res == Resolution::k16mm ? "16mm" : " 8mm") +
                                  (cls == 0 ? " body" : " skin") + (noise ? " noisy" : " clean");
          sum[key + " pSfS"] += test::occupancyIoU(p, thresholdByte(o.threshold), t);
          sum[key + " binary"] += test::occupancyIoU(b, 0, t);
        }
      }
    }
  }
  std::printf("simulated rig, 'wave' frames %d %d %d, mean IoU vs oracle (pSfS t = 0.75, skin k = 1 | binary SfS at 0.5):\n",
              frames[0], frames[1], frames[2]);
  const double k = 1.0 / frames.size();
  for (const char* res : {"16mm", " 8mm"})
    for (const char* cls : {" body", " skin"})
      for (const char* noise : {" clean", " noisy"}) {
        const std::string key = std::string(res) + cls + noise;
        std::printf("  %s%s%s: pSfS %.4f | binary %.4f\n", res, cls, noise, k * sum[key + " pSfS"],
                    k * sum[key + " binary"]);
      }
  for (const char* res : {"16mm", " 8mm"}) {
    const std::string body = std::string(res) + " body";
    // A visual hull from 8 views is larger than the person (concavities, the space between
    // arm and torso): binary SfS on clean masks scores ~0.86 here. 0.75 leaves room for the
    // multi-projection's partial-voxel decisions and flags anything broken.
    EXPECT_GT(k * sum[body + " clean pSfS"], 0.75) << res;
    EXPECT_GE(k * sum[body + " noisy pSfS"], k * sum[body + " noisy binary"]) << res;
    const std::string skin = std::string(res) + " skin";
    EXPECT_GE(k * sum[skin + " noisy pSfS"], k * sum[skin + " noisy binary"]) << res;
  }
}

}  // namespace
}  // namespace psfs
