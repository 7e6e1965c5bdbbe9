// export_frame_sets: the synchronised frame sets of a bag (/tabletop/frames) as per-camera PNG
// sequences, DIR/<camera>/NNNNN.png with the same name = the same set in every folder, the input
// of calibrate_intrinsics, calibrate_extrinsics and align_rig_to_marker (ros/frame_set_export.h).
//
//   export_frame_sets --bag lights.bag --out lights --every 2
//   calibrate_extrinsics --images lights ...
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include "tabletop_capture/ros/frame_set_export.h"
#include "tabletop_common/cli_args.h"

namespace {

void usage() {
  std::fprintf(stderr,
      "usage: export_frame_sets --bag FILE --out DIR [options]\n"
      "  --bag FILE         a bag with the synchroniser's frame sets (tabletop_msgs/MultiViewFrame):\n"
      "                     record /tabletop/frames, e.g. capture + synchroniser only:\n"
      "                       roslaunch launch/full_rig.launch ... psfs:=false tracking:=false \\\n"
      "                         body:=false meshes:=false\n"
      "                       rosbag record /tabletop/frames\n"
      "                     (raw camera topics are not accepted: the sets are what guarantees that\n"
      "                     the images of one file name were taken at the same instant)\n"
      "  --out DIR          writes DIR/<camera>/NNNNN.png (NNNNN: the set's index among the sets\n"
      "                     of the topic, so the same name is the same instant in every folder; a\n"
      "                     camera missing from a degraded set gets no file) and DIR/stamps.csv\n"
      "                     (index, stamp in s, cameras with a file)\n"
      "  --topic T          the frame sets' topic (default /tabletop/frames)\n"
      "  --every N          write only every Nth set (index 0, N, 2N, ...; default 1)\n"
      "  --max N            stop after N sets written (default: all)\n"
      "  --cameras A,B      only these cameras (default: all)\n"
      "  --quiet            no progress lines\n"
      "then e.g.: calibrate_extrinsics --images DIR ...,  align_rig_to_marker --images DIR ...,\n"
      "           calibrate_intrinsics --images 'DIR/cam0/*.png' ...\n");
}

std::vector<std::string> splitList(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream in(s);
  std::string item;
  while (std::getline(in, item, ','))
    if (!item.empty()) out.push_back(item);
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  std::string bag, out;
  bool quiet = false;
  tabletop_capture::FrameSetExportOptions options;
  tabletop_common::CliArgs args("export_frame_sets", argc, argv, usage);
  while (args.next()) {
    if (args.is("--bag")) {
      bag = args.text();
    } else if (args.is("--out")) {
      out = args.text();
    } else if (args.is("--topic")) {
      options.topic = args.text();
    } else if (args.is("--every")) {
      options.every = static_cast<int>(args.integer(1, 1000000));
    } else if (args.is("--max")) {
      options.max_sets = static_cast<int>(args.integer(1, 100000000));
    } else if (args.is("--cameras")) {
      options.cameras = splitList(args.text());
      if (options.cameras.empty()) args.fail("--cameras needs camera names, e.g. cam0,cam3");
    } else if (args.is("--quiet")) {
      quiet = true;
    } else if (args.help()) {
      usage();
      return 0;
    } else {
      args.unknown();
    }
  }
  if (bag.empty() || out.empty()) args.fail("--bag and --out are required");
  try {
    std::printf("[export_frame_sets] %s (%s) -> %s\n", bag.c_str(), options.topic.c_str(), out.c_str());
    std::fflush(stdout);
    const auto r = tabletop_capture::exportFrameSets(bag, out, options, [&](const std::string& line) {
      if (line.rfind("WARNING", 0) == 0) {
        std::fprintf(stderr, "[export_frame_sets] %s\n", line.c_str());
      } else if (!quiet) {
        std::printf("[export_frame_sets] %s\n", line.c_str());
        std::fflush(stdout);
      }
    });
    std::printf("[export_frame_sets] %d sets read, %d written (every %d)\n", r.sets_read,
                r.sets_written, options.every);
    for (const auto& c : r.cameras)
      std::printf("  %-8s %6d images written, %5d missing (degraded sets), %4d conversion failures\n",
                  c.name.c_str(), c.written, c.missing, c.failed);
    std::printf("[export_frame_sets] %d conversion failures; wrote %s/<camera>/NNNNN.png and %s/stamps.csv\n",
                r.conversion_failures, out.c_str(), out.c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "export_frame_sets: %s\n", e.what());
    return 1;
  }
  return 0;
}
