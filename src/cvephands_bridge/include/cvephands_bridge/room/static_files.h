// Static files of the room server (the browser client): maps an HTTP request target to a file
// under one root directory. The server listens on a machine that also holds calibration, bags
// and keys, so the mapping is deliberately narrow: only regular files that are really inside the
// root after resolving symlinks, no ".." or "." segments (also when percent-encoded), no
// backslashes or NUL bytes, no hidden names (".git", ".env"). "/" and any path ending in "/"
// mean that directory's index.html.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>

namespace cvephands {

struct StaticFileLookup {
  int status = 404;               // 200, 400 (bad target) or 404 (absent or not servable)
  std::filesystem::path path;     // the canonical file when 200
  const char* content_type = "";  // when 200
};

// `root` must be canonical (std::filesystem::canonical of an existing directory). `target` is
// the request target as received (query and fragment are ignored).
StaticFileLookup resolveStaticFile(const std::filesystem::path& root, std::string_view target);

// By extension: html, js/mjs, css, json, png, wasm, plus a few the client may grow into (svg,
// ico, jpg, txt, map); application/octet-stream otherwise.
const char* contentTypeFor(const std::filesystem::path& file);

}  // namespace cvephands
