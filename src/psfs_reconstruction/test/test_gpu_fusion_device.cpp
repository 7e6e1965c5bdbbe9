// GpuPsfsFusion on a CUDA device against PsfsFusion: identical bytes in every case of
// gpu_fusion_cases.h, with host evidence and with evidence already on the device
// (GpuEvidenceBuffer), and no device allocation after the first frame while a hand sub-volume
// moves every frame. Skips, saying why, without a usable device (PSFS_REQUIRE_GPU).
#include <gtest/gtest.h>

#include <cstdio>

#include "gpu_fusion_cases.h"
#include "gpu_test_support.h"
#include "psfs_reconstruction/gpu_psfs_fusion.h"

namespace psfs {
namespace {

using gpu_test::FusionCase;
using gpu_test::SimScene;

size_t firstDifference(const std::vector<uint8_t>& a, const std::vector<uint8_t>& b) {
  for (size_t i = 0; i < a.size() && i < b.size(); ++i)
    if (a[i] != b[i]) return i;
  return a.size() == b.size() ? a.size() : std::min(a.size(), b.size());
}

TEST(GpuPsfsFusionDevice, GivesPsfsFusionBytes) {
  PSFS_REQUIRE_GPU();
  for (int frame : {40, 120}) {
    const SimScene scene = gpu_test::simScene(frame, true);
    for (const FusionCase& fc : gpu_test::fusionCases(scene)) {
      const auto table = fc.table(scene);
      const ViewEvidence ev = fc.evidence(scene);
      ProbabilityVolume cpu, gpu, gpu_dev;
      PsfsFusion(fc.options).fuse(*table, ev, &cpu);
      GpuPsfsFusion fusion(fc.options);
      fusion.fuse(*table, ev, &gpu);
      ASSERT_EQ(gpu.grid, cpu.grid) << fc.name;
      ASSERT_TRUE(gpu.data == cpu.data) << fc.name << ", frame " << frame << ": first difference at voxel "
                                        << firstDifference(gpu.data, cpu.data);
      GpuEvidenceBuffer buffer;
      buffer.upload(ev);
      fusion.fuse(*table, buffer.views(), &gpu_dev);
      ASSERT_TRUE(gpu_dev.data == cpu.data) << fc.name << ", frame " << frame << ", device evidence";
      const GpuFusionTimings& t = fusion.lastTimings();
      std::printf("[ figures  ] frame %d, %-70s upload %.3f project %.3f fuse %.3f readback %.3f ms\n", frame,
                  fc.name.c_str(), t.upload_ms, t.project_ms, t.fuse_ms, t.readback_ms);
    }
  }
}

// Frames 2..10 of a tracking volume (stored table) and a hand sub-volume that follows the hand
// (a new on-the-fly table every frame, projected on the device) allocate nothing.
TEST(GpuPsfsFusionDevice, NoDeviceAllocationAfterTheFirstFrame) {
  PSFS_REQUIRE_GPU();
  PsfsOptions body_o;
  body_o.multi_projection = true;
  PsfsOptions hand_o;
  hand_o.occluded_views = 1;
  GpuPsfsFusion body(body_o), hand(hand_o);
  GpuEvidenceBuffer skin_on_device;
  ProjectionTableOptions bt;
  bt.multi_projection = true;
  const SimScene first = gpu_test::simScene(30, false);
  const ProjectionTable body_table(referenceGrid(Resolution::k16mm), first.cameras, bt);
  ProjectionTableOptions ht;
  ht.storage = TableStorage::kOnTheFly;
  ProjectionTable hand_table(snappedCubeGrid(first.right_hand, 0.30, 83), first.cameras, ht);
  size_t after_first[3] = {0, 0, 0};
  int moved = 0;
  for (int f = 1; f <= 10; ++f) {
    const SimScene s = gpu_test::simScene(30 + 4 * f, f % 3 == 0);
    moved += hand_table.update(snappedCubeGrid(s.right_hand, 0.30, 83), s.cameras);
    ViewEvidence body_ev, skin_ev;
    body_ev.set(s.views(0), true);
    skin_ev.set(s.views(1), false);
    ProbabilityVolume b, h, h_dev, b_cpu, h_cpu;
    body.fuse(body_table, body_ev, &b);
    hand.fuse(hand_table, skin_ev, &h);
    skin_on_device.upload(skin_ev);
    hand.fuse(hand_table, skin_on_device.views(), &h_dev);
    PsfsFusion(body_o).fuse(body_table, body_ev, &b_cpu);
    PsfsFusion(hand_o).fuse(hand_table, skin_ev, &h_cpu);
    ASSERT_TRUE(b.data == b_cpu.data) << "frame " << f << ", tracking volume";
    ASSERT_TRUE(h.data == h_cpu.data) << "frame " << f << ", hand sub-volume";
    ASSERT_TRUE(h_dev.data == h_cpu.data) << "frame " << f << ", hand sub-volume, device evidence";
    const size_t now[3] = {body.deviceAllocations(), hand.deviceAllocations(), skin_on_device.deviceAllocations()};
    if (f == 1) {
      for (int i = 0; i < 3; ++i) after_first[i] = now[i];
      EXPECT_GT(now[0], 0u);
      continue;
    }
    EXPECT_EQ(now[0], after_first[0]) << "frame " << f << ": tracking volume allocated";
    EXPECT_EQ(now[1], after_first[1]) << "frame " << f << ": hand sub-volume allocated";
    EXPECT_EQ(now[2], after_first[2]) << "frame " << f << ": evidence buffer allocated";
  }
  EXPECT_GE(moved, 3) << "the hand sub-volume must move for the test to mean something";
  std::printf("[ figures  ] allocations after frame 1: tracking %zu, hand %zu, evidence %zu; hand moved %d times\n",
              after_first[0], after_first[1], after_first[2], moved);
}

}  // namespace
}  // namespace psfs
