// bench_hand_codec: bitrate, accuracy and speed of the hand stream codec options on real hand
// sub-volumes of the simulated rig (sim_hand_volumes.h: 8 cameras, pSfS, 83^3 over 30 cm):
//   A   raw volume + zstd (lossless)
//   Bv  band-quantised VOLUME (non-band samples 0/255, band values at 2 bits) + zstd: the
//       simplest thing a client could decode, to show what splitting mask and codes buys
//   Bm  the above-iso mask alone as packed bits + zstd, vs our gap coding (bits 0 row)
//   B   the codec's band method, key frames only, for several code widths / levels / zstd levels
//   C   B with temporal deltas (key frame every 25 frames)
//   D   a quantised mesh (marching-cubes vertices on a 1/2^k voxel lattice, delta + varint coded,
//       indices as varint differences) + zstd
// Per option: mean and 95th-percentile message size, kbit/s per hand at 25 fps, the decoded
// mesh's distance from the original mesh (test/mesh_difference.h: mean and p95, averaged over
// the measured frames), whether the topology is identical, encode and decode ms per hand
// (one thread; the volume methods' receiver also runs marching cubes, ~1 ms per hand, the
// mesh method's sender does).
//
//   bench_hand_codec [--script NAME] [--first N] [--frames N] [--every K] [--short-sleeves 0|1]
#include <zstd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "../test/mesh_difference.h"
#include "cvephands_bridge/eval/sim_hand_volumes.h"
#include "cvephands_bridge/mesh/marching_cubes.h"
#include "cvephands_bridge/stream/hand_stream_codec.h"

namespace {

using cvephands::HandFrame;
using cvephands::TriangleMesh;
using Clock = std::chrono::steady_clock;

double msSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

cvephands::MarchingCubes& mesher() {
  static cvephands::MarchingCubes mc([] {
    cvephands::MarchingCubesOptions o;
    o.threads = 1;
    return o;
  }());
  return mc;
}
TriangleMesh mesh(const HandFrame& f) {
  TriangleMesh m;
  mesher().extract(f.view(), &m);
  return m;
}

std::vector<uint8_t> zstdCompress(const uint8_t* d, size_t n, int level) {
  std::vector<uint8_t> z(ZSTD_compressBound(n));
  z.resize(ZSTD_compress(z.data(), z.size(), d, n, level));
  return z;
}
std::vector<uint8_t> zstdDecompress(const std::vector<uint8_t>& z) {
  std::vector<uint8_t> r(ZSTD_getFrameContentSize(z.data(), z.size()));
  ZSTD_decompress(r.data(), r.size(), z.data(), z.size());
  return r;
}

void varint(std::vector<uint8_t>* o, uint32_t v) {
  while (v >= 0x80) o->push_back(uint8_t(v | 0x80)), v >>= 7;
  o->push_back(uint8_t(v));
}
uint32_t readVarint(const uint8_t** p) {
  uint32_t v = 0;
  for (int s = 0;; s += 7) {
    const uint8_t b = *(*p)++;
    v |= uint32_t(b & 0x7f) << s;
    if (!(b & 0x80)) return v;
  }
}
uint32_t zigzag(int32_t v) { return (uint32_t(v) << 1) ^ uint32_t(v >> 31); }
int32_t unzigzag(uint32_t v) { return int32_t(v >> 1) ^ -int32_t(v & 1); }

// Option D: the mesh, vertices on a 1/2^k voxel lattice relative to the origin.
std::vector<uint8_t> encodeMesh(const TriangleMesh& m, const HandFrame& f, int k) {
  std::vector<uint8_t> raw;
  varint(&raw, uint32_t(m.vertices.size()));
  varint(&raw, uint32_t(m.triangles.size()));
  const double scale = double(1 << k) / f.voxel_size;
  int32_t prev[3] = {0, 0, 0};
  for (const Eigen::Vector3f& v : m.vertices)
    for (int i = 0; i < 3; ++i) {
      const int32_t q = int32_t(std::lround((v[i] - f.origin[i]) * scale));
      varint(&raw, zigzag(q - prev[i]));
      prev[i] = q;
    }
  int32_t last = 0;
  for (uint32_t t : m.triangles) varint(&raw, zigzag(int32_t(t) - last)), last = int32_t(t);
  return zstdCompress(raw.data(), raw.size(), 3);
}
TriangleMesh decodeMesh(const std::vector<uint8_t>& z, const HandFrame& f, int k) {
  const std::vector<uint8_t> raw = zstdDecompress(z);
  const uint8_t* p = raw.data();
  TriangleMesh m;
  m.vertices.resize(readVarint(&p));
  m.triangles.resize(readVarint(&p));
  const double step = f.voxel_size / double(1 << k);
  int32_t q[3] = {0, 0, 0};
  for (Eigen::Vector3f& v : m.vertices)
    for (int i = 0; i < 3; ++i)
      q[i] += unzigzag(readVarint(&p)), v[i] = float(f.origin[i] + q[i] * step);
  int32_t last = 0;
  for (uint32_t& t : m.triangles) last += unzigzag(readVarint(&p)), t = uint32_t(last);
  return m;
}

struct Row {
  std::string name;
  std::vector<double> bytes, enc_ms, dec_ms, mean_mm, p95_mm;
  size_t topology_differs = 0;
};

double mean(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return v.empty() ? NAN : s / v.size();
}
double p95(std::vector<double> v) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, size_t(std::ceil(0.95 * v.size())) - 1)];
}

// One codec under test: encode(frame) -> message bytes; decode(message) -> mesh. Per hand stream
// state lives in the closures (one per target id).
struct Codec {
  std::function<std::vector<uint8_t>(const HandFrame&)> encode;
  std::function<TriangleMesh(const std::vector<uint8_t>&, const HandFrame&)>
      decode;  // frame: for D
};
using CodecFactory = std::function<Codec()>;

CodecFactory streamCodec(cvephands::HandStreamEncoderOptions o) {
  return [o] {
    auto enc = std::make_shared<cvephands::HandStreamEncoder>(o);
    auto dec = std::make_shared<cvephands::HandStreamDecoder>();
    auto out = std::make_shared<HandFrame>();
    Codec c;
    c.encode = [enc](const HandFrame& f) { return enc->encode(f); };
    c.decode = [dec, out](const std::vector<uint8_t>& m, const HandFrame&) {
      std::string why;
      if (!dec->decode(m, out.get(), &why)) {
        std::fprintf(stderr, "decode failed: %s\n", why.c_str());
        std::exit(1);
      }
      return mesh(*out);
    };
    return c;
  };
}

}  // namespace

int main(int argc, char** argv) {
  cvephands::SimHandVolumeOptions so;
  so.script = "all";
  so.frames = 500;
  so.skin_model = CVEPHANDS_SKIN_MODEL;
  int every = 10;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--script")
      so.script = argv[i + 1];
    else if (a == "--first")
      so.first_frame = std::atoi(argv[i + 1]);
    else if (a == "--frames")
      so.frames = std::atoi(argv[i + 1]);
    else if (a == "--every")
      every = std::max(1, std::atoi(argv[i + 1]));
    else if (a == "--short-sleeves")
      so.short_sleeves = std::atoi(argv[i + 1]) != 0;
    else {
      std::fprintf(stderr,
                   "usage: bench_hand_codec [--script NAME] [--first N] [--frames N] [--every K] "
                   "[--short-sleeves 0|1]\n");
      return 2;
    }
  }
  std::fprintf(stderr, "recording %d frames of '%s' ...\n", so.frames, so.script.c_str());
  std::vector<HandFrame> frames;
  for (cvephands::SimHandVolume& v : cvephands::recordSimHandVolumes(so)) {
    HandFrame f;
    f.target_id = uint32_t(v.side);
    f.origin = v.origin;
    f.voxel_size = v.voxel_size;
    f.dims = v.dims;
    f.data = std::move(v.data);
    frames.push_back(std::move(f));
  }
  std::vector<TriangleMesh> original(frames.size());
  for (size_t i = 0; i < frames.size(); ++i)
    if (i % every == 0) original[i] = mesh(frames[i]);

  using Opt = cvephands::HandStreamEncoderOptions;
  std::vector<std::pair<std::string, CodecFactory>> options;
  auto band = [](int bits, int keyframe_interval, int level = Opt().zstd_level,
                 bool adaptive = true) {
    Opt o;
    o.bits = bits;
    o.keyframe_interval = keyframe_interval;
    o.zstd_level = level;
    o.adaptive_levels = adaptive;
    return streamCodec(o);
  };
  for (int level : {1, 3}) {
    Opt o;
    o.method = cvephands::HandCodecMethod::kRaw;
    o.zstd_level = level;
    options.emplace_back("A  raw volume, zstd " + std::to_string(level), streamCodec(o));
  }
  options.emplace_back("Bv band volume 2 bit, zstd 3", [] {
    Codec inner = [] {
      Opt o;
      o.bits = 2;
      o.keyframe_interval = 1;
      return streamCodec(o)();
    }();
    auto dec = std::make_shared<cvephands::HandStreamDecoder>();
    Codec c;
    c.encode = [inner, dec](const HandFrame& f) {  // the band-quantised volume, zstd'd whole
      HandFrame q;
      std::string why;
      dec->decode(inner.encode(f), &q, &why);
      return zstdCompress(q.data.data(), q.data.size(), 3);
    };
    c.decode = [](const std::vector<uint8_t>& m, const HandFrame& f) {
      HandFrame q = f;
      q.data = zstdDecompress(m);
      return mesh(q);
    };
    return c;
  });
  options.emplace_back("Bm mask as packed bits, zstd 3", [] {
    Codec c;
    c.encode = [](const HandFrame& f) {
      std::vector<uint8_t> bits((f.data.size() + 7) / 8, 0);
      for (size_t i = 0; i < f.data.size(); ++i)
        if (f.data[i] > 153) bits[i >> 3] |= uint8_t(1u << (i & 7));
      return zstdCompress(bits.data(), bits.size(), 3);
    };
    c.decode = [](const std::vector<uint8_t>& m, const HandFrame& f) {
      const std::vector<uint8_t> bits = zstdDecompress(m);
      HandFrame q = f;
      for (size_t i = 0; i < q.data.size(); ++i)
        q.data[i] = (bits[i >> 3] >> (i & 7) & 1) ? 255 : 0;
      return mesh(q);
    };
    return c;
  });
  // B and C at the default zstd level (1) unless the name says otherwise.
  for (int bits : {0, 1, 2, 3, 4, 6, 8})
    options.emplace_back("B  band " + std::to_string(bits) + " bit", band(bits, 1));
  options.emplace_back("B  band 2 bit, even levels", band(2, 1, Opt().zstd_level, false));
  options.emplace_back("B  band 3 bit, even levels", band(3, 1, Opt().zstd_level, false));
  for (int level : {3, 9, 19})
    options.emplace_back("B  band 2 bit, zstd " + std::to_string(level), band(2, 1, level));
  for (int bits : {2, 3, 4})
    options.emplace_back("C  band " + std::to_string(bits) + " bit + deltas (key/25)" +
                             (bits == Opt().bits ? " = default" : ""),
                         band(bits, 25));
  for (int k : {2, 4})
    options.emplace_back("D  mesh, 1/" + std::to_string(1 << k) + " voxel, zstd 3", [k] {
      Codec c;
      c.encode = [k](const HandFrame& f) { return encodeMesh(mesh(f), f, k); };
      c.decode = [k](const std::vector<uint8_t>& m, const HandFrame& f) {
        return decodeMesh(m, f, k);
      };
      return c;
    });

  std::vector<Row> rows;
  for (auto& [name, factory] : options) {
    std::fprintf(stderr, "  %s\n", name.c_str());
    Row r;
    r.name = name;
    std::map<uint32_t, Codec> codecs;  // one stream per hand
    for (size_t i = 0; i < frames.size(); ++i) {
      Codec& c = codecs.try_emplace(frames[i].target_id, factory()).first->second;
      auto t0 = Clock::now();
      const std::vector<uint8_t> m = c.encode(frames[i]);
      r.enc_ms.push_back(msSince(t0));
      t0 = Clock::now();
      const TriangleMesh decoded = c.decode(m, frames[i]);
      r.dec_ms.push_back(msSince(t0));
      r.bytes.push_back(double(m.size()));
      if (i % every == 0) {
        const cvephands_test::MeshDifference d =
            cvephands_test::meshDifference(original[i], decoded);
        r.mean_mm.push_back(d.mean_mm);
        r.p95_mm.push_back(d.p95_mm);
        r.topology_differs += !d.same_triangles;
      }
    }
    rows.push_back(std::move(r));
  }

  std::printf("%zu hand sub-volumes (%s%s, script frames %d..%d), mesh distance on every %d-th\n",
              frames.size(), so.script.c_str(), so.short_sleeves ? ", short sleeves" : "",
              so.first_frame, so.first_frame + so.frames - 1, every);
  std::printf("%-44s | %8s %8s | %9s | %7s %7s | %4s | %7s %7s\n", "option", "B mean", "B p95",
              "kbit/s@25", "mean mm", "p95 mm", "topo", "enc ms", "dec ms");
  for (const Row& r : rows)
    std::printf("%-44s | %8.0f %8.0f | %9.0f | %7.3f %7.3f | %4s | %7.2f %7.2f\n", r.name.c_str(),
                mean(r.bytes), p95(r.bytes), mean(r.bytes) * 8 * 25 / 1000, mean(r.mean_mm),
                mean(r.p95_mm), r.topology_differs ? "diff" : "same", mean(r.enc_ms),
                mean(r.dec_ms));
  std::printf(
      "(dec ms of A, Bv, Bm, B, C includes marching cubes of the decoded volume; D's enc ms "
      "includes it)\n");
  return 0;
}
