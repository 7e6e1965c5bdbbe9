// The little JSON the room protocol needs (control messages of a few hundred bytes): a strict
// RFC 8259 parser into a plain tree, and writers for strings and numbers. Hand-written because
// Boost 1.74 has no Boost.JSON and no JSON library is installed; the room server must reject
// anything malformed, so the parser accepts nothing beyond the RFC (no comments, no trailing
// commas, no NaN, no lone surrogates, no duplicate keys) and limits nesting.
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
