// render_calibration: a simulated checkerboard calibration sequence for one camera of the
// simulated rig (issue 18 step 4; tabletop_sim/calibration_target.h): PNG images of a board at
// random poses seen through that camera's own distortion, and the true rig YAML to compare a
// calibration with.
//
//   render_calibration --camera 0 --views 80 --out /tmp/calib
//   calibrate_intrinsics --images '/tmp/calib/cam0_*.png' --board 9x6 --square 0.03 --camera cam0
#include <cstdio>
#include <string>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "tabletop_capture/calibration/board_poses.h"
#include "tabletop_capture/default_rig.h"
#include "tabletop_capture/rig_description.h"
#include "tabletop_common/cli_args.h"
#include "tabletop_sim/calibration_target.h"

namespace {
void usage() {
  std::fprintf(stderr,
      "usage: render_calibration --out DIR [options]\n"
      "  --out DIR      where cam<i>_NNN.png and truth_rig.yaml go (created)\n"
      "  --camera I     the default rig's camera (default 0)\n"
      "  --views N      board poses (default 80)\n"
      "  --board CxR    inner corners (default 9x6)\n"
      "  --square M     square edge in metres (default 0.03)\n"
      "  --noise S      sensor noise, grey levels (default 2)\n"
      "  --seed S       poses and noise (default 1)\n");
}
}  // namespace

int main(int argc, char** argv) {
  std::string out;
  int camera = 0, views = 80;
  unsigned seed = 1;
  tabletop_capture::CheckerboardSpec board{9, 6, 0.03};
  tabletop_sim::TargetImageOptions options;
  tabletop_common::CliArgs args("render_calibration", argc, argv, usage);
  while (args.next()) {
    if (args.is("--out")) out = args.text();
    else if (args.is("--camera")) camera = static_cast<int>(args.integer(0, 15));
    else if (args.is("--views")) views = static_cast<int>(args.integer(1, 10000));
    else if (args.is("--square")) board.square = args.number(1e-3, 1.0);
    else if (args.is("--noise")) options.noise_sigma = args.number(0, 50);
    else if (args.is("--seed")) seed = static_cast<unsigned>(args.integer(0, 1 << 30));
    else if (args.is("--board")) {
      const std::string b = args.text();
      if (std::sscanf(b.c_str(), "%dx%d", &board.cols, &board.rows) != 2)
        args.fail("--board needs COLSxROWS, e.g. 9x6, got '" + b + "'");
    } else if (args.help()) {
      usage();
      return 0;
    } else {
      args.unknown();
    }
  }
  if (out.empty()) args.fail("--out is required");
  try {
    const auto rig = tabletop_capture::makeDefaultRig(tabletop_capture::DefaultRigOptions{});
    if (camera >= static_cast<int>(rig.cameras.size())) args.fail("--camera out of range");
    const auto& cam = rig.cameras[camera];
    const tabletop_sim::CheckerboardRenderer renderer(cam, board, options);
    const auto poses = tabletop_capture::randomBoardPoses(cam, board, views, seed);
    if (static_cast<int>(poses.size()) < views)
      std::fprintf(stderr, "render_calibration: only %zu board poses fit the view\n", poses.size());
    if (std::system(("mkdir -p '" + out + "'").c_str()) != 0)
      throw std::runtime_error("cannot create " + out);
    for (size_t k = 0; k < poses.size(); ++k) {
      cv::Mat bgr;
      cv::cvtColor(renderer.render(poses[k], seed * 100000 + k), bgr, cv::COLOR_RGB2BGR);
      char name[64];
      std::snprintf(name, sizeof name, "/%s_%03zu.png", cam.name.c_str(), k);
      if (!cv::imwrite(out + name, bgr)) throw std::runtime_error("cannot write " + out + name);
      if ((k + 1) % 20 == 0 || k + 1 == poses.size())
        std::printf("[render_calibration] %zu/%zu images\n", k + 1, poses.size());
    }
    tabletop_capture::saveRigYaml(rig, out + "/truth_rig.yaml");
    std::printf("[render_calibration] %s: %zu views of a %dx%d board (%.0f mm squares), truth in "
                "%s/truth_rig.yaml\n", cam.name.c_str(), poses.size(), board.cols, board.rows,
                board.square * 1e3, out.c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "render_calibration: %s\n", e.what());
    return 1;
  }
  return 0;
}
