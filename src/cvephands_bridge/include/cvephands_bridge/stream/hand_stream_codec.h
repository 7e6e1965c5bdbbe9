// Hand stream codec (DESIGN.md section 4, "Hand meshes and the CVE"): one binary message per
// tracked hand per frame, carrying what a remote client needs to rebuild the hand mesh: the
// target id, the stamp, the sub-volume's world placement and a probability volume that marching
// cubes (iso_byte + 0.5, close_at_border) turns into the same mesh topology with vertices within
// a fraction of a voxel of the original. The client re-runs marching cubes itself.
//
// What is sent, and why (bench/bench_hand_codec.cpp on 1000 real 83^3 sub-volumes of the
// simulated rig, "all" script, both hands; per hand at 25 fps; distances between the decoded and
// the original mesh, point to triangle both ways):
// - Marching cubes reads a sample's value only when the sample is on a crossed edge (the "band":
//   a 6-neighbour on the other side of the iso); everywhere else it needs one bit, above the iso
//   or not. So a message carries the above-iso MASK exactly (identical triangles, lossless) and
//   one quantised CODE per band sample (~2 % of the samples); the decoder sets every other
//   sample to 0 or 255.
// - The raw volume barely compresses (pSfS leaves low noise everywhere, no sample is exactly
//   0): zstd gives ~260 kB per frame, 52 Mbit/s. The default (2 bits, deltas): 4.2 kB mean,
//   0.85 Mbit/s (1.31 with short sleeves, i.e. forearm skin in the cube), 0.14 mm mean, 0.47 mm
//   p95. 3 bits: 1.09 Mbit/s, 0.08 mm, but 1.69 Mbit/s with short sleeves.
// - The mask is coded as the positions of the samples that differ from a prediction (the
//   sample one z-slice below, or in a delta frame the previous frame's mask moved by the
//   cube's shift), as varint gaps: ~2.2 kB; a packed bit mask is ~35 % larger under zstd.
// - Codes: per band sample, a level index in a per-message table for its CONTEXT (side of the
//   iso x number of opposite-side neighbours, 12 contexts). The encoder fits each context's
//   levels to the frame (Lloyd) and numbers them by use, so the same small codes dominate in
//   every context and zstd's entropy stage sees a peaked distribution. 2 such bits are more
//   accurate than 3 bits of evenly spaced levels (0.14 vs 0.18 mm mean) and 18 % smaller.
// - The whole band-quantised volume (non-band samples 0/255) under zstd: 2.5x the size.
// - Temporal deltas help only while the cube stands still: sensor noise flips thousands of mask
//   samples per frame even on a resting hand. The delta mask is then ~20 % smaller, once the
//   cube moves it is larger; overall -8 %. The encoder picks per frame whichever predictor
//   leaves fewer residual samples, with a key frame at least every keyframe_interval frames so
//   a client can join late; a delta frame needs the previous frame of its target.
// - A quantised mesh (vertices on a 1/16 voxel lattice, delta + varint coded, indices as
//   varint differences, zstd): ~75 kB, 15 Mbit/s, ~18x the default: a marching-cubes mesh
//   spends most of its bytes on connectivity that the mask implies for free.
// Encode and decode cost per hand: see docs/benchmarks.md (bench_hand_codec).
//
// Wire format, version 1. All fields little endian; f64 = IEEE 754 binary64. Offsets in bytes.
//   0  u8[4] magic "CVHS"
//   4  u8    version (1)
//   5  u8    method: 0 = raw (the volume bytes, lossless), 1 = band (mask + band codes)
//   6  u8    flags: bit 0 = delta frame (method 1 only); other bits 0
//   7  u8    bits: band code bits 0..8 (method 1); 0 for method 0
//   8  u32   target id
//  12  u32   sequence number of this message in its stream (the encoder counts from 0)
//  16  u32   stamp seconds
//  20  u32   stamp nanoseconds (< 10^9)
//  24  f64x3 origin: world position of the min corner of voxel (0,0,0), metres, |.| <= 1e4
//  48  f64   voxel size, metres, 0 < . <= 1
//  56  u16x3 dims x, y, z: 1..256 each (so at most 2^24 samples)
//  62  u8    iso byte: a sample is above the iso iff its value > iso byte; 1..254 (153: p 0.6)
//  63  u8    reserved, 0
//  64  u32   reference sequence: delta frames only (the previous message of the target), else 0
//  68  i16x3 shift: delta frames only, else 0: the reference sample of voxel (x,y,z) is
//            (x,y,z) + shift (|shift| <= 256 per axis; outside the reference = below)
//  74  u16   reserved, 0
//  76  u32   band count: samples in the band (method 1), else 0
//  80  u32   mask bytes: size of the mask section of the raw payload (method 1), else 0
//  84  u32   raw size: decompressed payload size
//  88  u32   payload size P: bytes of the zstd frame that follows
//  92  u8[P] payload: ONE zstd frame (format of RFC 8878) whose header states the content size
//            (= raw size); no dictionary
//  92+P u32  CRC-32 (zlib / PNG polynomial) of bytes [0, 92 + P)
// Raw payload of method 0: the N = dims.x*dims.y*dims.z volume bytes, x fastest, then y, z.
// Raw payload of method 1, three sections back to back:
//   tables: 12 x 2^bits bytes; entry [c * 2^bits + code] is the value of that code in context
//           c = side * 6 + (k - 1), side 1 = above the iso, k = neighbours on the other side.
//           Values of side 0 contexts are <= iso byte, of side 1 > iso byte.
//   mask:   varints (unsigned LEB128, <= 4 bytes each): the residual's set samples in raster
//           order, each as the gap from the previous one + 1 (the first: its index). The mask is
//           above = residual XOR prediction, where prediction(x,y,z) = above(x,y,z-1) (0 for
//           z = 0) in a key frame, and the reference frame's above((x,y,z) + shift) in a delta
//           frame. Every index < N; the section ends exactly at its size.
//   codes:  one code per band sample in raster order, floor(8/bits) codes per byte (bits 1: 8,
//           2: 4, 3 and 4: 2, 5..8: 1; bits 0: no section), lowest bits first; unused bits 0.
//           Exactly ceil(band count / floor(8/bits)) bytes.
// Decoding a band message: mask -> band and contexts (a sample is in the band iff one of its 6
// neighbours, outside the volume counting as below, is on the other side; context from its
// side and that count) -> band count must match -> value = table[context][code] for band
// samples, 255 / 0 for the rest. A browser client can do this with a zstd decompressor in JS
// (expected: fzstd, pure JS, decompress-only) and a table CRC-32, then run marching cubes.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "cvephands_bridge/mesh/probability_grid.h"

namespace cvephands {

// One tracked hand in one frame: the sub-volume in the VoxelVolume layout (DESIGN.md section 3).
// The sub-volume is axis-aligned in the world frame, so its world pose is its origin.
struct HandFrame {
  uint32_t target_id = 0;
  uint32_t stamp_sec = 0, stamp_nsec = 0;
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  // min corner of voxel (0,0,0), world (m)
  double voxel_size = 0.0;                           // m
  Eigen::Vector3i dims = Eigen::Vector3i::Zero();    // 1..256 per axis
  std::vector<uint8_t> data;                         // p = value / 255, x fastest, then y, z

  ProbabilityGridView view() const {
    ProbabilityGridView g;
    g.data = data.empty() ? nullptr : data.data();
    g.dims = dims;
    g.origin = origin;
    g.voxel_size = voxel_size;
    return g;
  }
};

enum class HandCodecMethod : uint8_t {
  kRaw = 0,   // zstd of the volume bytes: lossless, ~50 Mbit/s per hand; for recording / tests
  kBand = 1,  // exact above-iso mask + quantised band values (the stream's method)
};

struct HandStreamEncoderOptions {
  HandCodecMethod method = HandCodecMethod::kBand;
  // Band code bits (0..8; 2^bits levels per context). Measured on the simulated rig (key frames
  // only, kbit/s per hand at 25 fps / mean distance from the original mesh): 2 bits 919 / 0.14 mm,
  // 1427 with short sleeves (more skin in the cube); 3 bits 1158 / 0.08 mm but 1813 with short
  // sleeves, over the 1.5 Mbit/s budget; 0 bits (mask only) 454 / 0.65 mm; 8 bits exact vertices.
  int bits = 2;
  // Fit each context's levels to the frame (Lloyd) instead of spacing them evenly on the side.
  bool adaptive_levels = true;
  // A key frame at least every n frames (1: no delta frames). A late joiner waits at most
  // n frames (25 = 1 s at 25 fps).
  int keyframe_interval = 25;
  // zstd level: on these ~5 kB payloads 1 is as small as 3-9 (19: 1 % smaller, encodes 1.6x
  // slower).
  int zstd_level = 1;
  // Above the iso iff value > iso_byte: 153 is MarchingCubesOptions' default iso 153.5 (p 0.6).
  int iso_byte = 153;
  void validate() const;  // throws std::invalid_argument naming the field
};

// What one message is (filled by the encoder for what it wrote, by the decoder for what it read).
struct HandMessageInfo {
  HandCodecMethod method = HandCodecMethod::kBand;
  int bits = 0;
  bool key_frame = true;
  uint32_t sequence = 0;
  uint32_t reference_sequence = 0;                  // delta frames
  Eigen::Vector3i shift = Eigen::Vector3i::Zero();  // delta frames
  size_t message_bytes = 0;                         // whole message
  size_t payload_bytes = 0;                         // zstd frame
  size_t raw_bytes = 0;                             // decompressed payload
  size_t mask_bytes = 0;                            // mask section (method 1)
  size_t band_samples = 0;                          // method 1
};

// One per hand stream (it keeps the previous frame's mask for delta frames). Not thread-safe.
class HandStreamEncoder {
 public:
  // Throws std::invalid_argument for invalid options.
  explicit HandStreamEncoder(const HandStreamEncoderOptions& options = HandStreamEncoderOptions());
  ~HandStreamEncoder();
  HandStreamEncoder(HandStreamEncoder&&) noexcept;
  HandStreamEncoder& operator=(HandStreamEncoder&&) noexcept;

  const HandStreamEncoderOptions& options() const { return options_; }

  // Encodes one frame into `message` (replacing its content). Throws std::invalid_argument
  // (naming the field) for a frame the format cannot carry: dims outside 1..256, data size
  // != dims product, non-finite or out-of-range origin / voxel size, nanoseconds >= 10^9.
  void encode(const HandFrame& frame, std::vector<uint8_t>* message);
  std::vector<uint8_t> encode(const HandFrame& frame) {
    std::vector<uint8_t> m;
    encode(frame, &m);
    return m;
  }
  // The next frame is a key frame (e.g. when a client joins).
  void requestKeyFrame();
  const HandMessageInfo& lastMessage() const { return last_; }

 private:
  struct State;
  HandStreamEncoderOptions options_;
  HandMessageInfo last_;
  std::unique_ptr<State> state_;
};

// Decodes messages of any number of streams (keeps the last decoded frame's mask per target id
// for delta frames, for the 16 most recently seen targets). Not thread-safe.
class HandStreamDecoder {
 public:
  HandStreamDecoder();
  ~HandStreamDecoder();
  HandStreamDecoder(HandStreamDecoder&&) noexcept;
  HandStreamDecoder& operator=(HandStreamDecoder&&) noexcept;

  // Never throws on bad input and never reads outside [data, data + size). On success fills
  // `out` (and `info` if given) and returns true. On failure returns false with a one-line
  // reason (e.g. "checksum mismatch", "missing reference frame: ..."), leaves `out` in an
  // unspecified but valid state and keeps the reference frames as they were. Allocation: up to
  // ~10 bytes per sample of the message's dims (170 MB at 256^3), only once the header, the
  // checksum and the zstd frame header agree on the sizes.
  bool decode(const uint8_t* data, size_t size, HandFrame* out, std::string* reason,
              HandMessageInfo* info = nullptr);
  bool decode(const std::vector<uint8_t>& message, HandFrame* out, std::string* reason,
              HandMessageInfo* info = nullptr) {
    return decode(message.data(), message.size(), out, reason, info);
  }
  // Forgets all reference frames (delta frames are rejected until the next key frame).
  void reset();

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace cvephands
