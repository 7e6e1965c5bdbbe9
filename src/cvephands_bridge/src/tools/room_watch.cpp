// room_watch: joins a room as a viewer and reports what flows through it, per participant:
// hand messages per second, kbit/s per hand, hands seen, and the latency from each hand's
// capture stamp to its arrival here (the pipeline, the bridge and the relay; a browser adds its
// own decoding, meshing and rendering). With --decode it also decodes and meshes every message
// as a client would (C++ decoder + marching cubes), counting failures. Face video messages
// (face_video.h) are counted apart (pictures per second, kbit/s).
//
//   room_watch [--host H] [--port N] [--room R] [--token T] [--seconds S] [--wait S] [--decode]
//              [--tls] [--tls-ca FILE]
//
// Prints a line per participant every --interval seconds and a summary at the end (after
// --seconds, or on SIGINT / SIGTERM). Exit status 1 when it could not join.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "cvephands_bridge/mesh/marching_cubes.h"
#include "cvephands_bridge/room/room_client.h"
#include "cvephands_bridge/stream/hand_stream_codec.h"
#include "cvephands_bridge/video/face_video.h"
#include "tabletop_common/cli_args.h"

namespace {

std::atomic<bool> g_stop{false};
void onSignal(int) { g_stop = true; }

void usage() {
  std::fprintf(stderr,
               "usage: room_watch [--host H] [--port N] [--room R] [--token T] [--seconds S] "
               "[--interval S] [--wait S] [--decode]\n"
               "                  [--tls] [--tls-ca FILE]\n"
               "  --host      room server address (default 127.0.0.1)\n"
               "  --port      its port (default 8765)\n"
               "  --room      room to watch (default tabletop)\n"
               "  --token     the server's shared token, if any\n"
               "  --seconds   stop after S seconds (default 0: until Ctrl-C)\n"
               "  --interval  seconds between report lines (default 5; 0: summary only)\n"
               "  --wait      keep trying to join for S seconds (a server still starting)\n"
               "  --decode    decode and mesh every message (C++ decoder + marching cubes)\n"
               "  --tls       wss:// (a room server with --tls-cert): its certificate must be for\n"
               "              --host and signed by a CA of the system's store, or of --tls-ca\n"
               "  --tls-ca    PEM file of the CA(s) to trust instead (a self-signed certificate is\n"
               "              its own CA); implies --tls\n");
}

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<size_t>(q * v.size()))];
}

// Per sender, since the start.
struct SenderStats {
  uint64_t messages = 0, bytes = 0, gaps = 0, decode_failures = 0;
  uint64_t faces = 0, face_bytes = 0, bad_faces = 0;  // face video (face_video.h)
  uint32_t last_sequence = 0;
  bool any = false;
  double first = 0.0, last = 0.0;  // arrival of the first and the latest message (s)
  std::set<uint32_t> targets;
  std::vector<double> latency_ms;  // capture stamp -> received here
  std::vector<double> decode_ms;   // decode + marching cubes (--decode)
  cvephands::HandStreamDecoder decoder;
};

double nowSeconds() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

}  // namespace

int main(int argc, char** argv) {
  cvephands::RoomClientOptions o;
  o.port = 8765;
  o.join.room = "tabletop";
  o.join.name = "room_watch";
  o.join.role = cvephands::room::Role::kViewer;
  double seconds = 0.0, interval = 5.0, wait = 0.0;
  bool decode = false;
  tabletop_common::CliArgs args("room_watch", argc, argv, usage);
  while (args.next()) {
    if (args.is("--host")) o.host = args.text();
    else if (args.is("--port")) o.port = static_cast<uint16_t>(args.integer(1, 65535));
    else if (args.is("--room")) o.join.room = args.text();
    else if (args.is("--token")) o.join.token = args.text();
    else if (args.is("--seconds")) seconds = args.number(0.0);
    else if (args.is("--interval")) interval = args.number(0.0);
    else if (args.is("--wait")) wait = args.number(0.0);
    else if (args.is("--decode")) decode = true;
    else if (args.is("--tls")) o.tls = true;
    else if (args.is("--tls-ca")) {
      o.tls_ca_file = args.text();
      o.tls = true;
    }
    else if (args.help()) {
      usage();
      return 0;
    } else {
      args.unknown();
    }
  }

  std::mutex mutex;
  std::map<uint32_t, SenderStats> senders;
  std::map<uint32_t, std::string> names;
  cvephands::MarchingCubesOptions mco;
  mco.threads = 1;
  cvephands::MarchingCubes mc(mco);
  o.on_participants = [&](const std::vector<cvephands::room::ParticipantInfo>& list) {
    std::lock_guard<std::mutex> lock(mutex);
    for (const auto& p : list) names[p.id] = p.name;
  };
  o.on_hands = [&](const cvephands::room::RelayHeader& h, const uint8_t* data, size_t size) {
    const double received = nowSeconds();
    std::lock_guard<std::mutex> lock(mutex);
    SenderStats& s = senders[h.sender];
    if (!s.any) s.first = received;
    s.last = received;
    // Forward gaps only (mod 2^32): a repeated or older sequence is no loss.
    const uint32_t gap = h.sequence - s.last_sequence - 1;
    if (s.any && gap < 0x80000000u) s.gaps += gap;
    s.any = true;
    s.last_sequence = h.sequence;
    if (cvephands::isFaceMessage(data, size)) {
      cvephands::FaceMessage face;
      ++s.faces;
      s.face_bytes += size;
      if (!cvephands::parseFaceMessage(data, size, &face, nullptr)) ++s.bad_faces;
      return;
    }
    ++s.messages;
    s.bytes += size;
    // Target id and stamp from the codec header (hand_stream_codec.h offsets 8 and 16), read
    // without decoding: latency is measured even for messages a decoder would reject.
    if (size >= 24) {
      uint32_t id, sec, nsec;
      std::memcpy(&id, data + 8, 4);
      std::memcpy(&sec, data + 16, 4);
      std::memcpy(&nsec, data + 20, 4);
      s.targets.insert(id);
      s.latency_ms.push_back(1e3 * (received - (sec + 1e-9 * nsec)));
    }
    if (decode) {
      const auto t0 = std::chrono::steady_clock::now();
      cvephands::HandFrame frame;
      std::string reason;
      if (s.decoder.decode(data, size, &frame, &reason)) {
        cvephands::TriangleMesh mesh;
        mc.extract(frame.view(), &mesh);
        s.decode_ms.push_back(
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
      } else {
        ++s.decode_failures;
      }
    }
  };

  std::signal(SIGINT, onSignal);
  std::signal(SIGTERM, onSignal);
  // One RoomClient is one connection attempt: retry with fresh ones while --wait allows.
  std::unique_ptr<cvephands::RoomClient> owner;
  const double wait_until = nowSeconds() + wait;
  for (;;) {
    owner = std::make_unique<cvephands::RoomClient>(o);
    std::string error;
    if (owner->connect(&error)) break;
    if (g_stop || nowSeconds() >= wait_until) {
      std::fprintf(stderr, "room_watch: cannot join room '%s' at %s:%u: %s\n",
                   o.join.room.c_str(), o.host.c_str(), o.port, error.c_str());
      return 1;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(250));
  }
  cvephands::RoomClient& client = *owner;
  std::printf("[room_watch] watching room '%s' at %s://%s:%u/ws\n", o.join.room.c_str(),
              o.tls ? "wss" : "ws", o.host.c_str(), o.port);
  std::fflush(stdout);

  const double start = nowSeconds();
  auto report = [&](const char* prefix) {
    std::lock_guard<std::mutex> lock(mutex);
    if (senders.empty()) std::printf("%sno hand messages\n", prefix);
    for (const auto& [id, s] : senders) {
      // Rates over the time the participant streamed (not while its pipeline was starting).
      const double elapsed = std::max(1e-3, s.last - s.first);
      const size_t hands = std::max<size_t>(1, s.targets.size());
      std::printf("%s%s (participant %u): %.1f msg/s, %zu hand id(s), %.0f kbit/s per hand, "
                  "capture->here latency median %.1f ms p95 %.1f ms, %llu missed",
                  prefix, names.count(id) ? names[id].c_str() : "?", id, s.messages / elapsed,
                  s.targets.size(), 8e-3 * s.bytes / elapsed / hands,
                  percentile(s.latency_ms, 0.5), percentile(s.latency_ms, 0.95),
                  static_cast<unsigned long long>(s.gaps));
      if (decode)
        std::printf(", decode+mesh %.2f ms, %llu undecodable", percentile(s.decode_ms, 0.5),
                    static_cast<unsigned long long>(s.decode_failures));
      if (s.faces)
        std::printf("; face video %.1f pictures/s, %.0f kbit/s, %llu malformed", s.faces / elapsed,
                    8e-3 * s.face_bytes / elapsed, static_cast<unsigned long long>(s.bad_faces));
      std::printf("\n");
    }
    std::fflush(stdout);
  };
  double last = start;
  while (!g_stop && client.connected()) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    const double now = nowSeconds();
    if (seconds > 0 && now - start >= seconds) break;
    if (interval > 0 && now - last >= interval) {
      last = now;
      report("[room_watch] ");
    }
  }
  const std::string why = client.closeReason();
  client.close();
  report("CVE room (room_watch viewer): ");
  if (!why.empty() && why.rfind("shutdown", 0) != 0)
    std::printf("[room_watch] connection ended: %s\n", why.c_str());
  return 0;
}
