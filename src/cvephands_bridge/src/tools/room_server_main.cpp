// room_server: the CVE's room server as a standalone program (no ROS needed): relays hand
// streams between the participants of each room and serves the browser client.
//
//   room_server [--bind ADDR] [--port N] [--token T] [--static DIR] [--seats N] [--status S]
//               [--max-clients N] [--max-pending N] [--max-pending-per-address N]
//               [--max-rate N] [--max-bandwidth B] [--tls-cert FILE --tls-key FILE]
//
// With --tls-cert and --tls-key (PEM) it serves https and wss instead of http and ws. Bound to
// an address other than loopback without them, it warns: the token and the hands would cross
// the network in clear text.
//
// Prints a status line every --status seconds (rooms, participants, connections waiting to
// join, messages, drops) and stops cleanly on SIGINT / SIGTERM. Arguments starting with "__" (what roslaunch appends: __name:=,
// __log:=) are ignored, so launch files can start it as a node.
//
// Without --static it serves the browser client it finds (defaultStaticRoot): the installed one
// next to its own executable, <prefix>/lib/cvephands_bridge/room_server ->
// <prefix>/share/cvephands_bridge/web/dist (install space), else the one built in the source
// tree (devel space, CVEPHANDS_WEB_DIST from CMake). `--static ""` serves no files.
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include <boost/asio/ip/address.hpp>

#include "cvephands_bridge/room/room_server.h"
#include "tabletop_common/cli_args.h"

namespace {

namespace fs = std::filesystem;

// The browser client's directory for a room server started without --static: the install
// space's share/cvephands_bridge/web/dist relative to this executable (found through
// /proc/self/exe, so a relocated install space works), else the source tree's web/dist that the
// devel-space binary was built from; "" when neither holds the client (relaying only).
std::string defaultStaticRoot() {
  std::vector<fs::path> candidates;
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) candidates.push_back(exe.parent_path() / "../../share/cvephands_bridge/web/dist");
#ifdef CVEPHANDS_WEB_DIST
  candidates.push_back(CVEPHANDS_WEB_DIST);
#endif
  for (const fs::path& c : candidates) {
    if (fs::is_regular_file(c / "index.html", ec)) return fs::weakly_canonical(c, ec).string();
  }
  return "";
}

std::atomic<bool> g_stop{false};
void onSignal(int) { g_stop = true; }

void usage() {
  std::fprintf(stderr,
               "usage: room_server [--bind ADDR] [--port N] [--token T] [--static DIR] [--seats N] "
               "[--status S]\n"
               "                   [--max-clients N] [--max-pending N] [--max-pending-per-address N]\n"
               "                   [--max-rate N] [--max-bandwidth B] [--tls-cert FILE --tls-key FILE]\n"
               "  --bind    address to listen on (default 127.0.0.1; 0.0.0.0 for every interface)\n"
               "  --port    TCP port of HTTP + WebSocket (default 8765; 0 = any free port)\n"
               "  --token   shared token every participant must send (default: none)\n"
               "  --static  directory of the browser client served over HTTP (default: the\n"
               "            installed share/cvephands_bridge/web/dist beside this program, else\n"
               "            the source tree's web/dist; \"\" = serve no files)\n"
               "  --seats   seats per room around the virtual table (default 6)\n"
               "  --status  seconds between status lines (default 5; 0 = none)\n"
               "  --max-clients N    joined participants, all rooms (default 64)\n"
               "  --max-pending N    connections waiting to join, in all (default 64) and\n"
               "  --max-pending-per-address N   from one address (default 8); one more and the\n"
               "                     oldest waiting one is closed (\"evicted\")\n"
               "  --max-rate N       hand messages/s per sender (default 200; 0 = no limit)\n"
               "  --max-bandwidth B  bytes/s per sender (default 16e6; 0 = no limit); beyond\n"
               "                     either, a sender's messages are dropped and counted\n"
               "  --tls-cert FILE    PEM certificate (chain) and\n"
               "  --tls-key FILE     its unencrypted PEM private key: serve https and wss (TLS 1.2+)\n"
               "                     instead of http and ws; both or neither. Needed whenever the\n"
               "                     port is reachable from other machines (--bind other than\n"
               "                     127.0.0.1): without TLS the token and the hands travel in\n"
               "                     clear text\n");
}

}  // namespace

int main(int argc, char** argv) {
  cvephands::RoomServerOptions o;
  o.port = 8765;
  double status = 5.0;
  bool static_given = false;
  tabletop_common::CliArgs args("room_server", argc, argv, usage, /*skip_ros_args=*/true);
  while (args.next()) {
    if (args.is("--bind")) o.bind_address = args.text();
    else if (args.is("--port")) o.port = static_cast<uint16_t>(args.integer(0, 65535));
    else if (args.is("--token")) o.token = args.text();
    else if (args.is("--static")) {
      o.static_root = args.text();
      static_given = true;
    }
    else if (args.is("--seats")) o.seats.seats = static_cast<int>(args.integer(1, 1024));
    else if (args.is("--status")) status = args.number(0.0);
    else if (args.is("--max-clients")) o.max_clients = static_cast<size_t>(args.integer(1, 100000));
    else if (args.is("--max-pending")) o.max_pending = static_cast<size_t>(args.integer(1, 100000));
    else if (args.is("--max-pending-per-address"))
      o.max_pending_per_address = static_cast<size_t>(args.integer(1, 100000));
    else if (args.is("--max-rate")) o.max_sender_messages_per_s = args.number(0.0);
    else if (args.is("--max-bandwidth")) o.max_sender_bytes_per_s = args.number(0.0);
    else if (args.is("--tls-cert")) o.tls_certificate_file = args.text();
    else if (args.is("--tls-key")) o.tls_private_key_file = args.text();
    else if (args.help()) {
      usage();
      return 0;
    } else {
      args.unknown();
    }
  }
  if (o.tls_certificate_file.empty() != o.tls_private_key_file.empty())
    args.fail(o.tls_certificate_file.empty() ? "--tls-key needs --tls-cert (its certificate)"
                                             : "--tls-cert needs --tls-key (its private key)");
  std::signal(SIGINT, onSignal);
  std::signal(SIGTERM, onSignal);
  if (!static_given) {
    o.static_root = defaultStaticRoot();
    if (o.static_root.empty())
      std::fprintf(stderr,
                   "[room_server] WARNING: no browser client found (not installed beside this "
                   "program, not built in the source tree: scripts/setup.sh builds it); relaying "
                   "hands only\n");
  }
  if (!o.static_root.empty() && !std::filesystem::is_directory(o.static_root)) {
    // Relaying hands needs no client files: keep serving the rigs, say what is missing.
    std::fprintf(stderr,
                 "[room_server] WARNING: no browser client at %s (build it with scripts/setup.sh); "
                 "relaying hands only\n",
                 o.static_root.c_str());
    o.static_root.clear();
  }
  cvephands::RoomServer server(o);
  try {
    server.start();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "room_server: cannot start: %s\n", e.what());
    return 1;
  }
  const bool tls = server.tls();
  std::printf("[room_server] listening on %s:%u (%s, path /ws)%s%s\n", o.bind_address.c_str(),
              server.port(), tls ? "wss, TLS" : "ws, no TLS", o.static_root.empty() ? "" : ", client from ",
              o.static_root.c_str());
  if (!o.static_root.empty())
    std::printf("[room_server] open %s://%s:%u/ in a browser to enter the room\n", tls ? "https" : "http",
                o.bind_address == "0.0.0.0" ? "127.0.0.1" : o.bind_address.c_str(), server.port());
  boost::system::error_code not_address;  // start() accepted it: an address
  if (!tls && !boost::asio::ip::make_address(o.bind_address, not_address).is_loopback())
    std::fprintf(stderr,
                 "[room_server] WARNING: listening on %s without TLS: the token and the hand streams "
                 "travel in clear text to anyone on the network path; give --tls-cert and --tls-key\n",
                 o.bind_address.c_str());
  std::fflush(stdout);
  auto last = std::chrono::steady_clock::now();
  while (!g_stop) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    if (status <= 0) continue;
    const auto now = std::chrono::steady_clock::now();
    if (std::chrono::duration<double>(now - last).count() < status) continue;
    last = now;
    const cvephands::RoomServerStats s = server.stats();
    uint64_t in = 0;
    for (const auto& r : s.rooms) in += r.messages_in;
    uint64_t kicked = 0;
    for (const auto& k : s.kicked) kicked += k.second;
    std::printf("[room_server] %zu room(s), %zu participant(s), %zu waiting to join, %llu hand "
                "messages in, %llu dropped for slow readers, %llu over senders' rates, %llu "
                "connection(s) closed for errors\n",
                s.rooms.size(), s.participants.size(), s.pending, static_cast<unsigned long long>(in),
                static_cast<unsigned long long>(s.dropped),
                static_cast<unsigned long long>(s.rate_dropped), static_cast<unsigned long long>(kicked));
    std::fflush(stdout);
  }
  server.stop();
  std::printf("[room_server] stopped\n");
  return 0;
}
