// Which kernels fusion runs. The hot loops exist twice: AVX2 (gathers, 8 voxels per step) and
// portable scalar code doing the same integer/float operations in the same order, so both give
// identical bytes. The AVX2 copies are compiled with function-level target attributes and
// chosen at run time, so the package needs no -march flag and still runs on any x86-64 (or
// other) CPU.
#pragma once

namespace psfs {

// True if the CPU supports AVX2 (and this build has the AVX2 kernels).
bool avx2Available();
// Forces the scalar kernels (tests compare both; benchmarks report both). Not thread-safe:
// call it while no fusion runs.
void forceScalarKernels(bool force);
// True if the AVX2 kernels are used now.
bool vectorKernelsActive();

}  // namespace psfs
