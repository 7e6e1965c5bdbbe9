// Which kernels fusion runs. The pSfS row loop exists three times: AVX-512 (16 voxels per step,
// where the CPU has AVX-512 F+BW), AVX2 (gathers, 8 voxels per step) and portable scalar code,
// all doing the same integer/float operations in the same order, so all give identical bytes. The AVX2 copies are compiled with function-level target attributes and
// chosen at run time, so the package needs no -march flag and still runs on any x86-64 (or
// other) CPU.
#pragma once

// The environment variable TABLETOP_SIMD=avx2 (or =scalar) makes a process start with the AVX2
// (or scalar) kernels: the suite and the demo then run as on a machine without AVX-512.
namespace psfs {

// True if the CPU supports AVX2 (and this build has the AVX2 kernels).
bool avx2Available();
// Forces the scalar kernels (tests compare both; benchmarks report both). Not thread-safe:
// call it while no fusion runs.
void forceScalarKernels(bool force);
// True if the AVX2 kernels are used now.
bool vectorKernelsActive();
// True if the CPU supports AVX-512 F and BW (and this build has those kernels).
bool avx512Available();
// Limits the vector kernels to AVX2 even where AVX-512 exists (tests compare all paths).
// Not thread-safe: call it while no fusion runs.
void forceAvx2Kernels(bool force);
// True if the pSfS kernels use AVX-512 now.
bool avx512KernelsActive();

}  // namespace psfs
