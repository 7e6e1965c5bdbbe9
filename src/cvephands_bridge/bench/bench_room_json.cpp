// The room server's own JSON parser (src/room/room_json.h) against nlohmann::json 3.11 on the
// control messages it parses: a join (what every client sends) and a participants list of 6
// (what every client receives after each join and leave). Strictness: test_room_json_fuzz.
//
//   bench_room_json --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <nlohmann/json.hpp>

#include "../src/room/room_json.h"
#include "cvephands_bridge/room/room_protocol.h"

namespace cvephands {
namespace {

std::string message(int which) {
  if (which == 0) {
    room::JoinRequest j;
    j.room = "meeting-room-1";
    j.name = "rig at the window";
    j.token = "0123456789abcdef0123456789abcdef";
    return room::encodeJoin(j);
  }
  std::vector<room::ParticipantInfo> list;
  for (int i = 0; i < 6; ++i) {
    room::ParticipantInfo p;
    p.id = uint32_t(100 + i);
    p.name = "participant " + std::to_string(i);
    p.seat = i;
    p.seat_pose = room::seatPose(i, room::SeatLayout());
    list.push_back(p);
  }
  return room::encodeParticipants("meeting-room-1", list);
}

void BM_OwnParser(benchmark::State& st) {
  const std::string text = message(static_cast<int>(st.range(0)));
  for (auto _ : st) {
    json::Value v;
    std::string error;
    benchmark::DoNotOptimize(json::parse(text, &v, &error));
  }
  st.SetBytesProcessed(static_cast<int64_t>(st.iterations() * text.size()));
  st.SetLabel(st.range(0) == 0 ? "join" : "participants (6)");
}
BENCHMARK(BM_OwnParser)->Arg(0)->Arg(1)->ArgName("message");

void BM_Nlohmann(benchmark::State& st) {
  const std::string text = message(static_cast<int>(st.range(0)));
  for (auto _ : st) {
    nlohmann::json j = nlohmann::json::parse(text, nullptr, false);
    benchmark::DoNotOptimize(j.is_discarded());
  }
  st.SetBytesProcessed(static_cast<int64_t>(st.iterations() * text.size()));
  st.SetLabel(st.range(0) == 0 ? "join" : "participants (6)");
}
BENCHMARK(BM_Nlohmann)->Arg(0)->Arg(1)->ArgName("message");

}  // namespace
}  // namespace cvephands

BENCHMARK_MAIN();
