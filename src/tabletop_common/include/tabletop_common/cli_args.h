// Command-line parsing shared by the tools (render_bag, track_eval, mesh_eval, room_server,
// room_watch, train_skin_model): "--option value" pairs and flags in any order. A missing or
// malformed value or an unknown option ends the program with a message naming the tool and the
// option, the tool's usage and exit status 2, so "--port abc" never silently becomes port 0.
//
//   tabletop_common::CliArgs args("room_watch", argc, argv, usage);
//   while (args.next()) {
//     if (args.is("--port")) port = args.integer(1, 65535);
//     else if (args.is("--decode")) decode = true;
//     else if (args.help()) { usage(); return 0; }
//     else args.unknown();
//   }
#pragma once

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <limits>
#include <string>

namespace tabletop_common {

class CliArgs {
 public:
  // usage() prints the tool's usage to stderr. skip_ros_args: ignore the "__name:=..." style
  // arguments roslaunch appends when a launch file starts the tool as a node.
  CliArgs(const char* tool, int argc, char** argv, std::function<void()> usage,
          bool skip_ros_args = false)
      : tool_(tool), argc_(argc), argv_(argv), usage_(std::move(usage)), skip_ros_(skip_ros_args) {}

  // Moves to the next option; false when none is left.
  bool next() {
    while (++i_ < argc_) {
      arg_ = argv_[i_];
      if (skip_ros_ && arg_.rfind("__", 0) == 0) continue;
      return true;
    }
    return false;
  }
  const std::string& arg() const { return arg_; }
  bool is(const char* option) const { return arg_ == option; }
  bool help() const { return arg_ == "-h" || arg_ == "--help"; }

  // The value after the current option.
  std::string text() {
    if (i_ + 1 >= argc_) fail(arg_ + " needs a value");
    return argv_[++i_];
  }
  long long integer(long long lo = std::numeric_limits<int>::min(),
                    long long hi = std::numeric_limits<int>::max()) {
    const std::string v = text();
    char* end = nullptr;
    errno = 0;
    const long long x = std::strtoll(v.c_str(), &end, 10);
    if (v.empty() || *end != '\0' || errno == ERANGE || x < lo || x > hi)
      fail(arg_ + " needs an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) +
           "], got '" + v + "'");
    return x;
  }
  double number(double lo = -std::numeric_limits<double>::max(),
                double hi = std::numeric_limits<double>::max()) {
    const std::string v = text();
    char* end = nullptr;
    const double x = std::strtod(v.c_str(), &end);
    if (v.empty() || *end != '\0' || !std::isfinite(x) || x < lo || x > hi)
      fail(arg_ + " needs a number in [" + shortNumber(lo) + ", " + shortNumber(hi) + "], got '" +
           v + "'");
    return x;
  }

  [[noreturn]] void fail(const std::string& message) const {
    std::fprintf(stderr, "%s: %s\n", tool_, message.c_str());
    if (usage_) usage_();
    std::exit(2);
  }
  [[noreturn]] void unknown() const { fail("unknown option '" + arg_ + "'"); }

 private:
  static std::string shortNumber(double x) {
    if (x <= -std::numeric_limits<double>::max()) return "-inf";
    if (x >= std::numeric_limits<double>::max()) return "inf";
    char buf[32];
    std::snprintf(buf, sizeof(buf), "%g", x);
    return buf;
  }

  const char* tool_;
  int argc_;
  char** argv_;
  std::function<void()> usage_;
  bool skip_ros_;
  int i_ = 0;
  std::string arg_;
};

}  // namespace tabletop_common
