#include <zstd.h>

#include <cmath>
#include <cstring>
#include <string>

#include "cvephands_bridge/stream/hand_stream_codec.h"
#include "hand_stream_format.h"

namespace cvephands {
namespace {

constexpr size_t kMaxReferences = 16;

std::string str(uint64_t v) { return std::to_string(v); }

}  // namespace

struct HandStreamDecoder::State {
  // The last decoded frame of a target: what its next delta frame is predicted from.
  struct Reference {
    uint32_t target = 0, sequence = 0;
    uint16_t dims[3] = {0, 0, 0};
    double voxel_size = 0;
    uint8_t iso_byte = 0;
    uint64_t last_use = 0;
    std::vector<uint8_t> above;
  };
  ZSTD_DCtx* dctx = nullptr;
  std::vector<Reference> refs;
  uint64_t tick = 0;
  std::vector<uint8_t> raw, above, context, padded, predicted;

  State() : dctx(ZSTD_createDCtx()) {
    if (!dctx) throw std::bad_alloc();
  }
  ~State() { ZSTD_freeDCtx(dctx); }

  Reference* find(uint32_t target) {
    for (Reference& r : refs)
      if (r.target == target) return &r;
    return nullptr;
  }
  // The slot for `target`: its own, a free one, or the least recently used.
  Reference* slot(uint32_t target) {
    if (Reference* r = find(target)) return r;
    if (refs.size() < kMaxReferences) return &refs.emplace_back();
    Reference* oldest = &refs[0];
    for (Reference& r : refs)
      if (r.last_use < oldest->last_use) oldest = &r;
    return oldest;
  }
};

HandStreamDecoder::HandStreamDecoder() : state_(std::make_unique<State>()) {}
HandStreamDecoder::~HandStreamDecoder() = default;
HandStreamDecoder::HandStreamDecoder(HandStreamDecoder&&) noexcept = default;
HandStreamDecoder& HandStreamDecoder::operator=(HandStreamDecoder&&) noexcept = default;

void HandStreamDecoder::reset() { state_->refs.clear(); }

bool HandStreamDecoder::decode(const uint8_t* data, size_t size, HandFrame* out,
                               std::string* reason, HandMessageInfo* info) {
  auto fail = [&](const std::string& why) {
    if (reason) *reason = why;
    return false;
  };
  State& s = *state_;
  using namespace wire;

  // ---- envelope: size, magic, version, length, checksum ----
  if (!out) return fail("no output frame");
  if (!data && size > 0) return fail("null data");
  if (size < kHeaderSize + kTrailerSize)
    return fail("truncated header: " + str(size) + " bytes, a message has at least " +
                str(kHeaderSize + kTrailerSize));
  if (std::memcmp(data, kMagic, 4) != 0) return fail("bad magic (not a hand stream message)");
  if (data[4] != kVersion)
    return fail("unsupported version " + str(data[4]) + " (this decoder reads " + str(kVersion) +
                ")");
  Header h;
  readHeader(data, &h);
  if (uint64_t(kHeaderSize) + h.payload_size + kTrailerSize != size)
    return fail("size mismatch: header says " + str(h.payload_size) +
                " payload bytes, message has " + str(size - kHeaderSize - kTrailerSize));
  if (crc32(data, size - kTrailerSize) != getU32(data + size - kTrailerSize))
    return fail("checksum mismatch");

  // ---- header fields ----
  if (h.method != kMethodRaw && h.method != kMethodBand)
    return fail("unknown method " + str(h.method));
  if (h.flags & ~kFlagDelta) return fail("unknown flags " + str(h.flags));
  const bool delta = h.flags & kFlagDelta;
  if (delta && h.method == kMethodRaw) return fail("delta flag on a raw message");
  if (h.bits > (h.method == kMethodBand ? kMaxBits : 0))
    return fail("bits " + str(h.bits) + " out of range for method " + str(h.method));
  if (h.reserved0 || h.reserved1) return fail("reserved field not zero");
  if (h.stamp_nsec >= 1000000000u) return fail("stamp nanoseconds out of range");
  for (double o : h.origin)
    if (!std::isfinite(o) || std::abs(o) > kMaxAbsOrigin)
      return fail("origin not finite or beyond 1e4 m");
  if (!std::isfinite(h.voxel_size) || !(h.voxel_size > 0.0) || h.voxel_size > kMaxVoxelSize)
    return fail("voxel size not finite or outside (0, 1] m");
  for (uint16_t d : h.dims)
    if (d < 1 || d > kMaxSide) return fail("dims out of range (1..256 per axis)");
  const int nx = h.dims[0], ny = h.dims[1], nz = h.dims[2];
  const size_t n = size_t(nx) * size_t(ny) * size_t(nz);  // <= 2^24 = kMaxVoxels
  if (h.iso_byte < 1 || h.iso_byte > 254) return fail("iso byte out of range (1..254)");
  if (!delta && (h.reference_sequence || h.shift[0] || h.shift[1] || h.shift[2]))
    return fail("reference fields set in a key frame");
  for (int16_t sh : h.shift)
    if (std::abs(int(sh)) > kMaxShift) return fail("shift out of range");
  size_t tables = 0;
  if (h.method == kMethodRaw) {
    if (h.band_count || h.mask_bytes) return fail("band fields set in a raw message");
    if (h.raw_size != n) return fail("raw size " + str(h.raw_size) + " != voxel count " + str(n));
  } else {
    tables = tableBytes(h.bits);
    if (h.band_count > n) return fail("band count exceeds voxel count");
    if (h.mask_bytes > 4 * n) return fail("mask section too large");
    if (uint64_t(tables) + h.mask_bytes + codeBytes(h.band_count, h.bits) != h.raw_size)
      return fail("section sizes do not add up to the raw size");
  }
  State::Reference* ref = nullptr;
  if (delta) {
    ref = s.find(h.target_id);
    if (!ref)
      return fail("missing reference frame: no earlier frame of target " + str(h.target_id));
    if (ref->sequence != h.reference_sequence)
      return fail("missing reference frame: target " + str(h.target_id) + " needs sequence " +
                  str(h.reference_sequence) + ", last decoded is " + str(ref->sequence));
    if (std::memcmp(ref->dims, h.dims, sizeof(h.dims)) != 0 || ref->voxel_size != h.voxel_size ||
        ref->iso_byte != h.iso_byte)
      return fail("reference frame mismatch (dims, voxel size or iso byte differ)");
  }

  // ---- payload: exactly one zstd frame of the announced size ----
  const uint8_t* payload = data + kHeaderSize;
  const unsigned long long content = ZSTD_getFrameContentSize(payload, h.payload_size);
  if (content == ZSTD_CONTENTSIZE_ERROR) return fail("zstd: invalid frame header");
  if (content == ZSTD_CONTENTSIZE_UNKNOWN) return fail("zstd: frame has no content size");
  if (content != h.raw_size)
    return fail("zstd: content size " + str(content) + " != raw size " + str(h.raw_size));
  const size_t frame_size = ZSTD_findFrameCompressedSize(payload, h.payload_size);
  if (ZSTD_isError(frame_size)) return fail(std::string("zstd: ") + ZSTD_getErrorName(frame_size));
  if (frame_size != h.payload_size) return fail("zstd: payload is not exactly one frame");
  uint8_t* raw;
  if (h.method == kMethodRaw) {
    out->data.resize(n);  // decompress straight into the volume
    raw = out->data.data();
  } else {
    s.raw.resize(h.raw_size);
    raw = s.raw.data();
  }
  // zstd itself rejects a frame whose blocks decode to other than its content size.
  const size_t got = ZSTD_decompressDCtx(s.dctx, raw, h.raw_size, payload, h.payload_size);
  if (ZSTD_isError(got)) return fail(std::string("zstd: ") + ZSTD_getErrorName(got));

  // ---- volume ----
  s.above.resize(n);
  if (h.method == kMethodRaw) {
    aboveIso(raw, n, h.iso_byte, s.above.data());
  } else {
    const int bits = h.bits, L = levelsFor(bits);
    const uint8_t* table = raw;
    for (int c = 0; c < kContexts; ++c)
      for (int j = 0; j < L; ++j) {
        const uint8_t v = table[c * L + j];
        if ((c >= 6) != (v > h.iso_byte))
          return fail("table value " + str(v) + " on the wrong side of the iso for context " +
                      str(c));
      }
    // Mask: residual samples from the gaps, then undo the prediction.
    std::memset(s.above.data(), 0, n);
    const uint8_t* p = raw + tables;
    const uint8_t* const mask_end = p + h.mask_bytes;
    uint64_t next = 0;
    while (p < mask_end) {
      uint32_t gap;
      if (!getVarint(&p, mask_end, &gap)) return fail("mask: bad varint");
      const uint64_t i = next + gap;
      if (i >= n) return fail("mask: sample index out of range");
      s.above[i] = 1;
      next = i + 1;
    }
    if (delta) {
      s.predicted.resize(n);
      shiftedMask(ref->above.data(), nx, ny, nz, h.shift[0], h.shift[1], h.shift[2],
                  s.predicted.data());
      xorInto(s.above.data(), s.predicted.data(), n);
    } else {
      const size_t slice = size_t(nx) * size_t(ny);
      for (int z = 1; z < nz; ++z)
        xorInto(s.above.data() + z * slice, s.above.data() + (z - 1) * slice, slice);
    }
    s.context.resize(n);
    const size_t band = classifyBand(s.above.data(), nx, ny, nz, &s.padded, s.context.data());
    if (band != h.band_count)
      return fail("band count mismatch: mask gives " + str(band) + ", header says " +
                  str(h.band_count));
    const int k = codesPerByte(bits);
    const uint8_t* codes = mask_end;
    if (k > 0 && bits * k < 8) {  // padding bits of every code byte must be zero
      const uint8_t pad = uint8_t(0xff << (bits * k));
      const size_t bytes = codeBytes(band, bits);
      for (size_t b = 0; b < bytes; ++b)
        if (codes[b] & pad) return fail("codes: nonzero padding bits");
    }
    if (k > 0 && band % k) {  // unused code slots of the last byte must be zero
      const uint8_t used = uint8_t((1u << (bits * (band % k))) - 1);
      if (codes[band / k] & ~used) return fail("codes: nonzero unused slots in the last byte");
    }
    out->data.resize(n);
    uint8_t* const volume = out->data.data();
    maskToBytes(s.above.data(), n, volume);
    const uint8_t code_mask = uint8_t((1u << bits) - 1);
    size_t j = 0;
    forEachBandSample(s.context.data(), n, [&](size_t i, uint8_t c) {
      const uint8_t code = k ? uint8_t((codes[j / k] >> (bits * (j % k))) & code_mask) : 0;
      volume[i] = table[(c - 1) * L + code];
      ++j;
    });
  }

  out->target_id = h.target_id;
  out->stamp_sec = h.stamp_sec;
  out->stamp_nsec = h.stamp_nsec;
  out->origin = Eigen::Vector3d(h.origin[0], h.origin[1], h.origin[2]);
  out->voxel_size = h.voxel_size;
  out->dims = Eigen::Vector3i(nx, ny, nz);

  State::Reference* r = s.slot(h.target_id);
  r->target = h.target_id;
  r->sequence = h.sequence;
  std::memcpy(r->dims, h.dims, sizeof(h.dims));
  r->voxel_size = h.voxel_size;
  r->iso_byte = h.iso_byte;
  r->last_use = ++s.tick;
  r->above.swap(s.above);

  if (info) {
    HandMessageInfo m;
    m.method = HandCodecMethod(h.method);
    m.bits = h.bits;
    m.key_frame = !delta;
    m.sequence = h.sequence;
    m.reference_sequence = h.reference_sequence;
    m.shift = Eigen::Vector3i(h.shift[0], h.shift[1], h.shift[2]);
    m.message_bytes = size;
    m.payload_bytes = h.payload_size;
    m.raw_bytes = h.raw_size;
    m.mask_bytes = h.mask_bytes;
    m.band_samples = h.band_count;
    *info = m;
  }
  return true;
}

}  // namespace cvephands
