// render_bag: renders a scripted simulated-rig sequence into a bag (camera topics,
// camera_info, latched /tf_static, ground truth), with a progress bar.
// Run `rosrun tabletop_sim render_bag --help` for the options.
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <string>

#include "tabletop_common/cli_args.h"
#include "tabletop_sim/ros/sim_bag_writer.h"

namespace {

void usage() {
  std::printf(
      "Usage: render_bag --out FILE.bag [options]\n"
      "  --frames N        frame sets, the empty background frames included (default 100)\n"
      "  --cameras N       number of cameras (default 8)\n"
      "  --width W --height H   image size (default 320x240)\n"
      "  --fps F           frame rate, sets the stamps (default 25)\n"
      "  --script NAME     motion script (default all)\n"
      "  --empty-frames N  frames without the person at the start (default 25)\n"
      "  --seed N          noise seed (default 1)\n"
      "  --noise SIGMA     sensor noise in grey levels (default 2.0)\n"
      "  --bayer ENC       write Bayer images (bayer_rggb8, ...) instead of rgb8\n"
      "  --scenario NAME   default, a preset or random-SEED (tabletop_sim/scenario.h);\n"
      "                    any but default replaces cameras, size and noise\n"
      "  --short-sleeves   bare forearms\n"
      "  --no-compress     do not LZ4-compress the bag chunks\n");
}

}  // namespace

int main(int argc, char** argv) {
  tabletop_sim::SimOptions so;
  tabletop_sim::SimBagOptions bo;
  tabletop_common::CliArgs args("render_bag", argc, argv, usage);
  while (args.next()) {
    if (args.is("--out")) bo.path = args.text();
    else if (args.is("--frames")) bo.frames = static_cast<int>(args.integer(1));
    else if (args.is("--cameras")) so.num_cameras = static_cast<int>(args.integer(1, 16));
    else if (args.is("--width")) so.width = static_cast<int>(args.integer(16, 8192));
    else if (args.is("--height")) so.height = static_cast<int>(args.integer(16, 8192));
    else if (args.is("--fps")) so.fps = args.number(0.1, 1000.0);
    else if (args.is("--script")) so.script = args.text();
    else if (args.is("--empty-frames")) so.empty_frames = static_cast<int>(args.integer(0));
    else if (args.is("--seed"))
      so.seed = static_cast<decltype(so.seed)>(args.integer(0, std::numeric_limits<long long>::max()));
    else if (args.is("--noise")) so.noise_sigma = args.number(0.0, 255.0);
    else if (args.is("--bayer")) so.bayer = args.text();
    else if (args.is("--short-sleeves")) so.short_sleeves = true;
    else if (args.is("--scenario")) so.scenario = args.text();
    else if (args.is("--no-compress")) bo.lz4 = false;
    else if (args.help()) {
      usage();
      return 0;
    } else {
      args.unknown();
    }
  }
  if (bo.path.empty()) {
    std::fprintf(stderr, "render_bag: --out FILE.bag is required\n");
    usage();
    return 2;
  }
  try {
    const tabletop_sim::SimulatedRig rig(so);
    const bool tty = isatty(fileno(stderr));
    const auto start = std::chrono::steady_clock::now();
    tabletop_sim::writeSimBag(rig, bo, [&](int done, int total) {
      if (!tty && done != total && done % 25 != 0) return;
      const double s =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      const int width = 40, filled = width * done / total;
      std::fprintf(stderr, "%s[%s%s] %d/%d frame sets, %.1f s%s", tty ? "\r" : "",
                   std::string(filled, '#').c_str(), std::string(width - filled, '.').c_str(),
                   done, total, s, tty ? "" : "\n");
    });
    std::fprintf(stderr, "\nrender_bag: wrote %s (%d frame sets, %d cameras)\n", bo.path.c_str(),
                 bo.frames, so.num_cameras);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "\nrender_bag: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
