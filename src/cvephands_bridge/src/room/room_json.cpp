#include "room_json.h"

#include <charconv>
#include <cmath>

namespace cvephands {
namespace json {
namespace {

class Parser {
 public:
  explicit Parser(std::string_view text) : s_(text) {}

  bool run(Value* out, std::string* error) {
    skipSpace();
    if (!value(out, 0)) return fail(error);
    skipSpace();
    if (p_ != s_.size()) {
      error_ = "trailing characters";
      return fail(error);
    }
    return true;
  }

 private:
  bool fail(std::string* error) {
    if (error) *error = error_ + " at byte " + std::to_string(p_);
    return false;
  }
  bool bad(const char* what) {
    error_ = what;
    return false;
  }
  void skipSpace() {
    while (p_ < s_.size() && (s_[p_] == ' ' || s_[p_] == '\t' || s_[p_] == '\n' || s_[p_] == '\r'))
      ++p_;
  }
  bool literal(std::string_view word) {
    if (s_.substr(p_, word.size()) != word) return bad("invalid literal");
    p_ += word.size();
    return true;
  }

  bool value(Value* v, int depth) {
    if (p_ >= s_.size()) return bad("unexpected end");
    const char c = s_[p_];
    if (c == '{' || c == '[') {
      if (depth >= kMaxDepth) return bad("nesting too deep");
      return c == '{' ? object(v, depth + 1) : array(v, depth + 1);
    }
    if (c == '"') {
      v->type = Value::Type::kString;
      return string(&v->string);
    }
    if (c == 't') {
      v->type = Value::Type::kBool;
      v->boolean = true;
      return literal("true");
    }
    if (c == 'f') {
      v->type = Value::Type::kBool;
      v->boolean = false;
      return literal("false");
    }
    if (c == 'n') {
      v->type = Value::Type::kNull;
      return literal("null");
    }
    if (c == '-' || (c >= '0' && c <= '9')) {
      v->type = Value::Type::kNumber;
      return number(&v->number);
    }
    return bad("unexpected character");
  }

  bool object(Value* v, int depth) {
    v->type = Value::Type::kObject;
    ++p_;  // '{'
    skipSpace();
    if (p_ < s_.size() && s_[p_] == '}') {
      ++p_;
      return true;
    }
    for (;;) {
      skipSpace();
      if (p_ >= s_.size() || s_[p_] != '"') return bad("expected a key");
      std::string key;
      if (!string(&key)) return false;
      for (const auto& member : v->object)
        if (member.first == key) return bad("duplicate key");
      skipSpace();
      if (p_ >= s_.size() || s_[p_] != ':') return bad("expected ':'");
      ++p_;
      skipSpace();
      v->object.emplace_back(std::move(key), Value());
      if (!value(&v->object.back().second, depth)) return false;
      skipSpace();
      if (p_ >= s_.size()) return bad("unexpected end");
      if (s_[p_] == ',') {
        ++p_;
        continue;
      }
      if (s_[p_] == '}') {
        ++p_;
        return true;
      }
      return bad("expected ',' or '}'");
    }
  }

  bool array(Value* v, int depth) {
    v->type = Value::Type::kArray;
    ++p_;  // '['
    skipSpace();
    if (p_ < s_.size() && s_[p_] == ']') {
      ++p_;
      return true;
    }
    for (;;) {
      skipSpace();
      v->array.emplace_back();
      if (!value(&v->array.back(), depth)) return false;
      skipSpace();
      if (p_ >= s_.size()) return bad("unexpected end");
      if (s_[p_] == ',') {
        ++p_;
        continue;
      }
      if (s_[p_] == ']') {
        ++p_;
        return true;
      }
      return bad("expected ',' or ']'");
    }
  }

  bool hex4(uint32_t* u) {
    if (p_ + 4 > s_.size()) return bad("short \\u escape");
    *u = 0;
    for (int i = 0; i < 4; ++i) {
      const char c = s_[p_++];
      uint32_t d;
      if (c >= '0' && c <= '9')
        d = c - '0';
      else if (c >= 'a' && c <= 'f')
        d = c - 'a' + 10;
      else if (c >= 'A' && c <= 'F')
        d = c - 'A' + 10;
      else
        return bad("bad \\u escape");
      *u = *u * 16 + d;
    }
    return true;
  }

  static void appendUtf8(std::string* out, uint32_t cp) {
    if (cp < 0x80) {
      out->push_back(char(cp));
    } else if (cp < 0x800) {
      out->push_back(char(0xC0 | (cp >> 6)));
      out->push_back(char(0x80 | (cp & 0x3F)));
    } else if (cp < 0x10000) {
      out->push_back(char(0xE0 | (cp >> 12)));
      out->push_back(char(0x80 | ((cp >> 6) & 0x3F)));
      out->push_back(char(0x80 | (cp & 0x3F)));
    } else {
      out->push_back(char(0xF0 | (cp >> 18)));
      out->push_back(char(0x80 | ((cp >> 12) & 0x3F)));
      out->push_back(char(0x80 | ((cp >> 6) & 0x3F)));
      out->push_back(char(0x80 | (cp & 0x3F)));
    }
  }

  // The text is already valid UTF-8 (WebSocket text frames are checked by Beast), so bytes
  // >= 0x80 are copied through.
  bool string(std::string* out) {
    ++p_;  // '"'
    out->clear();
    for (;;) {
      if (p_ >= s_.size()) return bad("unterminated string");
      const unsigned char c = static_cast<unsigned char>(s_[p_++]);
      if (c == '"') return true;
      if (c < 0x20) return bad("control character in string");
      if (c != '\\') {
        out->push_back(char(c));
        continue;
      }
      if (p_ >= s_.size()) return bad("unterminated string");
      const char e = s_[p_++];
      switch (e) {
        case '"':
          out->push_back('"');
          break;
        case '\\':
          out->push_back('\\');
          break;
        case '/':
          out->push_back('/');
          break;
        case 'b':
          out->push_back('\b');
          break;
        case 'f':
          out->push_back('\f');
          break;
        case 'n':
          out->push_back('\n');
          break;
        case 'r':
          out->push_back('\r');
          break;
        case 't':
          out->push_back('\t');
          break;
        case 'u': {
          uint32_t cp;
          if (!hex4(&cp)) return false;
          if (cp >= 0xDC00 && cp <= 0xDFFF) return bad("lone low surrogate");
          if (cp >= 0xD800 && cp <= 0xDBFF) {
            if (s_.substr(p_, 2) != "\\u") return bad("lone high surrogate");
            p_ += 2;
            uint32_t lo;
            if (!hex4(&lo)) return false;
            if (lo < 0xDC00 || lo > 0xDFFF) return bad("bad surrogate pair");
            cp = 0x10000 + ((cp - 0xD800) << 10) + (lo - 0xDC00);
          }
          appendUtf8(out, cp);
          break;
        }
        default:
          return bad("bad escape");
      }
    }
  }

  // Grammar checked here; the conversion is from_chars' (locale-independent, unlike strtod) on
  // the validated span.
  bool number(double* out) {
    const size_t start = p_;
    if (s_[p_] == '-') ++p_;
    auto digits = [&] {
      const size_t d0 = p_;
      while (p_ < s_.size() && s_[p_] >= '0' && s_[p_] <= '9') ++p_;
      return p_ - d0;
    };
    if (p_ >= s_.size()) return bad("bad number");
    if (s_[p_] == '0') {
      ++p_;
    } else if (digits() == 0) {
      return bad("bad number");
    }
    if (p_ < s_.size() && s_[p_] == '.') {
      ++p_;
      if (digits() == 0) return bad("bad number");
    }
    if (p_ < s_.size() && (s_[p_] == 'e' || s_[p_] == 'E')) {
      ++p_;
      if (p_ < s_.size() && (s_[p_] == '+' || s_[p_] == '-')) ++p_;
      if (digits() == 0) return bad("bad number");
    }
    const auto r = std::from_chars(s_.data() + start, s_.data() + p_, *out);
    if (r.ec != std::errc() || !std::isfinite(*out)) return bad("number out of range");
    return true;
  }

  std::string_view s_;
  size_t p_ = 0;
  std::string error_;
};

}  // namespace

const Value* Value::find(std::string_view key) const {
  if (type != Type::kObject) return nullptr;
  for (const auto& member : object)
    if (member.first == key) return &member.second;
  return nullptr;
}

bool parse(std::string_view text, Value* out, std::string* error) {
  *out = Value();
  return Parser(text).run(out, error);
}

void appendString(std::string* out, std::string_view s) {
  static const char kHex[] = "0123456789abcdef";
  out->push_back('"');
  for (const char ch : s) {
    const unsigned char c = static_cast<unsigned char>(ch);
    if (c == '"' || c == '\\') {
      out->push_back('\\');
      out->push_back(ch);
    } else if (c < 0x20) {
      out->append("\\u00");
      out->push_back(kHex[c >> 4]);
      out->push_back(kHex[c & 15]);
    } else {
      out->push_back(ch);
    }
  }
  out->push_back('"');
}

void appendNumber(std::string* out, double v) {
  if (!std::isfinite(v)) v = 0.0;
  if (v == 0.0) v = 0.0;  // no "-0"
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof(buf), v);
  out->append(buf, r.ptr);
}

void appendInteger(std::string* out, int64_t v) {
  char buf[24];
  const auto r = std::to_chars(buf, buf + sizeof(buf), v);
  out->append(buf, r.ptr);
}

}  // namespace json
}  // namespace cvephands
