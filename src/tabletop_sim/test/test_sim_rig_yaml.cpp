// The committed config/sim_rig.yaml documents the rig format and must stay identical to the
// simulated rig's built-in layout (the simulator and the YAML-driven tools must agree).
#include <gtest/gtest.h>

#include "tabletop_capture/rig_description.h"
#include "tabletop_capture/default_rig.h"

using namespace tabletop_capture;

TEST(SimRigYaml, CommittedFileEqualsBuiltInRig) {
  const RigDescription file = loadRigYaml(TABLETOP_SIM_CONFIG_DIR "/sim_rig.yaml");
  const RigDescription built = tabletop_capture::makeDefaultRig();
  ASSERT_EQ(file.cameras.size(), built.cameras.size());
  EXPECT_EQ(file.world_frame, "world");
  for (size_t i = 0; i < built.cameras.size(); ++i) {
    const CameraModel& a = file.cameras[i];
    const CameraModel& b = built.cameras[i];
    EXPECT_EQ(a.name, b.name);
    EXPECT_EQ(a.frame_id, b.frame_id);
    EXPECT_EQ(a.width, b.width);
    EXPECT_EQ(a.height, b.height);
    EXPECT_NEAR(a.fx, b.fx, 1e-9);
    EXPECT_NEAR(a.fy, b.fy, 1e-9);
    EXPECT_NEAR(a.cx, b.cx, 1e-9);
    EXPECT_NEAR(a.cy, b.cy, 1e-9);
    for (int k = 0; k < 5; ++k) EXPECT_NEAR(a.distortion[k], b.distortion[k], 1e-12);
    EXPECT_LT((a.world_T_camera.matrix() - b.world_T_camera.matrix()).cwiseAbs().maxCoeff(), 1e-12)
        << a.name << ": regenerate with `rosrun tabletop_capture write_default_rig` (see the file)";
  }
}
