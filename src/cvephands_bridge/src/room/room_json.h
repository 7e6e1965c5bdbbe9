// The little JSON the room protocol needs (control messages of a few hundred bytes): a strict
// RFC 8259 parser into a plain tree, and writers for strings and numbers. The room server must
// reject anything malformed, so the parser accepts nothing beyond the RFC (no comments, no
// trailing commas, no NaN, no lone surrogates, no BOM) and refuses what the RFC leaves to the
// implementation: duplicate keys, nesting deeper than kMaxDepth, numbers beyond double's range.
// Kept instead of nlohmann::json (Debian nlohmann-json3-dev 3.11), as issue 19 allows, because
// test_room_json_fuzz shows it at least as strict (on 10^6 seeded mutations of protocol
// messages and edge cases it accepts nothing nlohmann refuses, with the same trees, and refuses
// what nlohmann accepts only for the rules above) and bench_room_json at least as fast
// (docs/benchmarks.md, "Room server"); nlohmann accepts duplicate keys (the last wins) and any
// nesting depth.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace cvephands {
namespace json {

struct Value {
  enum class Type { kNull, kBool, kNumber, kString, kArray, kObject };
  Type type = Type::kNull;
  bool boolean = false;
  double number = 0.0;
  std::string string;
  std::vector<Value> array;
  std::vector<std::pair<std::string, Value>> object;  // in document order, keys unique

  bool isNull() const { return type == Type::kNull; }
  bool isNumber() const { return type == Type::kNumber; }
  bool isString() const { return type == Type::kString; }
  bool isArray() const { return type == Type::kArray; }
  bool isObject() const { return type == Type::kObject; }
  // Member of an object (nullptr if absent or not an object).
  const Value* find(std::string_view key) const;
};

constexpr int kMaxDepth = 16;

// Parses one JSON text (whitespace around it allowed). On failure returns false and says where
// in *error.
bool parse(std::string_view text, Value* out, std::string* error);

// Appends s as a JSON string literal (quotes, escapes for '"', '\\' and control characters;
// other bytes are copied, so valid UTF-8 stays valid UTF-8).
void appendString(std::string* out, std::string_view s);
// Appends a finite double in its shortest round-trip form (non-finite values are written as 0:
// JSON has no NaN or infinity).
void appendNumber(std::string* out, double v);
void appendInteger(std::string* out, int64_t v);

}  // namespace json
}  // namespace cvephands
