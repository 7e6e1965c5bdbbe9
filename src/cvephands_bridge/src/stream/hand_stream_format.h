// Internals of the hand stream wire format shared by the encoder and the decoder (the format
// itself is documented in include/cvephands_bridge/stream/hand_stream_codec.h): header layout,
// little-endian field access, CRC-32, varints, and the band classification both sides must
// compute identically from the above-iso mask.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

namespace cvephands {
namespace wire {

constexpr uint8_t kMagic[4] = {'C', 'V', 'H', 'S'};
constexpr uint8_t kVersion = 1;
constexpr size_t kHeaderSize = 92;
constexpr size_t kTrailerSize = 4;  // CRC-32
constexpr int kMaxSide = 256;
constexpr size_t kMaxVoxels = size_t(1) << 24;
static_assert(size_t(kMaxSide) * kMaxSide * kMaxSide == kMaxVoxels,
              "dims cap implies the total cap");
constexpr double kMaxVoxelSize = 1.0;    // m
constexpr double kMaxAbsOrigin = 1.0e4;  // m
constexpr int kMaxShift = 256;           // voxels, per axis
constexpr int kContexts = 12;            // side (2) x opposite-side neighbours (1..6)
constexpr int kMaxBits = 8;
constexpr uint8_t kFlagDelta = 1;

enum Method : uint8_t { kMethodRaw = 0, kMethodBand = 1 };

// Field by field as on the wire (offsets in the public header's table).
struct Header {
  uint8_t version = kVersion, method = kMethodBand, flags = 0, bits = 0;
  uint32_t target_id = 0, sequence = 0, stamp_sec = 0, stamp_nsec = 0;
  double origin[3] = {0, 0, 0};
  double voxel_size = 0;
  uint16_t dims[3] = {0, 0, 0};
  uint8_t iso_byte = 0, reserved0 = 0;
  uint32_t reference_sequence = 0;
  int16_t shift[3] = {0, 0, 0};
  uint16_t reserved1 = 0;
  uint32_t band_count = 0, mask_bytes = 0, raw_size = 0, payload_size = 0;
};

void writeHeader(const Header& h, uint8_t* out);  // kHeaderSize bytes, magic included
void readHeader(const uint8_t* in, Header* h);    // no checks (magic not read)

// CRC-32 as in zlib / PNG / IEEE 802.3 (reflected polynomial 0xEDB88320, init and final xor
// 0xFFFFFFFF): crc32("123456789") = 0xCBF43926.
uint32_t crc32(const uint8_t* data, size_t size);

inline void putU32(uint8_t* p, uint32_t v) {
  for (int i = 0; i < 4; ++i) p[i] = uint8_t(v >> (8 * i));
}
inline uint32_t getU32(const uint8_t* p) {
  return uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24;
}

// Unsigned LEB128: 7 bits per byte, low group first, high bit = more follows. Values here are
// below 2^24, so at most 4 bytes; the reader rejects anything longer (a 4th byte >= 0x80).
inline void putVarint(std::vector<uint8_t>* out, uint32_t v) {
  while (v >= 0x80) {
    out->push_back(uint8_t(v | 0x80));
    v >>= 7;
  }
  out->push_back(uint8_t(v));
}
// Reads one varint from [*p, end); false if it is unterminated or longer than 4 bytes.
inline bool getVarint(const uint8_t** p, const uint8_t* end, uint32_t* v) {
  uint32_t r = 0;
  for (int i = 0; i < 4 && *p < end; ++i) {
    const uint8_t b = *(*p)++;
    r |= uint32_t(b & 0x7f) << (7 * i);
    if (!(b & 0x80)) {
      *v = r;
      return true;
    }
  }
  return false;
}

inline int levelsFor(int bits) { return 1 << bits; }
inline size_t tableBytes(int bits) { return size_t(kContexts) << bits; }
// Band codes are packed whole into bytes, low bits first: 8/bits codes per byte (bits 3 and 4
// both give 2), so a code never straddles a byte and zstd's byte-wise entropy coder sees pairs
// or quads of codes as one symbol (measured: 15 % smaller than one code per byte at 3 bits).
inline int codesPerByte(int bits) { return bits == 0 ? 0 : 8 / bits; }
inline size_t codeBytes(size_t band_count, int bits) {
  const int k = codesPerByte(bits);
  return k == 0 ? 0 : (band_count + size_t(k) - 1) / size_t(k);
}

// The band: samples with at least one of their 6 neighbours on the other side of the iso
// (outside the volume counts as below, as MarchingCubesOptions::close_at_border does). Only
// their values move mesh vertices. Writes context[i] = 0 for samples outside the band, else
// 1 + side * 6 + (opposite neighbours - 1) (side 1 = above), and returns the band's size.
// `above` holds one 0/1 byte per sample; `padded` is scratch.
size_t classifyBand(const uint8_t* above, int nx, int ny, int nz, std::vector<uint8_t>* padded,
                    uint8_t* context);

// Byte loops over whole volumes, out of line with restrict pointers so that GCC vectorises them
// (-O3; inlined, the restrict is lost and a uint8_t store may alias anything).
void aboveIso(const uint8_t* in, size_t n, uint8_t iso, uint8_t* out);  // out[i] = in[i] > iso
void xorInto(uint8_t* dst, const uint8_t* src, size_t n);               // dst[i] ^= src[i]
void maskToBytes(const uint8_t* mask, size_t n, uint8_t* out);          // 0 / 1 -> 0 / 255

// Calls f(i, context[i]) for the band samples in raster order, skipping 8 samples at a time
// where there are none (the band is ~2 % of a hand sub-volume).
template <typename F>
inline void forEachBandSample(const uint8_t* context, size_t n, F f) {
  size_t i = 0;
  for (; i + 8 <= n; i += 8) {
    uint64_t w;
    std::memcpy(&w, context + i, 8);
    if (!w) continue;
    for (size_t j = i; j < i + 8; ++j)
      if (context[j]) f(j, context[j]);
  }
  for (; i < n; ++i)
    if (context[i]) f(i, context[i]);
}

// out(x,y,z) = mask(x + sx, y + sy, z + sz), 0 outside the mask's volume: the prediction of a
// delta frame (and, with shift (0,0,-1), of a key frame: the slice below).
void shiftedMask(const uint8_t* mask, int nx, int ny, int nz, int sx, int sy, int sz, uint8_t* out);

}  // namespace wire
}  // namespace cvephands
