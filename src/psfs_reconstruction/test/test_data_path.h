// Locates data the tests read but the repository does not hold: the project's shared data
// directory (`../shared/data` next to the repository root, see shared/data/README.md).
// Order: the environment variable PSFS_SHARED_DATA_DIR, the compile definition
// PSFS_SHARED_DATA_DIR (CMake sets it to <package>/../../../shared/data = <repo>/../shared/data),
// then `../shared/data` or `shared/data` from the current directory or any ancestor. Returns ""
// when the file is absent, so the test can GTEST_SKIP() with a message.
#pragma once

#include <cstdlib>
#include <string>
#include <sys/stat.h>

#include <unistd.h>

namespace psfs_test {

inline bool fileExists(const std::string& path) {
  struct stat st;
  return ::stat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode);
}

inline std::string findSharedData(const std::string& relative) {
  if (const char* env = std::getenv("PSFS_SHARED_DATA_DIR")) {
    const std::string p = std::string(env) + "/" + relative;
    if (fileExists(p)) return p;
  }
#ifdef PSFS_SHARED_DATA_DIR
  {
    const std::string p = std::string(PSFS_SHARED_DATA_DIR) + "/" + relative;
    if (fileExists(p)) return p;
  }
#endif
  char buf[4096];
  if (!::getcwd(buf, sizeof(buf))) return "";
  std::string dir = buf;
  for (int level = 0; level < 12 && !dir.empty(); ++level) {
    for (const char* sub : {"/../shared/data/", "/shared/data/"}) {
      const std::string p = dir + sub + relative;
      if (fileExists(p)) return p;
    }
    const auto slash = dir.find_last_of('/');
    if (slash == std::string::npos || dir == "/") break;
    dir = slash == 0 ? "/" : dir.substr(0, slash);
  }
  return "";
}

// The package's config directory (compile definition PSFS_RECONSTRUCTION_CONFIG_DIR, set by
// CMake to <package>/config), or "" when not defined.
inline std::string configDir() {
#ifdef PSFS_RECONSTRUCTION_CONFIG_DIR
  return PSFS_RECONSTRUCTION_CONFIG_DIR;
#else
  return "";
#endif
}

}  // namespace psfs_test
