// The room server's own JSON parser (src/room/room_json.h) against nlohmann::json 3.11 (Debian's
// nlohmann-json3-dev), the reference issue 19 names: on seeded mutations of protocol messages
// and JSON edge cases, whatever the own parser accepts, nlohmann accepts too with the same
// tree, and whatever it refuses that nlohmann accepts breaks one of its documented extra rules
// (a duplicate key, nesting deeper than json::kMaxDepth, a number beyond double's range, or a
// leading byte order mark, which nlohmann skips). So it is at least as strict as the
// reference. Inputs are valid UTF-8, as the WebSocket layer guarantees for text frames.
// Speed: bench_room_json.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "../src/room/room_json.h"
#include "cvephands_bridge/room/room_protocol.h"

namespace cvephands {
namespace {

#ifndef CVEPHANDS_JSON_FUZZ_INPUTS
#define CVEPHANDS_JSON_FUZZ_INPUTS 1000000
#endif

bool validUtf8(const std::string& s) {
  size_t i = 0;
  while (i < s.size()) {
    const unsigned char c = static_cast<unsigned char>(s[i]);
    int n = 0;
    uint32_t cp = 0;
    if (c < 0x80) {
      ++i;
      continue;
    } else if ((c & 0xE0) == 0xC0) {
      n = 1, cp = c & 0x1F;
    } else if ((c & 0xF0) == 0xE0) {
      n = 2, cp = c & 0x0F;
    } else if ((c & 0xF8) == 0xF0) {
      n = 3, cp = c & 0x07;
    } else {
      return false;
    }
    for (int k = 1; k <= n; ++k) {
      if (i + k >= s.size()) return false;
      const unsigned char d = static_cast<unsigned char>(s[i + k]);
      if ((d & 0xC0) != 0x80) return false;
      cp = (cp << 6) | (d & 0x3F);
    }
    if ((n == 1 && cp < 0x80) || (n == 2 && cp < 0x800) || (n == 3 && cp < 0x10000) ||
        cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF))
      return false;
    i += n + 1;
  }
  return true;
}

// Same tree: numbers as doubles (nlohmann keeps integers apart), objects as key sets.
bool same(const json::Value& a, const nlohmann::json& b, std::string* why) {
  using T = json::Value::Type;
  switch (a.type) {
    case T::kNull:
      if (b.is_null()) return true;
      break;
    case T::kBool:
      if (b.is_boolean() && b.get<bool>() == a.boolean) return true;
      break;
    case T::kNumber:
      if (b.is_number() && b.get<double>() == a.number) return true;
      break;
    case T::kString:
      if (b.is_string() && b.get<std::string>() == a.string) return true;
      break;
    case T::kArray:
      if (b.is_array() && b.size() == a.array.size()) {
        for (size_t i = 0; i < a.array.size(); ++i)
          if (!same(a.array[i], b[i], why)) return false;
        return true;
      }
      break;
    case T::kObject:
      if (b.is_object() && b.size() == a.object.size()) {
        for (const auto& [k, v] : a.object) {
          const auto it = b.find(k);
          if (it == b.end() || !same(v, *it, why)) return false;
        }
        return true;
      }
      break;
  }
  *why = "differs at " + b.dump().substr(0, 80);
  return false;
}

// nlohmann's verdict and the two rules the own parser adds (duplicate keys, depth).
struct Reference {
  bool accepted = false;
  bool duplicate_key = false;
  int depth = 0;
};

Reference reference(const std::string& text) {
  Reference r;
  int depth = 0;
  std::vector<std::vector<std::string>> keys;  // per open object
  const nlohmann::json::parser_callback_t cb = [&](int, nlohmann::json::parse_event_t e, nlohmann::json& parsed) {
    using E = nlohmann::json::parse_event_t;
    if (e == E::object_start || e == E::array_start) {
      r.depth = std::max(r.depth, ++depth);
      keys.emplace_back();
    } else if (e == E::object_end || e == E::array_end) {
      --depth;
      keys.pop_back();
    } else if (e == E::key) {
      const std::string k = parsed.get<std::string>();
      for (const std::string& seen : keys.back())
        if (seen == k) r.duplicate_key = true;
      keys.back().push_back(k);
    }
    return true;
  };
  const nlohmann::json j = nlohmann::json::parse(text, cb, /*allow_exceptions=*/false);
  r.accepted = !j.is_discarded();
  return r;
}

std::vector<std::string> seedCorpus() {
  std::vector<std::string> c;
  room::JoinRequest j;
  j.room = "r\xC3\xA9union";  // UTF-8
  j.name = "rig \"one\"\n";
  j.token = "t\\k";
  c.push_back(room::encodeJoin(j));
  room::ParticipantInfo p;
  p.id = 7;
  p.name = "viewer \xE2\x82\xAC";
  p.seat = 2;
  p.seat_pose = room::seatPose(2, room::SeatLayout());
  c.push_back(room::encodeWelcome("room", p, 6, 1234567890123ULL));
  c.push_back(room::encodeParticipants("room", {p, p}));
  c.push_back(room::encodeError("bad_token", "missing or wrong token"));
  c.push_back(room::encodePong("\"abc\"", 42));
  for (const char* s :
       {"{\"type\":\"ping\",\"id\":1.5e3}", "[]", "{}", "[[[[[[[[[[[[[[[[1]]]]]]]]]]]]]]]]",
        "[[[[[[[[[[[[[[[[[1]]]]]]]]]]]]]]]]]", "{\"a\":1,\"a\":2}", "-0", "0.5", "1E+2", "1e-7",
        "-123456789012345678", "\"\\u00e9\\ud83d\\ude00\\n\\t\\/\"", "\"\\ud800\"", "\"\\x\"",
        "[1,]", "{\"a\":1,}", "01", ".5", "1.", "NaN", "true", "false", "null", " \t\r\n[ ] ",
        "\"\xF0\x9F\x98\x80\"", "{\"k\":[true,false,null,{\"x\":\"y\"}]}", "1e400", "\"a\"\"b\"",
        "[\"\\u0000\"]", "/* c */ 1", "{'a':1}", "\xEF\xBB\xBF{}"})
    c.push_back(s);
  return c;
}

std::string mutate(const std::string& in, std::mt19937& rng) {
  static const std::string kBytes = "{}[]\":,\\-+.0123456789eEtfnulr ab\t\n\xC3\xA9";
  std::string s = in;
  const int edits = 1 + static_cast<int>(rng() % 4);
  for (int e = 0; e < edits; ++e) {
    const size_t pos = s.empty() ? 0 : rng() % (s.size() + 1);
    switch (rng() % 5) {
      case 0:  // insert a JSON-ish byte
        s.insert(s.begin() + static_cast<long>(pos), kBytes[rng() % kBytes.size()]);
        break;
      case 1:  // delete a byte
        if (pos < s.size()) s.erase(pos, 1);
        break;
      case 2:  // replace a byte
        if (pos < s.size()) s[pos] = kBytes[rng() % kBytes.size()];
        break;
      case 3:  // truncate
        s.resize(pos);
        break;
      default:  // duplicate a span
        if (pos < s.size()) s.insert(pos, s.substr(pos, 1 + rng() % 8));
        break;
    }
  }
  return s;
}

TEST(RoomJson, AtLeastAsStrictAsNlohmannWithTheSameTrees) {
  const std::vector<std::string> corpus = seedCorpus();
  std::mt19937 rng(20261203);
  size_t tried = 0, both = 0, extra_rules = 0, neither = 0;
  for (int i = 0; i < CVEPHANDS_JSON_FUZZ_INPUTS + static_cast<int>(corpus.size()); ++i) {
    const std::string text = i < static_cast<int>(corpus.size())
                                 ? corpus[i]
                                 : mutate(corpus[rng() % corpus.size()], rng);
    if (!validUtf8(text)) continue;
    ++tried;
    json::Value own;
    std::string error;
    const bool own_ok = json::parse(text, &own, &error);
    const Reference ref = reference(text);
    if (own_ok) {
      ASSERT_TRUE(ref.accepted) << "the own parser accepted what nlohmann refuses: " << text;
      std::string why;
      ASSERT_TRUE(same(own, nlohmann::json::parse(text), &why)) << why << " for " << text;
      ++both;
    } else if (ref.accepted) {
      const bool bom = text.rfind("\xEF\xBB\xBF", 0) == 0;  // RFC 8259 lets parsers refuse it
      // A number a double cannot hold (1e400, 1e-7777): RFC 8259 section 6 allows the limit.
      const bool range = error.rfind("number out of range", 0) == 0;
      ASSERT_TRUE(ref.duplicate_key || ref.depth > json::kMaxDepth || bom || range)
          << "the own parser refused valid JSON (" << error << "): " << text;
      ++extra_rules;
    } else {
      ++neither;
    }
  }
  std::printf("[ figures  ] %zu inputs: %zu accepted by both, %zu refused by both, %zu refused only "
              "by the own parser (duplicate keys, nesting > %d, range, a BOM)\n",
              tried, both, neither, extra_rules, json::kMaxDepth);
  EXPECT_GT(both, tried / 50);
  EXPECT_GT(neither, tried / 4);
  EXPECT_GT(extra_rules, 0u);
}

}  // namespace
}  // namespace cvephands
