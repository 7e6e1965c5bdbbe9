#include <gtest/gtest.h>

#include "tabletop_capture/camera_model.h"
#include "tabletop_capture/sim/default_rig.h"

using namespace tabletop_capture;

TEST(CameraModel, DefaultRigRoundTrip) {
  const RigDescription rig = sim::makeDefaultRig();
  ASSERT_EQ(rig.cameras.size(), 8u);
  for (const auto& cam : rig.cameras) {
    const Eigen::Vector3d p(0.1, -0.1, 0.3);
    Eigen::Vector2d px;
    ASSERT_TRUE(cam.projectWorld(p, &px));
    const Eigen::Vector3d ray = cam.rayWorld(px);
    const Eigen::Vector3d expected = (p - cam.center()).normalized();
    EXPECT_LT((ray - expected).norm(), 1e-9) << cam.name;
  }
}
