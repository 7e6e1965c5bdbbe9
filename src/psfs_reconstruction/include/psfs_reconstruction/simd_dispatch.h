// Which kernels fusion runs. All kernels of one kind do the same integer and float operations
// in the same order, so all give identical bytes:
//  * the single-projection row kernel (also footprint levels and hand sub-volumes) is one Google
//    Highway source, dispatched at run time to the best target the CPU has (AVX-512, AVX2, SSE4
//    on x86; NEON on ARM), or to Highway's portable target when the scalar kernels are forced;
//  * the multi-projection (face) kernel is one Highway source too, dispatched the same way.
// Highway compiles each target's copy with function-level target attributes, so the package
// needs no -march flag and still runs on any x86-64 (or other) CPU.
#pragma once

#include <cstddef>
#include <cstdint>

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
// True if the portable (scalar) kernels are forced (forceScalarKernels, TABLETOP_SIMD=scalar):
// without it the Highway kernels take the CPU's best target, AVX2 or not.
bool scalarKernelsForced();
// True if the CPU supports AVX-512 F and BW (and this build has those kernels).
bool avx512Available();
// Limits the vector kernels to AVX2 even where AVX-512 exists (tests compare all paths).
// Not thread-safe: call it while no fusion runs.
void forceAvx2Kernels(bool force);
// True if the pSfS kernels use AVX-512 now.
bool avx512KernelsActive();

// For other packages' Highway kernels (body_tracking's part_spans_hwy.cpp), so that they follow
// the same switches: the Highway target (HWY_AVX3, HWY_AVX2, ..., or the portable one where the
// scalar kernels are forced) the pSfS row kernels use now, and a target's slot in the
// HWY_DISPATCH_TABLE of a kernel built with the default Highway targets less SVE and RVV.
int64_t highwayTarget();
size_t highwayDispatchIndex(int64_t target);

}  // namespace psfs
