// Private: marks the per-part score arithmetic that the CPU observation and the CUDA kernels
// share (issue 20; psfs_reconstruction's PSFS_HD, which is private to that package). Compiled
// by nvcc it is __host__ __device__, by the C++ compiler plain inline, so the host unit tests
// exercise the very code the GPU runs.
#pragma once

#if defined(__CUDACC__)
#define BT_HD __host__ __device__ __forceinline__
#else
#define BT_HD inline
#endif
