// The GPU particle weights (gpu_particle_weights.h), after the thesis' figure 6.4: the part
// poses are built on the host (module 1, see gpu_particle_weights.cpp), then
//   partScoresKernel     one block per (particle, part): each thread computes one voxel row's
//                        partial weights (module 2, the rows being the sub-volumes), thread 0
//                        adds them up in row order (module 3);
//   particleScoresKernel one thread per particle sums its parts' scores (module 4).
// Both are thin wrappers around part_score.h, the arithmetic the CPU path runs, and add in the
// CPU's order, so the scores are the CPU's to the last bit (built with --fmad=false).
#include <cuda_runtime.h>

#include <cstring>
#include <stdexcept>
#include <string>

#include "particle_weights_device.h"

namespace body_tracking {
namespace gpu {

using part_score::ObservationGrid;
using part_score::PartQuadric;
using part_score::PartSetup;
using part_score::PartSums;
using part_score::RowSumsView;
using part_score::RowTerms;

bool compiledIn() { return true; }

namespace {

static_assert(sizeof(PartQuadric) % sizeof(double) == 0, "parts are copied as doubles");
constexpr int kPartWords = sizeof(PartQuadric) / sizeof(double);
constexpr int kParticleThreads = 128;

void check(cudaError_t e, const char* what) {
  if (e != cudaSuccess)
    throw std::runtime_error(std::string("GPU particle weights: ") + what + ": " + cudaGetErrorString(e));
}

__global__ void partScoresKernel(const PartQuadric* parts, const uint8_t* collides,
                                 int parts_per_particle, ObservationGrid g, RowSumsView body,
                                 RowSumsView blended, double* part_scores) {
  const int item = blockIdx.x;
  if (collides[item / parts_per_particle]) return;  // the whole block: scores 0 anyway
  __shared__ PartQuadric q;
  __shared__ RowTerms terms[kRowThreads];
  const double* src = reinterpret_cast<const double*>(parts + item);
  double* dst = reinterpret_cast<double*>(&q);
  for (int i = threadIdx.x; i < kPartWords; i += blockDim.x) dst[i] = src[i];
  __syncthreads();
  const PartSetup s = part_score::setupPart(q, g);
  const RowSumsView sums = q.skin ? blended : body;
  const int rows = part_score::rowCount(s);
  PartSums acc = {0.0, 0.0, 0.0, 0.0};
  for (int first = 0; first < rows; first += kRowThreads) {
    const int k = first + static_cast<int>(threadIdx.x);
    if (k < rows) terms[threadIdx.x] = part_score::rowTermsAt(s, q, g, sums, k);
    __syncthreads();
    if (threadIdx.x == 0) {
      const int m = min(kRowThreads, rows - first);
      for (int j = 0; j < m; ++j) part_score::accumulateRow(terms[j], &acc);
    }
    __syncthreads();
  }
  if (threadIdx.x == 0) part_scores[item] = part_score::finishPart(acc, g.unknown, q.shell_weight);
}

__global__ void particleScoresKernel(const double* part_scores, const uint8_t* collides,
                                     int particles, int parts_per_particle, double* scores) {
  const int i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i < particles)
    scores[i] = part_score::particleScore(part_scores + static_cast<size_t>(i) * parts_per_particle,
                                          parts_per_particle, collides[i] != 0);
}

}  // namespace

struct ParticleWeightsDevice::State {
  int device = 0;
  cudaStream_t stream = nullptr;
  size_t allocations = 0;
  // Device buffers and their pinned host twins, each with its capacity in elements.
  double* d_sums = nullptr;
  double* h_sums = nullptr;
  size_t sums_cap = 0;
  PartQuadric* d_parts = nullptr;
  PartQuadric* h_parts = nullptr;
  double* d_part_scores = nullptr;
  size_t parts_cap = 0;
  uint8_t* d_collides = nullptr;
  uint8_t* h_collides = nullptr;
  double* d_scores = nullptr;
  double* h_scores = nullptr;
  size_t particles_cap = 0;
  ObservationGrid grid{};
  RowSumsView body{}, blended{};
  bool have_sums = false;

  template <typename T>
  void deviceAlloc(T** p, size_t n) {
    check(cudaMalloc(reinterpret_cast<void**>(p), n * sizeof(T)), "cudaMalloc");
    ++allocations;
  }
  template <typename T>
  void pinnedAlloc(T** p, size_t n) {
    check(cudaMallocHost(reinterpret_cast<void**>(p), n * sizeof(T)), "cudaMallocHost");
    ++allocations;
  }
  void freeAll() {
    for (void* p : {static_cast<void*>(d_sums), static_cast<void*>(d_parts),
                    static_cast<void*>(d_part_scores), static_cast<void*>(d_collides),
                    static_cast<void*>(d_scores)})
      if (p) cudaFree(p);
    for (void* p : {static_cast<void*>(h_sums), static_cast<void*>(h_parts),
                    static_cast<void*>(h_collides), static_cast<void*>(h_scores)})
      if (p) cudaFreeHost(p);
  }
};

ParticleWeightsDevice::ParticleWeightsDevice(int device_index) : s_(new State) {
  s_->device = device_index;
  check(cudaSetDevice(device_index), "cudaSetDevice");
  check(cudaStreamCreateWithFlags(&s_->stream, cudaStreamNonBlocking), "cudaStreamCreate");
}

ParticleWeightsDevice::~ParticleWeightsDevice() {
  // No throwing here: errors at teardown have nowhere to go.
  cudaSetDevice(s_->device);
  if (s_->stream) {
    cudaStreamSynchronize(s_->stream);
    cudaStreamDestroy(s_->stream);
  }
  s_->freeAll();
}

size_t ParticleWeightsDevice::allocations() const { return s_->allocations; }

void ParticleWeightsDevice::uploadRowSums(const RowSumsView& body, const RowSumsView& blended,
                                          size_t count, const ObservationGrid& grid) {
  State& s = *s_;
  check(cudaSetDevice(s.device), "cudaSetDevice");
  check(cudaStreamSynchronize(s.stream), "previous work");  // the staging may still be read
  const size_t total = 6 * count;
  if (total > s.sums_cap) {
    if (s.d_sums) check(cudaFree(s.d_sums), "cudaFree");
    if (s.h_sums) check(cudaFreeHost(s.h_sums), "cudaFreeHost");
    s.d_sums = s.h_sums = nullptr;
    s.sums_cap = 0;
    s.deviceAlloc(&s.d_sums, total);
    s.pinnedAlloc(&s.h_sums, total);
    s.sums_cap = total;
  }
  const double* src[6] = {body.s0, body.s1, body.s2, blended.s0, blended.s1, blended.s2};
  for (int k = 0; k < 6; ++k) std::memcpy(s.h_sums + k * count, src[k], count * sizeof(double));
  check(cudaMemcpyAsync(s.d_sums, s.h_sums, total * sizeof(double), cudaMemcpyHostToDevice, s.stream),
        "row sums upload");
  s.body = {s.d_sums, s.d_sums + count, s.d_sums + 2 * count};
  s.blended = {s.d_sums + 3 * count, s.d_sums + 4 * count, s.d_sums + 5 * count};
  s.grid = grid;
  s.have_sums = true;
}

void ParticleWeightsDevice::reserve(int particles, int parts_per_particle) {
  State& s = *s_;
  check(cudaSetDevice(s.device), "cudaSetDevice");
  const size_t n = static_cast<size_t>(particles), items = n * parts_per_particle;
  if (items > s.parts_cap || n > s.particles_cap) check(cudaStreamSynchronize(s.stream), "previous work");
  if (items > s.parts_cap) {
    if (s.d_parts) check(cudaFree(s.d_parts), "cudaFree");
    if (s.d_part_scores) check(cudaFree(s.d_part_scores), "cudaFree");
    if (s.h_parts) check(cudaFreeHost(s.h_parts), "cudaFreeHost");
    s.d_parts = s.h_parts = nullptr;
    s.d_part_scores = nullptr;
    s.parts_cap = 0;
    s.deviceAlloc(&s.d_parts, items);
    s.deviceAlloc(&s.d_part_scores, items);
    s.pinnedAlloc(&s.h_parts, items);
    s.parts_cap = items;
  }
  if (n > s.particles_cap) {
    if (s.d_collides) check(cudaFree(s.d_collides), "cudaFree");
    if (s.d_scores) check(cudaFree(s.d_scores), "cudaFree");
    if (s.h_collides) check(cudaFreeHost(s.h_collides), "cudaFreeHost");
    if (s.h_scores) check(cudaFreeHost(s.h_scores), "cudaFreeHost");
    s.d_collides = s.h_collides = nullptr;
    s.d_scores = s.h_scores = nullptr;
    s.particles_cap = 0;
    s.deviceAlloc(&s.d_collides, n);
    s.deviceAlloc(&s.d_scores, n);
    s.pinnedAlloc(&s.h_collides, n);
    s.pinnedAlloc(&s.h_scores, n);
    s.particles_cap = n;
  }
}

PartQuadric* ParticleWeightsDevice::stagedParts() { return s_->h_parts; }
uint8_t* ParticleWeightsDevice::stagedCollides() { return s_->h_collides; }

const double* ParticleWeightsDevice::score(int particles, int parts_per_particle) {
  State& s = *s_;
  if (!s.have_sums) throw std::logic_error("GPU particle weights: score() before the row sums");
  const size_t n = static_cast<size_t>(particles), items = n * parts_per_particle;
  if (items > s.parts_cap || n > s.particles_cap)
    throw std::logic_error("GPU particle weights: score() beyond reserve()");
  if (n == 0) return s.h_scores;
  check(cudaSetDevice(s.device), "cudaSetDevice");
  check(cudaMemcpyAsync(s.d_parts, s.h_parts, items * sizeof(PartQuadric), cudaMemcpyHostToDevice, s.stream),
        "parts upload");
  check(cudaMemcpyAsync(s.d_collides, s.h_collides, n, cudaMemcpyHostToDevice, s.stream),
        "collision flags upload");
  partScoresKernel<<<static_cast<unsigned>(items), kRowThreads, 0, s.stream>>>(
      s.d_parts, s.d_collides, parts_per_particle, s.grid, s.body, s.blended, s.d_part_scores);
  check(cudaGetLastError(), "part kernel launch");
  const unsigned blocks = static_cast<unsigned>((n + kParticleThreads - 1) / kParticleThreads);
  particleScoresKernel<<<blocks, kParticleThreads, 0, s.stream>>>(s.d_part_scores, s.d_collides,
                                                                 particles, parts_per_particle, s.d_scores);
  check(cudaGetLastError(), "particle kernel launch");
  check(cudaMemcpyAsync(s.h_scores, s.d_scores, n * sizeof(double), cudaMemcpyDeviceToHost, s.stream),
        "scores download");
  check(cudaStreamSynchronize(s.stream), "particle weights");
  return s.h_scores;
}

}  // namespace gpu
}  // namespace body_tracking
