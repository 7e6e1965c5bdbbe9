// Randomised test of the hand stream decoder: CVEPHANDS_FUZZ_MESSAGES (default 10^6) mutated
// messages from a corpus of valid ones (band messages of every code width, key and delta frames,
// raw messages, odd and extreme dims). Mutations: bit flips, byte changes, truncation,
// extension, random garbage (these never get past the checksum), and mutations with the
// checksum recomputed so the parser behind it is exercised: header field overwrites, zstd frame
// edits, payload edits behind zstd (decompress, edit, recompress), header / payload splices.
// Every message must either decode to a self-consistent frame or be rejected with a reason; the
// reasons are counted and printed. Built once at -O2 and once with ASan + UBSan (the sanitizer
// build catches out-of-bounds reads and UB that would not crash here).
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "cvephands_bridge/stream/hand_stream_codec.h"
#include "hand_stream_messages.h"
#include "synthetic_hand_motion.h"

#ifndef CVEPHANDS_FUZZ_MESSAGES
#define CVEPHANDS_FUZZ_MESSAGES 1000000
#endif

namespace {

using cvephands::HandCodecMethod;
using cvephands::HandFrame;
using cvephands::HandMessageInfo;
using cvephands::HandStreamDecoder;
using cvephands::HandStreamEncoder;
using cvephands::HandStreamEncoderOptions;
using namespace cvephands_test;

struct Entry {
  Message message;
  int reference = -1;  // corpus index of the message a delta frame needs decoded first
  double weight = 1.0;
};

// A few random spheres in a box of any dims (cubes come from the synthetic hand).
HandFrame blobs(const Eigen::Vector3i& dims, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double voxel = 0.01;
  std::vector<Sdf> parts;
  for (int i = 0; i < 3; ++i)
    parts.push_back(
        sphere(voxel * dims.cast<double>().cwiseProduct(Eigen::Vector3d(u(rng), u(rng), u(rng))),
               voxel * (1.0 + 0.3 * dims.minCoeff() * u(rng))));
  TestVolume v = sampleSdf(dims, Eigen::Vector3d::Zero(), voxel, unite(parts), 2 * voxel);
  addNoise(&v, 30, seed);
  HandFrame f;
  f.target_id = seed;
  f.voxel_size = voxel;
  f.dims = dims;
  f.data = std::move(v.data);
  return f;
}

std::vector<Entry> makeCorpus() {
  std::vector<Entry> corpus;
  auto stream = [&](const std::vector<HandFrame>& frames, const HandStreamEncoderOptions& o,
                    double w) {
    HandStreamEncoder enc(o);
    for (size_t i = 0; i < frames.size(); ++i) {
      Entry e;
      e.message = enc.encode(frames[i]);
      e.reference = enc.lastMessage().key_frame ? -1 : int(corpus.size()) - 1;
      e.weight = w;
      corpus.push_back(std::move(e));
    }
  };
  HandStreamEncoderOptions o;
  for (int bits : {0, 1, 2, 3, 4, 5, 8}) {  // a resting hand: key + delta frames
    o.bits = bits;
    o.keyframe_interval = 3;
    std::vector<HandFrame> frames;
    for (int f = 20; f < 24; ++f) frames.push_back(syntheticHandFrame(f, bits % 2, 12 + 2 * bits));
    stream(frames, o, 1.0);
  }
  o = HandStreamEncoderOptions();
  for (int f = 0; f < 3; ++f) stream({syntheticHandFrame(f * 7, 1, 20)}, o, 1.0);  // moving
  stream({blobs({7, 13, 29}, 3), blobs({31, 5, 9}, 4), blobs({1, 1, 1}, 5), blobs({2, 40, 3}, 6)},
         o, 1.0);
  HandFrame all_above = blobs({9, 8, 7}, 7), all_below = all_above;
  std::fill(all_above.data.begin(), all_above.data.end(), 200);  // band = the volume's faces
  std::fill(all_below.data.begin(), all_below.data.end(), 20);   // empty band and mask
  stream({all_above, all_below}, o, 0.5);
  o.method = HandCodecMethod::kRaw;
  stream({syntheticHandFrame(4, 0, 16), blobs({6, 9, 4}, 8)}, o, 1.0);
  o = HandStreamEncoderOptions();
  stream({syntheticHandFrame(20, 0), syntheticHandFrame(21, 0)}, o, 0.01);  // full size, rare
  return corpus;
}

struct Field {
  size_t offset;
  int bytes;
  bool f64;
};
const Field kFields[] = {
    {field::kVersion, 1, false},   {field::kMethod, 1, false},     {field::kFlags, 1, false},
    {field::kBits, 1, false},      {field::kTarget, 4, false},     {field::kSequence, 4, false},
    {field::kStampSec, 4, false},  {field::kStampNsec, 4, false},  {field::kOrigin, 8, true},
    {field::kOrigin + 8, 8, true}, {field::kOrigin + 16, 8, true}, {field::kVoxel, 8, true},
    {field::kDims, 2, false},      {field::kDims + 2, 2, false},   {field::kDims + 4, 2, false},
    {field::kIso, 1, false},       {field::kReserved0, 1, false},  {field::kRefSequence, 4, false},
    {field::kShift, 2, false},     {field::kShift + 2, 2, false},  {field::kShift + 4, 2, false},
    {field::kReserved1, 2, false}, {field::kBandCount, 4, false},  {field::kMaskBytes, 4, false},
    {field::kRawSize, 4, false},   {field::kPayloadSize, 4, false}};

class Mutator {
 public:
  explicit Mutator(uint32_t seed) : rng_(seed) {}
  uint32_t below(uint32_t n) { return n ? uint32_t(rng_() % n) : 0; }
  bool coin(int one_in) { return below(uint32_t(one_in)) == 0; }
  uint8_t byte() { return uint8_t(rng_()); }

  uint64_t interestingInt(uint64_t current, int bytes) {
    const uint64_t max = bytes == 8 ? ~uint64_t(0) : (uint64_t(1) << (8 * bytes)) - 1;
    switch (below(7)) {
      case 0:
        return 0;
      case 1:
        return 1;
      case 2:
        return max;
      case 3:
        return (current + 1) & max;
      case 4:
        return (current - 1) & max;
      case 5:
        return below(300);
      default:
        return (uint64_t(rng_()) << 32 | rng_()) & max;
    }
  }
  double interestingDouble(double current) {
    switch (below(9)) {
      case 0:
        return std::numeric_limits<double>::quiet_NaN();
      case 1:
        return below(2) ? std::numeric_limits<double>::infinity()
                        : -std::numeric_limits<double>::infinity();
      case 2:
        return 0.0;
      case 3:
        return -0.0;
      case 4:
        return std::numeric_limits<double>::denorm_min();
      case 5:
        return 1e300;
      case 6:
        return current * (1.0 + 1e-12);
      case 7:
        return current + (int(below(5)) - 2) * 0.01;
      default: {
        const uint64_t b = uint64_t(rng_()) << 32 | rng_();
        double d;
        std::memcpy(&d, &b, 8);
        return d;
      }
    }
  }

  // Returns the mutated message and the mutation's name.
  Message mutate(const std::vector<Entry>& corpus, const Entry& e, const char** kind) {
    Message m = e.message;
    switch (below(10)) {
      case 0: {
        *kind = "bit flips";
        for (uint32_t k = 1 + below(8); k > 0; --k)
          m[below(uint32_t(m.size()))] ^= uint8_t(1u << below(8));
        return m;
      }
      case 1: {
        *kind = "byte changes";
        for (uint32_t k = 1 + below(4); k > 0; --k)
          m[below(uint32_t(m.size()))] = coin(3) ? 0 : coin(2) ? 0xff : byte();
        return m;
      }
      case 2:
        *kind = "truncation";
        m.resize(below(uint32_t(m.size())));
        return m;
      case 3: {
        *kind = "extension";
        for (uint32_t k = 1 + below(64); k > 0; --k) m.push_back(byte());
        return m;
      }
      case 4: {
        *kind = "field + crc";
        for (uint32_t k = 1 + below(3); k > 0; --k) {
          const Field& f = kFields[below(sizeof(kFields) / sizeof(kFields[0]))];
          if (f.f64)
            putF64(&m, f.offset, interestingDouble(getF64(m, f.offset)));
          else
            putLE(&m, f.offset, interestingInt(getLE(m, f.offset, f.bytes), f.bytes), f.bytes);
        }
        fixCrc(&m);
        return m;
      }
      case 5: {
        *kind = "zstd bytes + crc";
        const size_t p = getLE(m, field::kPayloadSize, 4);
        for (uint32_t k = 1 + below(4); k > 0 && p > 0; --k) {
          uint8_t& b = m[field::kPayload + below(uint32_t(p))];
          b = coin(2) ? uint8_t(b ^ (1u << below(8))) : byte();
        }
        fixCrc(&m);
        return m;
      }
      case 6:
      case 7: {
        *kind = "payload + zstd + crc";
        std::vector<uint8_t> raw = rawPayloadOf(m);
        const size_t tables = m[field::kMethod] == 1 ? size_t(12) << m[field::kBits] : 0;
        const size_t mask_end = tables + getLE(m, field::kMaskBytes, 4);
        switch (below(6)) {
          case 0:  // flips anywhere
            for (uint32_t k = 1 + below(4); k > 0 && !raw.empty(); --k)
              raw[below(uint32_t(raw.size()))] ^= uint8_t(1u << below(8));
            break;
          case 1:  // bytes in the mask section
            for (uint32_t k = 1 + below(3); k > 0 && mask_end > tables; --k)
              raw[tables + below(uint32_t(mask_end - tables))] = byte();
            break;
          case 2:  // a table entry
            if (tables) raw[below(uint32_t(tables))] = byte();
            break;
          case 3: {  // insert or remove bytes (the section sizes then disagree unless fixed below)
            const size_t at = below(uint32_t(raw.size() + 1));
            if (coin(2))
              raw.insert(raw.begin() + at, 1 + below(4), byte());
            else if (at < raw.size())
              raw.erase(raw.begin() + at);
            break;
          }
          case 4:  // truncate or extend
            raw.resize(below(uint32_t(raw.size() * 2 + 2)), byte());
            break;
          default:  // the last code byte
            if (!raw.empty()) raw.back() = byte();
        }
        Message out = withRawPayload(m, raw);
        if (coin(2)) {  // keep the sections adding up, so the band parser sees it
          const int64_t d = int64_t(raw.size()) - int64_t(getLE(m, field::kRawSize, 4));
          putLE(&out, field::kMaskBytes, uint32_t(int64_t(getLE(m, field::kMaskBytes, 4)) + d), 4);
          if (coin(3))
            putLE(&out, field::kBandCount, getLE(m, field::kBandCount, 4) + below(5) - 2, 4);
          fixCrc(&out);
        }
        return out;
      }
      case 8: {
        *kind = "splice + crc";
        const Message& other = corpus[below(uint32_t(corpus.size()))].message;
        Message s(m.begin(), m.begin() + field::kPayload);
        s.insert(s.end(), other.begin() + field::kPayload, other.end());
        if (coin(2)) putLE(&s, field::kPayloadSize, other.size() - field::kPayload - 4, 4);
        fixCrc(&s);
        return s;
      }
      default: {
        *kind = "garbage";
        Message g(below(200));
        for (uint8_t& b : g) b = byte();
        if (g.size() >= 5 && coin(2)) std::memcpy(g.data(), "CVHS\x01", 5);
        if (g.size() >= 4 && coin(2)) fixCrc(&g);
        return g;
      }
    }
  }

 private:
  std::mt19937 rng_;
};

// Decodes the chain of messages entry `i` needs, so delta frames meet their reference.
void prime(HandStreamDecoder* d, const std::vector<Entry>& corpus, int i) {
  if (corpus[i].reference >= 0) prime(d, corpus, corpus[i].reference);
  HandFrame f;
  std::string why;
  ASSERT_TRUE(d->decode(corpus[i].message, &f, &why)) << "corpus entry " << i << ": " << why;
}

std::string reasonKind(const std::string& why) {
  return why.substr(0, std::min(why.find_first_of("0123456789("), why.size()));
}

TEST(HandStreamFuzz, MutatedMessagesAreDecodedConsistentlyOrRejectedWithAReason) {
  const auto t0 = std::chrono::steady_clock::now();
  const std::vector<Entry> corpus = makeCorpus();
  std::vector<double> weights;
  for (const Entry& e : corpus) weights.push_back(e.weight);
  std::discrete_distribution<int> pick(weights.begin(), weights.end());
  std::mt19937 pick_rng(12345);
  Mutator mutator(2024);
  HandStreamDecoder decoder;
  std::map<std::string, long> reasons, accepted;
  long unguarded_accepted = 0;
  HandFrame out;
  std::string why;
  HandMessageInfo info;
  const long total = CVEPHANDS_FUZZ_MESSAGES;
  for (long i = 0; i < total; ++i) {
    const int k = pick(pick_rng);
    const Entry& e = corpus[k];
    if (e.reference >= 0 && !mutator.coin(8)) prime(&decoder, corpus, e.reference);
    const char* kind = "";
    const Message m = mutator.mutate(corpus, e, &kind);
    why.clear();
    if (decoder.decode(m.data(), m.size(), &out, &why, &info)) {
      ++accepted[kind];
      // Mutations that leave the checksum stale must never get through.
      const std::string k2 = kind;
      if ((k2 == "bit flips" || k2 == "byte changes" || k2 == "truncation" || k2 == "extension") &&
          m != e.message)
        ++unguarded_accepted;
      ASSERT_TRUE((out.dims.array() >= 1).all() && (out.dims.array() <= 256).all()) << kind;
      ASSERT_EQ(out.data.size(), size_t(out.dims.prod())) << kind;
      ASSERT_TRUE(out.origin.allFinite() && out.origin.cwiseAbs().maxCoeff() <= 1e4) << kind;
      ASSERT_TRUE(std::isfinite(out.voxel_size) && out.voxel_size > 0 && out.voxel_size <= 1)
          << kind;
      ASSERT_LT(out.stamp_nsec, 1000000000u) << kind;
      ASSERT_EQ(info.message_bytes, m.size()) << kind;
    } else {
      ASSERT_FALSE(why.empty()) << kind;
      ++reasons[reasonKind(why)];
    }
  }
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("[ figures ] %ld mutated messages from %zu valid ones in %.1f s\n", total,
              corpus.size(), s);
  for (const auto& r : reasons)
    std::printf("[ figures ]   rejected %9ld  %s\n", r.second, r.first.c_str());
  for (const auto& a : accepted)
    std::printf("[ figures ]   accepted %9ld  (%s)\n", a.second, a.first.c_str());
  EXPECT_EQ(unguarded_accepted, 0);
  // The checksum-fixed mutations must reach the parser behind it: header, zstd and band layers.
  for (const std::string r :
       {"checksum mismatch", "size mismatch", "unknown method", "dims out of range",
        "zstd: ", "missing reference frame: target ", "table value ", "mask: bad varint",
        "mask: sample index", "band count mismatch", "codes: nonzero"}) {
    long n = 0;
    for (const auto& kv : reasons) n += kv.first.compare(0, r.size(), r) == 0 ? kv.second : 0;
    EXPECT_GT(n, 0) << r;
  }
}

}  // namespace
