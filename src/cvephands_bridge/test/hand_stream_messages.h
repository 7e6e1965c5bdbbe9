// Byte-level access to hand stream messages for the codec tests: the field offsets of the wire
// format (as documented in hand_stream_codec.h, written out again here on purpose: the tests
// check the documentation, like the browser client will rely on it), field overwrites with the
// checksum recomputed, and payload rewrites (decompress, edit, recompress) to reach the parser
// behind the checksum and behind zstd.
#pragma once

#include <zstd.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <vector>

namespace cvephands_test {

using Message = std::vector<uint8_t>;

namespace field {  // offsets
constexpr size_t kMagic = 0, kVersion = 4, kMethod = 5, kFlags = 6, kBits = 7, kTarget = 8,
                 kSequence = 12, kStampSec = 16, kStampNsec = 20, kOrigin = 24, kVoxel = 48,
                 kDims = 56, kIso = 62, kReserved0 = 63, kRefSequence = 64, kShift = 68,
                 kReserved1 = 74, kBandCount = 76, kMaskBytes = 80, kRawSize = 84,
                 kPayloadSize = 88, kPayload = 92;
}  // namespace field

// Bitwise CRC-32 (zlib polynomial), independent of the codec's table-driven one.
inline uint32_t referenceCrc32(const uint8_t* d, size_t n) {
  uint32_t c = 0xFFFFFFFFu;
  for (size_t i = 0; i < n; ++i) {
    c ^= d[i];
    for (int k = 0; k < 8; ++k) c = (c >> 1) ^ (0xEDB88320u & (0u - (c & 1u)));
  }
  return ~c;
}

inline void putLE(Message* m, size_t offset, uint64_t value, int bytes) {
  for (int i = 0; i < bytes; ++i) (*m)[offset + i] = uint8_t(value >> (8 * i));
}
inline uint64_t getLE(const Message& m, size_t offset, int bytes) {
  uint64_t v = 0;
  for (int i = 0; i < bytes; ++i) v |= uint64_t(m[offset + i]) << (8 * i);
  return v;
}
inline void putF64(Message* m, size_t offset, double v) {
  uint64_t b;
  std::memcpy(&b, &v, 8);
  putLE(m, offset, b, 8);
}
inline double getF64(const Message& m, size_t offset) {
  const uint64_t b = getLE(m, offset, 8);
  double v;
  std::memcpy(&v, &b, 8);
  return v;
}

// Rewrites the trailing CRC for the bytes before it (the message must be >= 4 bytes).
inline void fixCrc(Message* m) {
  putLE(m, m->size() - 4, referenceCrc32(m->data(), m->size() - 4), 4);
}
inline Message withField(Message m, size_t offset, uint64_t value, int bytes) {
  putLE(&m, offset, value, bytes);
  fixCrc(&m);
  return m;
}

inline std::vector<uint8_t> payloadOf(const Message& m) {
  const size_t p = getLE(m, field::kPayloadSize, 4);
  return std::vector<uint8_t>(m.begin() + field::kPayload, m.begin() + field::kPayload + p);
}
inline std::vector<uint8_t> rawPayloadOf(const Message& m) {
  const std::vector<uint8_t> z = payloadOf(m);
  std::vector<uint8_t> raw(getLE(m, field::kRawSize, 4));
  const size_t r = ZSTD_decompress(raw.data(), raw.size(), z.data(), z.size());
  if (ZSTD_isError(r) || r != raw.size())
    throw std::runtime_error("rawPayloadOf: not a valid message");
  return raw;
}
// Replaces the zstd frame (payload size and CRC updated; raw size left as it is).
inline Message withPayload(const Message& m, const std::vector<uint8_t>& zstd_frame) {
  Message out(field::kPayload + zstd_frame.size() + 4, 0);
  std::copy(m.begin(), m.begin() + field::kPayload, out.begin());
  std::copy(zstd_frame.begin(), zstd_frame.end(), out.begin() + field::kPayload);
  putLE(&out, field::kPayloadSize, zstd_frame.size(), 4);
  fixCrc(&out);
  return out;
}
inline std::vector<uint8_t> zstdFrame(const std::vector<uint8_t>& raw, int level = 3) {
  std::vector<uint8_t> z(ZSTD_compressBound(raw.size()));
  z.resize(ZSTD_compress(z.data(), z.size(), raw.data(), raw.size(), level));
  return z;
}
// Replaces the raw payload (recompressed; raw size, payload size and CRC updated).
inline Message withRawPayload(const Message& m, const std::vector<uint8_t>& raw) {
  Message out = withPayload(m, zstdFrame(raw));
  putLE(&out, field::kRawSize, raw.size(), 4);
  fixCrc(&out);
  return out;
}

}  // namespace cvephands_test
