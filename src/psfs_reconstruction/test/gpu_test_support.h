// GPU tests skip, saying why, where the CUDA backend is not compiled in or no device is usable.
#pragma once

#include <gtest/gtest.h>

#include "psfs_reconstruction/cuda_device.h"

#define PSFS_REQUIRE_GPU()                                                              \
  do {                                                                                  \
    if (!psfs::cuda::device().usable)                                                   \
      GTEST_SKIP() << "GPU test skipped: " << psfs::cuda::device().describe();          \
  } while (0)
