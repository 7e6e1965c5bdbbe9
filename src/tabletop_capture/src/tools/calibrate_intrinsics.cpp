// calibrate_intrinsics: one camera's intrinsics from images of a checkerboard (issue 18, step 1
// of the rig calibration; calibration/intrinsic_calibration.h). Prints progress per image and a
// report (intrinsics, reprojection error overall and for the worst views, image coverage,
// warnings), and writes a rig YAML with that one camera (identity pose: the extrinsic steps
// set it) or, with --rig, the given rig with that camera's intrinsics replaced.
//
//   calibrate_intrinsics --images 'cam0/*.png' --board 9x6 --square 0.03 --camera cam0 \
//       --out cam0_intrinsics.yaml
#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include <opencv2/core/utility.hpp>

#include "tabletop_capture/calibration/intrinsic_calibration.h"
#include "tabletop_capture/rig_description.h"
#include "tabletop_common/cli_args.h"

namespace {

void usage() {
  std::fprintf(stderr,
      "usage: calibrate_intrinsics --images PATTERN --board COLSxROWS --square M [options]\n"
      "  --images PATTERN  image files, a glob in quotes ('cam0/*.png'; sorted by name)\n"
      "  --board CxR       inner corners per row x per column (squares - 1), e.g. 9x6\n"
      "  --square M        edge of one square in metres, e.g. 0.03\n"
      "  --camera NAME     the camera's name in the rig (default cam0)\n"
      "  --rig FILE        update this rig YAML's camera NAME instead of writing a new rig\n"
      "  --out FILE        the rig YAML to write (default <camera>_intrinsics.yaml)\n"
      "  --max-views N     calibrate from at most N views with the board, evenly spread over the\n"
      "                    sequence (default 80; the solver's cost grows with the cube of N)\n"
      "  --k3              also estimate k3 (wide-angle lenses)\n"
      "  --no-tangential   p1 = p2 = 0\n"
      "  --quiet           no line per image\n");
}

}  // namespace

int main(int argc, char** argv) {
  std::string pattern, camera = "cam0", rig_file, out;
  tabletop_capture::CheckerboardSpec board;
  board.cols = 0;
  board.square = 0;
  int max_views = 80;
  bool quiet = false;
  tabletop_capture::IntrinsicCalibrationOptions options;
  tabletop_common::CliArgs args("calibrate_intrinsics", argc, argv, usage);
  while (args.next()) {
    if (args.is("--images")) {
      pattern = args.text();
    } else if (args.is("--board")) {
      const std::string b = args.text();
      if (std::sscanf(b.c_str(), "%dx%d", &board.cols, &board.rows) != 2)
        args.fail("--board needs COLSxROWS, e.g. 9x6, got '" + b + "'");
    } else if (args.is("--square")) {
      board.square = args.number(1e-4, 1.0);
    } else if (args.is("--camera")) {
      camera = args.text();
    } else if (args.is("--rig")) {
      rig_file = args.text();
    } else if (args.is("--out")) {
      out = args.text();
    } else if (args.is("--max-views")) {
      max_views = static_cast<int>(args.integer(3, 10000));
    } else if (args.is("--k3")) {
      options.estimate_k3 = true;
    } else if (args.is("--no-tangential")) {
      options.tangential = false;
    } else if (args.is("--quiet")) {
      quiet = true;
    } else if (args.help()) {
      usage();
      return 0;
    } else {
      args.unknown();
    }
  }
  if (pattern.empty() || board.cols == 0 || board.square == 0)
    args.fail("--images, --board and --square are required");
  if (out.empty()) out = camera + "_intrinsics.yaml";
  try {
    board.validate();
    std::vector<cv::String> found;
    cv::glob(pattern, found, false);
    std::vector<std::string> files(found.begin(), found.end());
    std::sort(files.begin(), files.end());
    if (files.empty()) throw std::runtime_error("no file matches '" + pattern + "'");
    std::printf("[calibrate_intrinsics] %zu images, board %dx%d inner corners of %.1f mm\n",
                files.size(), board.cols, board.rows, board.square * 1e3);
    const auto r = tabletop_capture::calibrateIntrinsicsFromImages(
        files, board, max_views, options, [&](int i, const std::string& f, bool ok) {
          if (!quiet || (i + 1) % 50 == 0 || i + 1 == static_cast<int>(files.size()))
            std::printf("[calibrate_intrinsics] %d/%zu %s: %s\n", i + 1, files.size(), f.c_str(),
                        ok ? "board found" : "no board");
          std::fflush(stdout);
        });
    const auto& c = r.calibration;
    std::printf("[calibrate_intrinsics] board found in %d of %d images; calibrated from %d views\n",
                r.boards_found, r.images, c.views);
    std::printf("  %s: %dx%d  fx %.3f  fy %.3f  cx %.3f  cy %.3f  (px)\n", camera.c_str(),
                c.camera.width, c.camera.height, c.camera.fx, c.camera.fy, c.camera.cx, c.camera.cy);
    std::printf("  D (k1 k2 p1 p2 k3): %.5f %.5f %.6f %.6f %.5f\n", c.camera.distortion[0],
                c.camera.distortion[1], c.camera.distortion[2], c.camera.distortion[3],
                c.camera.distortion[4]);
    std::printf("  reprojection error %.3f px RMS; image coverage %.0f %%\n", c.rms_px, c.coverage * 100);
    std::vector<size_t> order(c.view_rms_px.size());
    for (size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return c.view_rms_px[a] > c.view_rms_px[b]; });
    for (size_t k = 0; k < std::min<size_t>(3, order.size()); ++k)
      std::printf("  worst view %zu: %s %.3f px\n", k + 1, r.used[order[k]].c_str(), c.view_rms_px[order[k]]);
    for (const auto& w : c.warnings) std::printf("  WARNING: %s\n", w.c_str());

    tabletop_capture::RigDescription rig;
    tabletop_capture::CameraModel cam = c.camera;
    cam.name = camera;
    cam.frame_id = camera + "_optical_frame";
    if (!rig_file.empty()) {
      rig = tabletop_capture::loadRigYaml(rig_file);
      auto it = std::find_if(rig.cameras.begin(), rig.cameras.end(),
                             [&](const tabletop_capture::CameraModel& m) { return m.name == camera; });
      if (it == rig.cameras.end()) throw std::runtime_error(rig_file + ": no camera '" + camera + "'");
      cam.frame_id = it->frame_id;
      cam.world_T_camera = it->world_T_camera;
      *it = cam;
    } else {
      rig.name = camera + "_intrinsics";
      rig.cameras.push_back(cam);
    }
    tabletop_capture::saveRigYaml(rig, out);
    std::printf("[calibrate_intrinsics] wrote %s\n", out.c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "calibrate_intrinsics: %s\n", e.what());
    return 1;
  }
  return 0;
}
