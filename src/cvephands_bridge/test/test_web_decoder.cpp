// The browser client's decoder and marching cubes (web/src/hand_decoder.js, marching_cubes.js)
// against the C++ ones: real hand sub-volumes of the simulated rig are encoded into one stream
// (both hands, key and delta frames, code widths 0, 2, 3, 8 and the raw method) with corrupted
// messages in between; C++ decodes and meshes every message and writes the fixture, and
// web/test/cross_check.mjs (Node) decodes the same sequence with one decoder and compares:
// identical volumes, identical triangles, vertices within 1e-4 voxel, the same rejections with
// the same reasons.
#include <gtest/gtest.h>
#include <stdlib.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "cvephands_bridge/eval/sim_hand_volumes.h"
#include "cvephands_bridge/mesh/marching_cubes.h"
#include "cvephands_bridge/stream/hand_stream_codec.h"
#include "hand_stream_messages.h"

namespace {

namespace fs = std::filesystem;
using cvephands::HandCodecMethod;
using cvephands::HandFrame;
using cvephands::HandStreamDecoder;
using cvephands::HandStreamEncoder;
using cvephands::HandStreamEncoderOptions;
using cvephands::TriangleMesh;
using namespace cvephands_test;

std::vector<HandFrame> simulatedHands(int frames) {
  cvephands::SimHandVolumeOptions so;
  so.script = "wave";  // the left hand waves, the right one rests: deltas for the right
  so.frames = frames;
  so.skin_model = CVEPHANDS_SKIN_MODEL;
  std::vector<HandFrame> out;
  for (cvephands::SimHandVolume& v : cvephands::recordSimHandVolumes(so))
    out.push_back(cvephands::toHandFrame(std::move(v)));
  return out;
}

// One entry of the fixture's sequence: a message the decoder must accept, or one it must reject.
struct Entry {
  Message message;
  bool good = true;
};

// Corrupted messages, from a band key frame (2 bits), a 3-bit band key frame (2 codes per byte:
// padding bits), a raw message and a delta frame whose reference the decoder holds at that point
// of the sequence. Each reaches a different check of the decoder (as in
// test_hand_stream_codec.cpp's EveryRejectionHasItsReason).
std::vector<Message> corruptedMessages(const Message& key, const Message& key3, const Message& raw,
                                       const Message& delta) {
  using namespace field;
  auto edited = [](Message m, auto edit) {
    edit(&m);
    fixCrc(&m);
    return m;
  };
  auto rawEdited = [](const Message& base, auto edit) {
    std::vector<uint8_t> r = rawPayloadOf(base);
    Message m = base;
    edit(&r, &m);
    return withRawPayload(m, r);
  };
  const size_t n = getLE(key, kDims, 2) * getLE(key, kDims + 2, 2) * getLE(key, kDims + 4, 2);
  const size_t tables3 = 12 * 8, mask3 = getLE(key3, kMaskBytes, 4);
  const std::vector<uint8_t> key_raw = rawPayloadOf(key);
  std::vector<Message> v;
  // envelope
  v.push_back(Message(key.begin(), key.begin() + 50));
  v.push_back(Message());
  v.push_back(edited(key, [](Message* m) { (*m)[0] = 'X'; }));
  v.push_back(edited(key, [](Message* m) { (*m)[kVersion] = 2; }));
  v.push_back(Message(key.begin(), key.end() - 1));
  Message flipped = key;
  flipped[kPayload + 3] ^= 0x10;
  v.push_back(flipped);
  // header fields
  v.push_back(withField(key, kMethod, 2, 1));
  v.push_back(withField(key, kFlags, 2, 1));
  v.push_back(withField(raw, kFlags, 1, 1));
  v.push_back(withField(key, kBits, 9, 1));
  v.push_back(withField(key, kReserved1, 1, 2));
  v.push_back(withField(key, kStampNsec, 1000000000, 4));
  v.push_back(edited(key, [](Message* m) {
    putF64(m, kOrigin + 8, std::numeric_limits<double>::quiet_NaN());
  }));
  v.push_back(edited(key, [](Message* m) { putF64(m, kVoxel, 0.0); }));
  v.push_back(withField(key, kDims + 2, 0, 2));
  v.push_back(withField(key, kDims + 4, 257, 2));
  v.push_back(withField(key, kIso, 255, 1));
  v.push_back(withField(key, kRefSequence, 5, 4));
  v.push_back(withField(delta, kShift + 2, uint16_t(-300), 2));
  v.push_back(withField(raw, kBandCount, 1, 4));
  v.push_back(withField(raw, kRawSize, n + 1, 4));
  v.push_back(withField(key, kBandCount, n + 1, 4));
  v.push_back(withField(key, kMaskBytes, 4 * n + 1, 4));
  v.push_back(withField(key, kMaskBytes, getLE(key, kMaskBytes, 4) + 1, 4));
  // references
  v.push_back(withField(delta, kTarget, 777, 4));
  v.push_back(withField(delta, kRefSequence, getLE(delta, kRefSequence, 4) + 5, 4));
  v.push_back(edited(delta, [](Message* m) { putF64(m, kVoxel, getF64(*m, kVoxel) * 1.5); }));
  // zstd layer
  v.push_back(edited(key, [](Message* m) { (*m)[kPayload] ^= 0xff; }));
  {
    std::vector<uint8_t> bigger = key_raw;
    bigger.push_back(0);
    v.push_back(withPayload(key, zstdFrame(bigger)));
    std::vector<uint8_t> z = payloadOf(key);
    z.pop_back();
    v.push_back(withPayload(key, z));
    std::vector<uint8_t> two = payloadOf(key), second = zstdFrame({1, 2, 3});
    two.insert(two.end(), second.begin(), second.end());
    v.push_back(withPayload(key, two));
    for (bool content_size : {false, true}) {  // no content size; then a wrong XXH64 checksum
      ZSTD_CCtx* c = ZSTD_createCCtx();
      ZSTD_CCtx_setParameter(c, ZSTD_c_contentSizeFlag, content_size);
      ZSTD_CCtx_setParameter(c, ZSTD_c_checksumFlag, 1);
      std::vector<uint8_t> f(ZSTD_compressBound(key_raw.size()));
      f.resize(ZSTD_compress2(c, f.data(), f.size(), key_raw.data(), key_raw.size()));
      ZSTD_freeCCtx(c);
      f.back() ^= 0x01;
      v.push_back(withPayload(key, f));
    }
  }
  // behind zstd
  v.push_back(rawEdited(key3, [](std::vector<uint8_t>* r, Message*) { (*r)[0] = 200; }));
  v.push_back(rawEdited(key3, [](std::vector<uint8_t>* r, Message*) { (*r)[6 * 8] = 100; }));
  v.push_back(rawEdited(key3, [&](std::vector<uint8_t>* r, Message*) {
    (*r)[tables3 + mask3 - 1] |= 0x80;
  }));
  v.push_back(rawEdited(key3, [&](std::vector<uint8_t>* r, Message* m) {
    const uint8_t past_end[4] = {0xff, 0xff, 0xff, 0x7f};  // gap 2^28 - 1: beyond any volume
    r->insert(r->begin() + tables3 + mask3, past_end, past_end + 4);
    putLE(m, kMaskBytes, mask3 + 4, 4);
  }));
  v.push_back(rawEdited(key3, [&](std::vector<uint8_t>* r, Message* m) {
    r->push_back(0);
    putLE(m, kBandCount, getLE(*m, kBandCount, 4) + 2, 4);
  }));
  v.push_back(rawEdited(key3, [&](std::vector<uint8_t>* r, Message*) {
    (*r)[tables3 + mask3] |= 0x40;
  }));
  return v;
}

void writeFile(const fs::path& p, const void* data, size_t size) {
  std::ofstream f(p, std::ios::binary);
  f.write(static_cast<const char*>(data), std::streamsize(size));
  ASSERT_TRUE(f.good()) << p;
}

// u32 vertex count, u32 triangle count, f32 positions (3 per vertex), u32 indices (3 per
// triangle), f32 normals (3 per vertex).
void writeMesh(const fs::path& p, const TriangleMesh& m) {
  std::vector<uint8_t> b(8);
  const uint32_t counts[2] = {uint32_t(m.numVertices()), uint32_t(m.numTriangles())};
  std::memcpy(b.data(), counts, 8);
  auto append = [&](const void* d, size_t size) {
    b.insert(b.end(), static_cast<const uint8_t*>(d), static_cast<const uint8_t*>(d) + size);
  };
  append(m.vertices.data(), m.vertices.size() * sizeof(m.vertices[0]));
  append(m.triangles.data(), m.triangles.size() * sizeof(uint32_t));
  append(m.normals.data(), m.normals.size() * sizeof(m.normals[0]));
  writeFile(p, b.data(), b.size());
}

// The number after "key": in a one-line JSON object (NaN if absent).
double jsonNumber(const std::string& json, const std::string& key) {
  const size_t k = json.find("\"" + key + "\":");
  if (k == std::string::npos) return std::numeric_limits<double>::quiet_NaN();
  return std::strtod(json.c_str() + k + key.size() + 3, nullptr);
}

// Removes the fixture directory however the test ends.
struct TempDir {
  fs::path path;
  TempDir() {
    std::string t = (fs::temp_directory_path() / "cvephands_web_XXXXXX").string();
    if (mkdtemp(t.data())) path = t;
  }
  ~TempDir() {
    std::error_code ec;
    if (!path.empty()) fs::remove_all(path, ec);
  }
};

TEST(WebDecoder, MatchesTheCppDecoderAndMarchingCubes) {
  const fs::path web = CVEPHANDS_WEB_DIR;
  if (std::system("command -v node > /dev/null 2>&1") != 0) GTEST_SKIP() << "node is not on PATH";
  if (!fs::exists(web / "node_modules" / "fzstd" / "package.json"))
    GTEST_SKIP() << "fzstd is not installed in " << web << " (run npm install there)";

  // ---- the stream: 30 rig frames of both hands, then short streams of other code widths ----
  const std::vector<HandFrame> hands = simulatedHands(30);
  ASSERT_GE(hands.size(), 50u);  // both hands in the workspace in (nearly) every frame
  std::vector<Entry> seq;
  std::map<uint32_t, HandStreamEncoder> encoders;
  int deltas = 0;
  size_t delta_at = 0;  // a delta frame of the main stream
  for (const HandFrame& f : hands) {
    HandStreamEncoder& e = encoders.try_emplace(f.target_id).first->second;
    seq.push_back({e.encode(f)});
    if (!e.lastMessage().key_frame && ++deltas == 1) delta_at = seq.size() - 1;
  }
  ASSERT_GT(deltas, 0) << "no delta frame in the rig stream";
  ASSERT_GT(int(hands.size()) - deltas, 2);
  const Message key = seq[0].message;
  Message key3, raw;
  for (int bits : {0, 3, 8, -1}) {  // -1: the raw method
    HandStreamEncoderOptions o;
    o.method = bits < 0 ? HandCodecMethod::kRaw : HandCodecMethod::kBand;
    o.bits = std::max(bits, 0);
    HandStreamEncoder e(o);
    for (int k = 0; k < 4; ++k) {
      HandFrame f = hands[hands.size() - 8 + 2 * k];  // left before right: one hand
      f.target_id = uint32_t(100 + bits);
      seq.push_back({e.encode(f)});
      if (k == 0 && bits == 3) key3 = seq.back().message;
      if (k == 0 && bits < 0) raw = seq.back().message;
    }
  }
  // Random bytes, each above the iso with probability 1/2: every cell case ~40 times, so the
  // two case tables are compared whole (hands meet only some of the cases).
  {
    HandFrame f = hands[0];
    f.target_id = 300;
    f.dims = Eigen::Vector3i(24, 23, 22);
    f.data.resize(24 * 23 * 22);
    std::mt19937 rng(5);
    for (uint8_t& b : f.data) b = uint8_t(rng() % 2 ? 154 + rng() % 102 : rng() % 154);
    HandStreamEncoderOptions o;
    o.method = HandCodecMethod::kRaw;
    seq.push_back({HandStreamEncoder(o).encode(f)});
  }
  // The corrupted messages go just before the delta frame: its reference is the decoder's then.
  const Message delta = seq[delta_at].message;
  std::vector<Entry> bad;
  for (Message& m : corruptedMessages(key, key3, raw, delta)) bad.push_back({std::move(m), false});
  seq.insert(seq.begin() + long(delta_at), bad.begin(), bad.end());

  // ---- decode and mesh in C++, write the fixture ----
  TempDir dir;
  ASSERT_FALSE(dir.path.empty()) << "mkdtemp failed";
  HandStreamDecoder decoder;
  cvephands::MarchingCubesOptions mo;
  mo.threads = 1;
  cvephands::MarchingCubes mc(mo);
  size_t good = 0, rejected = 0;
  for (size_t i = 0; i < seq.size(); ++i) {
    char stem[32];
    std::snprintf(stem, sizeof(stem), "%s_%04zu", seq[i].good ? "msg" : "bad", i);
    const fs::path base = dir.path / stem;
    writeFile(base.string() + ".bin", seq[i].message.data(), seq[i].message.size());
    HandFrame out;
    std::string why;
    const bool ok = decoder.decode(seq[i].message, &out, &why);
    if (seq[i].good) {
      ASSERT_TRUE(ok) << stem << ": " << why;
      ++good;
      writeFile(base.string() + ".vol", out.data.data(), out.data.size());
      TriangleMesh m;
      mc.extract(out.view(), &m);
      writeMesh(base.string() + ".mesh", m);
    } else {
      ASSERT_FALSE(ok) << stem << " was accepted";
      ++rejected;
      writeFile(base.string() + ".txt", why.data(), why.size());
    }
  }

  // ---- the same sequence in Node ----
  const std::string cmd = "node \"" + (web / "test" / "cross_check.mjs").string() + "\" \"" +
                          dir.path.string() + "\" 2>&1";
  FILE* pipe = popen(cmd.c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  std::string output;
  char buf[4096];
  while (size_t got = std::fread(buf, 1, sizeof(buf), pipe)) output.append(buf, got);
  const int status = pclose(pipe);
  const size_t brace = output.rfind('{');
  ASSERT_NE(brace, std::string::npos) << output;
  const std::string json = output.substr(brace);
  std::printf("[ figures ] %zu messages (%d rig delta frames), %zu rejected; node: %s", good,
              deltas, rejected, json.c_str());
  EXPECT_EQ(status, 0) << output;
  EXPECT_EQ(jsonNumber(json, "messages"), double(good));
  EXPECT_EQ(jsonNumber(json, "volumes_identical"), double(good));
  EXPECT_EQ(jsonNumber(json, "meshes_identical_topology"), double(good));
  // Both compute each coordinate with the same double and float steps (no FMA contraction on
  // x86-64 without -march): bit-identical in practice; the bound is the brief's 1e-4 voxel.
  EXPECT_LE(jsonNumber(json, "max_vertex_error_m"), 1e-4 * hands[0].voxel_size);
  EXPECT_LE(jsonNumber(json, "max_normal_error"), 1e-5);  // unit vectors, same float steps
  EXPECT_EQ(jsonNumber(json, "rejected_bad"), double(rejected));
  EXPECT_EQ(jsonNumber(json, "reasons_identical"), double(rejected));
}

}  // namespace
