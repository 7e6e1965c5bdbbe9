// Private: marks the per-pixel and per-voxel arithmetic that the CPU path and the CUDA kernels
// share (issue 20). Compiled by nvcc it is __host__ __device__, by the C++ compiler plain
// inline, so the host unit tests exercise the very code the GPU runs.
#pragma once

#if defined(__CUDACC__)
#define PSFS_HD __host__ __device__ __forceinline__
#else
#define PSFS_HD inline
#endif
