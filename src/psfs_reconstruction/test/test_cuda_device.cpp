// The CUDA backend's device probe: it never throws, says why a device is unusable, and
// describes a usable one well enough for a benchmark report.
#include <gtest/gtest.h>

#include <cstdio>

#include "psfs_reconstruction/cuda_device.h"

TEST(CudaDevice, ProbeReportsUsableDeviceOrReason) {
  const psfs::cuda::DeviceInfo& d = psfs::cuda::device();
  std::printf("[ device   ] compiled in: %s; %s\n", psfs::cuda::compiledIn() ? "yes" : "no",
              d.describe().c_str());
  EXPECT_EQ(&d, &psfs::cuda::device()) << "probed once";
  if (!psfs::cuda::compiledIn()) {
    EXPECT_FALSE(d.usable);
    EXPECT_NE(d.reason.find("no CUDA backend"), std::string::npos) << d.reason;
  }
  if (!d.usable) {
    EXPECT_FALSE(d.reason.empty());
    EXPECT_NE(d.describe().find(d.reason), std::string::npos);
    return;
  }
  EXPECT_TRUE(d.reason.empty());
  EXPECT_FALSE(d.name.empty());
  EXPECT_GE(d.compute_major * 10 + d.compute_minor, 75);
  EXPECT_GT(d.memory_bytes, size_t(1) << 30);
  EXPECT_GT(d.memory_bandwidth_gbs, 50.0);
  EXPECT_GT(d.runtime_version, 0);
}
