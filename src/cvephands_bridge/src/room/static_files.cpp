#include "cvephands_bridge/room/static_files.h"

#include <algorithm>
#include <system_error>
#include <vector>

namespace cvephands {
namespace {

int hexValue(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

// Percent-decodes the path part; false on a broken escape.
bool decodePath(std::string_view in, std::string* out) {
  out->clear();
  for (size_t i = 0; i < in.size(); ++i) {
    if (in[i] != '%') {
      out->push_back(in[i]);
      continue;
    }
    if (i + 2 >= in.size()) return false;
    const int hi = hexValue(in[i + 1]), lo = hexValue(in[i + 2]);
    if (hi < 0 || lo < 0) return false;
    out->push_back(char(hi * 16 + lo));
    i += 2;
  }
  return true;
}

bool isInside(const std::filesystem::path& root, const std::filesystem::path& p) {
  auto r = root.begin(), q = p.begin();
  for (; r != root.end(); ++r, ++q)
    if (q == p.end() || *r != *q) return false;
  return q != p.end();  // strictly below the root
}

}  // namespace

StaticFileLookup resolveStaticFile(const std::filesystem::path& root, std::string_view target) {
  StaticFileLookup result;
  const size_t end = target.find_first_of("?#");
  std::string path;
  if (!decodePath(target.substr(0, end), &path) || path.empty() || path[0] != '/' ||
      path.find('\0') != std::string::npos || path.find('\\') != std::string::npos) {
    result.status = 400;
    return result;
  }
  // Split on '/', dropping empty segments; never let a segment be absolute or climb.
  std::vector<std::string> segments;
  size_t start = 1;
  while (start <= path.size()) {
    const size_t slash = std::min(path.find('/', start), path.size());
    std::string segment = path.substr(start, slash - start);
    start = slash + 1;
    if (segment.empty()) continue;
    if (segment == "." || segment == "..") {
      result.status = 400;
      return result;
    }
    if (segment[0] == '.') return result;  // hidden: 404
    segments.push_back(std::move(segment));
  }
  if (path.back() == '/') segments.push_back("index.html");

  std::filesystem::path file = root;
  for (const std::string& s : segments) file /= s;
  std::error_code ec;
  const std::filesystem::path real = std::filesystem::canonical(file, ec);
  if (ec || !isInside(root, real) || !std::filesystem::is_regular_file(real, ec) || ec)
    return result;
  result.status = 200;
  result.path = real;
  result.content_type = contentTypeFor(real);
  return result;
}

const char* contentTypeFor(const std::filesystem::path& file) {
  std::string ext = file.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return char(std::tolower(c)); });
  if (ext == ".html" || ext == ".htm") return "text/html; charset=utf-8";
  if (ext == ".js" || ext == ".mjs") return "text/javascript; charset=utf-8";
  if (ext == ".css") return "text/css; charset=utf-8";
  if (ext == ".json" || ext == ".map") return "application/json";
  if (ext == ".png") return "image/png";
  if (ext == ".wasm") return "application/wasm";
  if (ext == ".svg") return "image/svg+xml";
  if (ext == ".ico") return "image/x-icon";
  if (ext == ".jpg" || ext == ".jpeg") return "image/jpeg";
  if (ext == ".txt") return "text/plain; charset=utf-8";
  return "application/octet-stream";
}

}  // namespace cvephands
