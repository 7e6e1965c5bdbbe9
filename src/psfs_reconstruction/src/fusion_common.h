// Private: input checks and kernel views shared by the fusion variants.
#pragma once

#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "cpu_dispatch.h"
#include "psfs_kernels.h"
#include "psfs_reconstruction/projection_table.h"
#include "psfs_reconstruction/view_evidence.h"

namespace psfs {
namespace detail {

// Throws std::invalid_argument (prefixed with `who`) unless the evidence fits the table.
inline void checkInputs(const ProjectionTable& table, const ViewEvidence& evidence, bool multi,
                        const std::string& who) {
  if (table.numCameras() == 0) throw std::invalid_argument(who + ": empty projection table");
  if (evidence.numViews() != table.numCameras())
    throw std::invalid_argument(who + ": " + std::to_string(evidence.numViews()) +
                                " views for " + std::to_string(table.numCameras()) + " cameras");
  for (int c = 0; c < table.numCameras(); ++c)
    if (evidence.width(c) != table.camera(c).width || evidence.height(c) != table.camera(c).height)
      throw std::invalid_argument(who + ": view " + std::to_string(c) + " is " +
                                  std::to_string(evidence.width(c)) + "x" +
                                  std::to_string(evidence.height(c)) + " but camera '" +
                                  table.camera(c).name + "' is " +
                                  std::to_string(table.camera(c).width) + "x" +
                                  std::to_string(table.camera(c).height));
  if (multi && !table.multiProjection())
    throw std::invalid_argument(who + ": multi-projection needs a table built with multi_projection");
  if (multi && !evidence.bilinear())
    throw std::invalid_argument(who + ": multi-projection needs evidence set with bilinear = true");
}

// Footprint tables point into stacked evidence levels: only the footprint pSfS reads them, and
// only from evidence with at least the table's levels.
inline void checkFootprint(const ProjectionTable& table, const ViewEvidence& evidence, bool footprint,
                           const std::string& who) {
  const int tl = table.footprintLevels(), el = evidence.footprint().levels;
  if (!footprint && tl > 0)
    throw std::invalid_argument(who + ": the table has footprint levels (needs PsfsOptions::footprint)");
  if (footprint && tl == 0)
    throw std::invalid_argument(who + ": footprint fusion needs a table built with footprint_levels");
  if (footprint && el < tl)
    throw std::invalid_argument(who + ": footprint fusion needs evidence with " + std::to_string(tl) +
                                " footprint levels (has " + std::to_string(el) + ")");
}

// The rows of a grid in parallel, dynamic chunks of `chunk` rows: fn(row, centres) with the
// row's ProjectionTable::rowCentres (a per-thread scratch when the table projects on the fly).
template <class Fn>
void forEachRow(const ProjectionTable& table, int threads, int chunk, const Fn& fn,
                size_t first_row = 0) {
  const long long rows = static_cast<long long>(table.grid().numRows());
#pragma omp parallel num_threads(resolveThreads(threads))
  {
    std::vector<uint32_t> cs(table.precomputed() ? 0 : table.centreScratchSize());
#pragma omp for schedule(dynamic, chunk)
    for (long long r = static_cast<long long>(first_row); r < rows; ++r)
      fn(size_t(r), table.rowCentres(size_t(r), cs.data()));
  }
}

// The same with parts of rows skipped (flags[row * chunksPerRow() + chunk] = 1: not computed):
// fn(row, centres, span) once per run of unflagged chunks, the centres projected for that span
// only when the table projects on the fly; skip_fn(row, begin, end) for each run of flagged
// chunks (voxels [begin, min(end, nx)) of the row).
template <class Fn, class SkipFn>
void forEachRowSpan(const ProjectionTable& table, int threads, int chunk, const uint8_t* flags, const Fn& fn,
                    const SkipFn& skip_fn, size_t first_row = 0) {
  const long long rows = static_cast<long long>(table.grid().numRows());
  const int chunks = table.chunksPerRow();
  constexpr int kChunk = ProjectionTable::kChunk;
#pragma omp parallel num_threads(resolveThreads(threads))
  {
    std::vector<uint32_t> cs(table.precomputed() ? 0 : table.centreScratchSize());
#pragma omp for schedule(dynamic, chunk)
    for (long long r = static_cast<long long>(first_row); r < rows; ++r) {
      const uint8_t* f = flags + size_t(r) * chunks;
      for (int a = 0; a < chunks;) {
        int b = a + 1;
        while (b < chunks && f[b] == f[a]) ++b;
        if (f[a])
          skip_fn(size_t(r), a * kChunk, b * kChunk);
        else
          fn(size_t(r), table.rowCentres(size_t(r), cs.data(), a * kChunk, b * kChunk), RowSpan{a * kChunk, b * kChunk});
        a = b;
      }
    }
  }
}

// Walks the rows of a multi-projection grid in the order the shared face samples need
// (psfs_kernels.h). The work is split into slabs of consecutive z layers, each walked in
// memory order (z, then y) by one thread with its own face buffers, so the stored table
// streams through the caches as one sequence per slab; a slab that does not start at z = 0
// samples the +z faces of the layer below it (plusFacesOfRow) row by row as its first layer
// needs them, so the result does not depend on the split. Slabs are handed out dynamically, about 3 per thread: a thread on a
// busier core takes fewer (the extra layer per slab costs a third of a layer's lookups, plus
// its projections for a table projected on the fly). Slabs are at least 2 layers deep, so a
// grid of nz layers uses at most nz / 2 threads.
// fn(row, centres, offsets, yface, zface, span) with the buffers as the face kernels take them,
// once per span of the row to compute.
// skip (optional, one flag per row and chunk of the table: skip[row * chunksPerRow() + chunk]):
// chunks flagged 1 are not fused; each run of unflagged chunks is a span, its x carry taken
// from the voxel before it (plusXFaces), and skip_fn(row) is called once for a row with any
// flagged chunk (after its spans) to write those. The faces a span needs from a neighbour
// that did not compute them (the row before it in y, the same row in the layer below) are
// sampled with plusFacesOfRow first, so a computed voxel is the same bytes whatever is skipped
// (a slab's first layer is the same case: nothing below it was computed by this thread).
template <class Fn, class SkipFn>
void forEachFaceRow(const ProjectionTable& table, const std::vector<KernelView>& views,
                    int threads, const Fn& fn, const uint8_t* skip, const SkipFn& skip_fn) {
  const int ny = table.grid().dims.y(), nz = table.grid().dims.z();
  const int nxp = table.paddedRowLength(), C = table.numCameras();
  const int chunks = table.chunksPerRow();
  constexpr int kChunk = ProjectionTable::kChunk;
  const size_t row_faces = size_t(C) * nxp;
  const int T = resolveThreads(threads);
  const int depth = T == 1 ? nz : std::max(2, (nz + 3 * T - 1) / (3 * T));
  const int slabs = (nz + depth - 1) / depth;
  const std::vector<uint8_t> none(size_t(chunks), 0);
#pragma omp parallel num_threads(T)
  {
    std::vector<uint32_t> cs(table.precomputed() ? 0 : table.centreScratchSize());
    std::vector<uint32_t> os(table.precomputed() ? 0 : table.offsetScratchSize());
    // + 16: the vector kernels read whole vectors past the last camera's row.
    std::vector<uint16_t> yface(row_faces + 16), zface(row_faces * ny + 16);
    // Per chunk: the slot holds the + faces of the previous row (y) / of the layer below (z).
    std::vector<uint8_t> yface_ok(size_t(chunks), 1), zface_ok(size_t(ny) * chunks, 1);
    std::vector<int32_t> x_carry(static_cast<size_t>(C));
    // The + faces along `axis` of row r into `faces` for the chunks computed now (flags 0)
    // that `ok` does not hold; ok then says what row r + 1 (or the layer above) finds.
    auto resample = [&](size_t r, int axis, uint16_t* faces, uint8_t* ok, const uint8_t* flags) {
      const uint32_t* cen = nullptr;
      const uint32_t* off = nullptr;
      for (int a = 0; a < chunks;) {
        if (flags[a] || ok[a]) { ++a; continue; }
        int b = a + 1;
        while (b < chunks && !flags[b] && !ok[b]) ++b;
        if (!cen) cen = table.rowCentres(r, cs.data()), off = table.rowOffsets(r, os.data());
        plusFacesOfRow(views.data(), C, nxp, cen, off, axis, faces, a * kChunk, b * kChunk);
        a = b;
      }
    };
#pragma omp for schedule(dynamic, 1)
    for (int sl = 0; sl < slabs; ++sl) {
      const int z0 = sl * depth, z1 = std::min(nz, z0 + depth);
      if (z0 == 0) std::fill(zface.begin(), zface.end(), kNoFace);  // no voxel below: sample from above
      std::fill(zface_ok.begin(), zface_ok.end(), uint8_t(z0 == 0));
      for (int z = z0; z < z1; ++z) {
        std::fill(yface.begin(), yface.end(), kNoFace);
        std::fill(yface_ok.begin(), yface_ok.end(), uint8_t(1));
        for (int y = 0; y < ny; ++y) {
          const size_t r = size_t(y) + size_t(ny) * z;
          const uint8_t* flags = skip ? skip + r * size_t(chunks) : none.data();
          uint8_t* zok = &zface_ok[size_t(y) * chunks];
          uint16_t* zf = &zface[size_t(y) * row_faces];
          const int flagged = int(std::count(flags, flags + chunks, uint8_t(1)));
          if (flagged < chunks) {
            if (y > 0) resample(r - 1, 1, yface.data(), yface_ok.data(), flags);
            if (z > 0) resample(r - size_t(ny), 2, zf, zok, flags);
            const uint32_t* cen = table.rowCentres(r, cs.data());
            const uint32_t* off = table.rowOffsets(r, os.data());
            for (int a = 0; a < chunks;) {
              if (flags[a]) { ++a; continue; }
              int b = a + 1;
              while (b < chunks && !flags[b]) ++b;
              if (a > 0) plusXFaces(views.data(), C, nxp, cen, off, a * kChunk - 1, x_carry.data());
              fn(r, cen, off, yface.data(), zf, RowSpan{a * kChunk, b * kChunk, a > 0 ? x_carry.data() : nullptr});
              a = b;
            }
          }
          for (int a = 0; a < chunks; ++a) yface_ok[size_t(a)] = zok[a] = uint8_t(!flags[a]);
          if (flagged > 0) skip_fn(r);
        }
      }
    }
  }
}

// Every row whole, fn(row, centres, offsets, yface, zface).
template <class Fn>
void forEachFaceRow(const ProjectionTable& table, const std::vector<KernelView>& views,
                    int threads, const Fn& fn) {
  forEachFaceRow(
      table, views, threads,
      [&](size_t r, const uint32_t* cen, const uint32_t* off, uint16_t* yf, uint16_t* zf, const RowSpan&) {
        fn(r, cen, off, yf, zf);
      },
      nullptr, [](size_t) {});
}

inline std::vector<KernelView> kernelViews(const ViewEvidence& e) {
  std::vector<KernelView> v(e.numViews());
  for (int c = 0; c < e.numViews(); ++c)
    v[c] = KernelView{e.terms(c), e.bilinear() ? e.pairs(c) : nullptr, e.width(c), e.quadStride(c),
                      e.hasInactivePixels(c), PackedUV::notObserved(e.height(c))};
  return v;
}

}  // namespace detail
}  // namespace psfs
