#include <zstd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numeric>
#include <stdexcept>
#include <string>

#include "cvephands_bridge/stream/hand_stream_codec.h"
#include "hand_stream_format.h"

namespace cvephands {
namespace {

// Level values (ranked: code 0 = most used) and the code of every byte value on one side of
// the iso, for one context of one frame.
struct ContextLevels {
  uint8_t table[256];
  uint8_t code[256];
};

// Nearest-level assignment over the sorted levels for v = lo..hi in one sweep; ties go to the
// lower level. Calls f(v, level index).
template <typename F>
void sweepNearest(const std::vector<double>& levels, int lo, int hi, F f) {
  size_t j = 0;
  for (int v = lo; v <= hi; ++v) {
    while (j + 1 < levels.size() && std::abs(levels[j + 1] - v) < std::abs(levels[j] - v)) ++j;
    f(v, j);
  }
}

// Fits 2^bits levels to one context's histogram of band values (all within [lo, hi]) and
// numbers them by use. Adaptive: the distinct values themselves when they fit, else Lloyd's
// algorithm (minimum squared value error) started from even spacing over the values present.
// Otherwise, or for an empty context: even spacing over [lo, hi].
void fitLevels(const uint32_t* hist, int lo, int hi, int bits, bool adaptive, ContextLevels* out) {
  const int L = wire::levelsFor(bits);
  int vmin = 256, vmax = -1, distinct = 0;
  for (int v = lo; v <= hi; ++v)
    if (hist[v]) vmin = std::min(vmin, v), vmax = std::max(vmax, v), ++distinct;
  std::vector<double> levels;
  if (adaptive && distinct > 0 && distinct <= L) {
    for (int v = lo; v <= hi; ++v)
      if (hist[v]) levels.push_back(v);
  } else {
    const bool fit = adaptive && distinct > 0;
    const double a = fit ? vmin : lo, w = fit ? vmax - vmin + 1 : hi - lo + 1;
    for (int j = 0; j < L; ++j) levels.push_back(a + (j + 0.5) * w / L - 0.5);
    for (int it = 0; fit && it < 20; ++it) {
      std::vector<double> sum(L, 0.0), n(L, 0.0);
      sweepNearest(levels, vmin, vmax,
                   [&](int v, size_t j) { sum[j] += double(v) * hist[v], n[j] += hist[v]; });
      bool moved = false;
      for (int j = 0; j < L; ++j)
        if (n[j] > 0 && std::abs(sum[j] / n[j] - levels[j]) > 1e-3)
          levels[j] = sum[j] / n[j], moved = true;
      std::sort(levels.begin(), levels.end());
      if (!moved) break;
    }
  }
  for (double& l : levels) l = std::clamp(std::round(l), double(lo), double(hi));
  std::sort(levels.begin(), levels.end());
  // Use of each level, then rank: most used first (ties: lower value first).
  std::vector<uint64_t> use(levels.size(), 0);
  std::vector<uint8_t> nearest(256, 0);
  sweepNearest(levels, lo, hi,
               [&](int v, size_t j) { nearest[v] = uint8_t(j), use[j] += hist[v]; });
  std::vector<int> order(levels.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return use[a] > use[b]; });
  std::vector<uint8_t> rank(levels.size());
  for (size_t r = 0; r < order.size(); ++r) rank[order[r]] = uint8_t(r);
  std::memset(out->table, 0, sizeof(out->table));
  std::memset(out->code, 0, sizeof(out->code));
  for (int r = 0; r < L; ++r)  // the levels padded with the last one when fewer than L
    out->table[r] = uint8_t(levels[order[std::min<size_t>(r, order.size() - 1)]]);
  for (int v = lo; v <= hi; ++v) out->code[v] = rank[nearest[v]];
}

// Indices where a and b differ, 8 bytes at a time (the residual is sparse).
void diffPositions(const uint8_t* a, const uint8_t* b, size_t n, std::vector<uint32_t>* pos) {
  pos->clear();
  size_t i = 0;
  for (; i + 8 <= n; i += 8) {
    uint64_t wa, wb;
    std::memcpy(&wa, a + i, 8);
    std::memcpy(&wb, b + i, 8);
    if (wa == wb) continue;
    for (size_t j = i; j < i + 8; ++j)
      if (a[j] != b[j]) pos->push_back(uint32_t(j));
  }
  for (; i < n; ++i)
    if (a[i] != b[i]) pos->push_back(uint32_t(i));
}

void checkFrame(const HandFrame& f) {
  auto bad = [](const std::string& what) {
    throw std::invalid_argument("cvephands::HandStreamEncoder: " + what);
  };
  if ((f.dims.array() < 1).any() || (f.dims.array() > wire::kMaxSide).any())
    bad("'dims' must be 1.." + std::to_string(wire::kMaxSide) + " per axis (got " +
        std::to_string(f.dims.x()) + "x" + std::to_string(f.dims.y()) + "x" +
        std::to_string(f.dims.z()) + ")");
  const size_t n = size_t(f.dims.x()) * size_t(f.dims.y()) * size_t(f.dims.z());
  if (f.data.size() != n)
    bad("'data' has " + std::to_string(f.data.size()) + " bytes, dims need " + std::to_string(n));
  if (!f.origin.allFinite() || f.origin.cwiseAbs().maxCoeff() > wire::kMaxAbsOrigin)
    bad("'origin' must be finite and within 1e4 m");
  if (!std::isfinite(f.voxel_size) || !(f.voxel_size > 0.0) || f.voxel_size > wire::kMaxVoxelSize)
    bad("'voxel_size' must be finite, > 0 and <= 1 m");
  if (f.stamp_nsec >= 1000000000u) bad("'stamp_nsec' must be < 10^9");
}

}  // namespace

void HandStreamEncoderOptions::validate() const {
  auto bad = [](const std::string& what) {
    throw std::invalid_argument("cvephands::HandStreamEncoderOptions: " + what);
  };
  if (method != HandCodecMethod::kRaw && method != HandCodecMethod::kBand) bad("unknown 'method'");
  if (bits < 0 || bits > wire::kMaxBits) bad("'bits' must be 0..8");
  if (keyframe_interval < 1) bad("'keyframe_interval' must be >= 1");
  if (zstd_level < ZSTD_minCLevel() || zstd_level > ZSTD_maxCLevel())
    bad("'zstd_level' out of zstd's range");
  if (iso_byte < 1 || iso_byte > 254) bad("'iso_byte' must be 1..254");
}

struct HandStreamEncoder::State {
  ZSTD_CCtx* cctx = nullptr;
  uint32_t next_sequence = 0;
  int frames_since_key = 0;
  bool key_requested = true;
  // The previous frame (what the decoder keeps as the reference).
  bool has_ref = false;
  uint32_t ref_target = 0, ref_sequence = 0;
  Eigen::Vector3i ref_dims = Eigen::Vector3i::Zero();
  Eigen::Vector3d ref_origin = Eigen::Vector3d::Zero();
  double ref_voxel = 0;
  std::vector<uint8_t> ref_above;
  // Scratch kept between frames.
  std::vector<uint8_t> above, context, padded, predicted, raw;
  std::vector<uint32_t> residual_key, residual_delta, hist;
  std::vector<ContextLevels> levels = std::vector<ContextLevels>(wire::kContexts);

  State() : cctx(ZSTD_createCCtx()) {
    if (!cctx) throw std::bad_alloc();
  }
  ~State() { ZSTD_freeCCtx(cctx); }
};

HandStreamEncoder::HandStreamEncoder(const HandStreamEncoderOptions& options) : options_(options) {
  options_.validate();
  state_ = std::make_unique<State>();
}
HandStreamEncoder::~HandStreamEncoder() = default;
HandStreamEncoder::HandStreamEncoder(HandStreamEncoder&&) noexcept = default;
HandStreamEncoder& HandStreamEncoder::operator=(HandStreamEncoder&&) noexcept = default;

void HandStreamEncoder::requestKeyFrame() { state_->key_requested = true; }

void HandStreamEncoder::encode(const HandFrame& frame, std::vector<uint8_t>* message) {
  checkFrame(frame);
  State& s = *state_;
  const int nx = frame.dims.x(), ny = frame.dims.y(), nz = frame.dims.z();
  const size_t n = frame.data.size();
  const uint8_t iso = uint8_t(options_.iso_byte);

  wire::Header h;
  h.method = uint8_t(options_.method);
  h.target_id = frame.target_id;
  h.sequence = s.next_sequence++;
  h.stamp_sec = frame.stamp_sec;
  h.stamp_nsec = frame.stamp_nsec;
  for (int i = 0; i < 3; ++i) h.origin[i] = frame.origin[i], h.dims[i] = uint16_t(frame.dims[i]);
  h.voxel_size = frame.voxel_size;
  h.iso_byte = iso;

  s.above.resize(n);
  wire::aboveIso(frame.data.data(), n, iso, s.above.data());
  HandMessageInfo info;
  info.method = options_.method;

  const uint8_t* raw_data = frame.data.data();
  size_t raw_size = n;
  if (options_.method == HandCodecMethod::kBand) {
    const int bits = options_.bits, L = wire::levelsFor(bits);
    h.bits = uint8_t(bits);
    s.context.resize(n);
    const size_t band = wire::classifyBand(s.above.data(), nx, ny, nz, &s.padded, s.context.data());
    // Levels per context from this frame's band values.
    s.hist.assign(size_t(wire::kContexts) * 256, 0);
    wire::forEachBandSample(s.context.data(), n, [&](size_t i, uint8_t c) {
      ++s.hist[size_t(c - 1) * 256 + frame.data[i]];
    });
    for (int c = 0; c < wire::kContexts; ++c) {
      const bool up = c >= 6;
      fitLevels(&s.hist[size_t(c) * 256], up ? iso + 1 : 0, up ? 255 : iso, bits,
                options_.adaptive_levels, &s.levels[c]);
    }
    // Mask residual: against the slice below (key) or the previous frame moved by the cube's
    // shift (delta), whichever leaves fewer samples.
    s.predicted.resize(n);
    wire::shiftedMask(s.above.data(), nx, ny, nz, 0, 0, -1, s.predicted.data());
    diffPositions(s.above.data(), s.predicted.data(), n, &s.residual_key);
    bool delta = false;
    Eigen::Vector3i shift = Eigen::Vector3i::Zero();
    if (s.has_ref && !s.key_requested && s.frames_since_key + 1 < options_.keyframe_interval &&
        s.ref_target == frame.target_id && s.ref_dims == frame.dims &&
        s.ref_voxel == frame.voxel_size) {
      const Eigen::Vector3d d = (frame.origin - s.ref_origin) / frame.voxel_size;
      if (d.cwiseAbs().maxCoeff() <= wire::kMaxShift) {
        shift = d.array().round().cast<int>();
        wire::shiftedMask(s.ref_above.data(), nx, ny, nz, shift.x(), shift.y(), shift.z(),
                          s.predicted.data());
        diffPositions(s.above.data(), s.predicted.data(), n, &s.residual_delta);
        delta = s.residual_delta.size() < s.residual_key.size();
      }
    }
    const std::vector<uint32_t>& residual = delta ? s.residual_delta : s.residual_key;
    if (delta) {
      h.flags = wire::kFlagDelta;
      h.reference_sequence = s.ref_sequence;
      for (int i = 0; i < 3; ++i) h.shift[i] = int16_t(shift[i]);
    }
    // Raw payload: tables, mask gaps, packed codes.
    s.raw.clear();
    for (int c = 0; c < wire::kContexts; ++c)
      s.raw.insert(s.raw.end(), s.levels[c].table, s.levels[c].table + L);
    uint32_t next = 0;
    for (uint32_t p : residual) wire::putVarint(&s.raw, p - next), next = p + 1;
    h.mask_bytes = uint32_t(s.raw.size() - wire::tableBytes(bits));
    const int k = wire::codesPerByte(bits);
    if (k > 0) {
      const size_t start = s.raw.size();
      s.raw.resize(start + wire::codeBytes(band, bits), 0);
      size_t j = 0;
      wire::forEachBandSample(s.context.data(), n, [&](size_t i, uint8_t c) {
        const uint8_t code = s.levels[c - 1].code[frame.data[i]];
        s.raw[start + j / k] |= uint8_t(code << (bits * (j % k)));
        ++j;
      });
    }
    h.band_count = uint32_t(band);
    raw_data = s.raw.data();
    raw_size = s.raw.size();
    info.bits = bits;
    info.key_frame = !delta;
    info.reference_sequence = h.reference_sequence;
    info.shift = shift;
    info.mask_bytes = h.mask_bytes;
    info.band_samples = band;
    s.frames_since_key = delta ? s.frames_since_key + 1 : 0;
  } else {
    s.frames_since_key = 0;
  }
  s.key_requested = false;

  h.raw_size = uint32_t(raw_size);
  message->resize(wire::kHeaderSize + ZSTD_compressBound(raw_size) + wire::kTrailerSize);
  const size_t z =
      ZSTD_compressCCtx(s.cctx, message->data() + wire::kHeaderSize, ZSTD_compressBound(raw_size),
                        raw_data, raw_size, options_.zstd_level);
  if (ZSTD_isError(z))  // cannot happen with a bound-sized buffer; never send a broken message
    throw std::runtime_error(std::string("cvephands::HandStreamEncoder: zstd: ") +
                             ZSTD_getErrorName(z));
  h.payload_size = uint32_t(z);
  wire::writeHeader(h, message->data());
  message->resize(wire::kHeaderSize + z + wire::kTrailerSize);
  wire::putU32(message->data() + wire::kHeaderSize + z,
               wire::crc32(message->data(), wire::kHeaderSize + z));

  // This frame becomes the reference (the decoder's mask is exactly this one).
  s.has_ref = true;
  s.ref_target = frame.target_id;
  s.ref_sequence = h.sequence;
  s.ref_dims = frame.dims;
  s.ref_origin = frame.origin;
  s.ref_voxel = frame.voxel_size;
  s.ref_above.swap(s.above);

  info.sequence = h.sequence;
  info.message_bytes = message->size();
  info.payload_bytes = z;
  info.raw_bytes = raw_size;
  last_ = info;
}

}  // namespace cvephands
