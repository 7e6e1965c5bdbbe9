// render_camera_images: the simulated rig's camera images as one PNG sequence per camera
// (DIR/cam<i>/NNNNN.png, the same number = the same instant) with the rig YAML beside them
// (DIR/rig.yaml): the input of CameraCapture nodelets posing as cameras
// (device file:DIR/cam<i>/%05d.png), as launch/full_rig.launch runs them without hardware.
//
//   render_camera_images --out /tmp/rig_images --cameras 4 --frames 60
//   roslaunch launch/full_rig.launch rig_file:=/tmp/rig_images/rig.yaml cameras:=4 \
//     devices:='file:/tmp/rig_images/{camera}/%05d.png' tolerance:=0.03 \
//     capture_config:=capture.yaml   # camera_capture.yaml with width 320, height 240
#include <cstdio>
#include <string>

#include "tabletop_capture/rig_description.h"
#include "tabletop_common/cli_args.h"
#include "tabletop_sim/camera_image_folders.h"
#include "tabletop_sim/simulated_rig.h"

namespace {
void usage() {
  std::fprintf(stderr,
      "usage: render_camera_images --out DIR [options]\n"
      "  --out DIR           where cam<i>/NNNNN.png and rig.yaml go (created)\n"
      "  --cameras N         cameras of the default ring (default 8)\n"
      "  --frames N          frames per camera (default 60)\n"
      "  --empty-frames N    of which the first N show no person (default 25)\n"
      "  --script NAME       the person's motion (default all; describe_scenario lists them)\n"
      "  --scenario NAME     default, a preset or random-<seed> (default default)\n"
      "  --seed S            sensor noise (default 1)\n");
}
}  // namespace

int main(int argc, char** argv) {
  std::string out;
  int frames = 60;
  tabletop_sim::SimOptions options;
  tabletop_common::CliArgs args("render_camera_images", argc, argv, usage);
  while (args.next()) {
    if (args.is("--out")) out = args.text();
    else if (args.is("--cameras")) options.num_cameras = static_cast<int>(args.integer(1, 16));
    else if (args.is("--frames")) frames = static_cast<int>(args.integer(1, 100000));
    else if (args.is("--empty-frames")) options.empty_frames = static_cast<int>(args.integer(0, 100000));
    else if (args.is("--script")) options.script = args.text();
    else if (args.is("--scenario")) options.scenario = args.text();
    else if (args.is("--seed")) options.seed = static_cast<uint64_t>(args.integer(0, 1 << 30));
    else if (args.help()) {
      usage();
      return 0;
    } else {
      args.unknown();
    }
  }
  if (out.empty()) args.fail("--out is required");
  try {
    const tabletop_sim::SimulatedRig sim(options);
    const auto& rig = sim.rig();
    tabletop_sim::makeCameraFolders(out, rig);
    for (int f = 0; f < frames; ++f) {
      const tabletop_sim::SimFrame frame = sim.render(f);
      for (size_t c = 0; c < rig.cameras.size(); ++c)
        tabletop_sim::writeCameraImage(out, rig.cameras[c].name, f, frame.images[c]);
      if ((f + 1) % 20 == 0 || f + 1 == frames)
        std::printf("[render_camera_images] %d/%d frames\n", f + 1, frames);
    }
    tabletop_capture::saveRigYaml(rig, out + "/rig.yaml");
    std::printf("[render_camera_images] %zu cameras x %d frames (%d empty) in %s, rig %s/rig.yaml\n",
                rig.cameras.size(), frames, options.empty_frames, out.c_str(), out.c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "render_camera_images: %s\n", e.what());
    return 1;
  }
  return 0;
}
