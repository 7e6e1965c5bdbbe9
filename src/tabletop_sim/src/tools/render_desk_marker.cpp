// render_desk_marker: simulated images of the desk markers for the world-frame step of the rig
// calibration (issue 18 step 3; tabletop_sim/desk_marker.h): every camera of the default rig
// (or --rig) sees the marker layout lying on the desk, frames differing in sensor noise only.
// Writes DIR/<camera>/NNNNN.png, DIR/truth_rig.yaml, DIR/marker_layout.yaml and
// DIR/rig_up_to_similarity.yaml: the truth moved by a similarity (scale 0.6, a turn about a
// skew axis, a shift), a stand-in for the point-light step's output to align.
//
//   render_desk_marker --out /tmp/marker --frames 8
//   align_rig_to_marker --rig /tmp/marker/rig_up_to_similarity.yaml --images /tmp/marker
//       --marker-layout /tmp/marker/marker_layout.yaml --out rig.yaml      (one line)
#include <cstdio>
#include <fstream>
#include <string>

#include "tabletop_capture/calibration/marker_alignment.h"
#include "tabletop_capture/calibration/marker_layout.h"
#include "tabletop_capture/default_rig.h"
#include "tabletop_capture/rig_description.h"
#include "tabletop_common/cli_args.h"
#include "tabletop_sim/camera_image_folders.h"
#include "tabletop_sim/desk_marker.h"

namespace {
void usage() {
  std::fprintf(stderr,
      "usage: render_desk_marker --out DIR [options]\n"
      "  --out DIR            where <camera>/NNNNN.png, truth_rig.yaml, marker_layout.yaml go\n"
      "  --frames N           images per camera (default 8; only the noise differs)\n"
      "  --seed S             noise (default 1)\n"
      "  --rig FILE           the true rig (default: the simulated default rig)\n"
      "  --marker-layout FILE markers on the desk (default: five 150 mm DICT_4X4_50 markers,\n"
      "                       tabletop_capture/calibration/marker_layout.h)\n"
      "  --marker-size M      one marker of this size at the origin instead (id 0)\n"
      "  --noise S            sensor noise, grey levels (default 2)\n"
      "  --paper-margin C     white paper around each marker, in marker cells (default 1)\n");
}
}  // namespace

int main(int argc, char** argv) {
  std::string out, rig_file, layout_file;
  int frames = 8;
  unsigned seed = 1;
  double single = 0;
  tabletop_sim::DeskMarkerImageOptions options;
  tabletop_common::CliArgs args("render_desk_marker", argc, argv, usage);
  while (args.next()) {
    if (args.is("--out")) out = args.text();
    else if (args.is("--frames")) frames = static_cast<int>(args.integer(1, 10000));
    else if (args.is("--seed")) seed = static_cast<unsigned>(args.integer(0, 1 << 30));
    else if (args.is("--rig")) rig_file = args.text();
    else if (args.is("--marker-layout")) layout_file = args.text();
    else if (args.is("--marker-size")) single = args.number(0.01, 2.0);
    else if (args.is("--noise")) options.noise_sigma = args.number(0, 50);
    else if (args.is("--paper-margin")) options.paper_margin_cells = args.number(0, 10);
    else if (args.help()) {
      usage();
      return 0;
    } else {
      args.unknown();
    }
  }
  if (out.empty()) args.fail("--out is required");
  try {
    const auto rig = rig_file.empty() ? tabletop_capture::makeDefaultRig() : tabletop_capture::loadRigYaml(rig_file);
    auto layout = layout_file.empty() ? tabletop_capture::defaultMarkerLayout()
                                      : tabletop_capture::loadMarkerLayoutYaml(layout_file);
    if (single > 0) layout.markers = {{0, single, Eigen::Vector2d::Zero()}};
    layout.validate();
    tabletop_sim::makeCameraFolders(out, rig);
    for (const auto& cam : rig.cameras) {
      const tabletop_sim::DeskMarkerRenderer renderer(cam, layout, options);
      for (int f = 0; f < frames; ++f)
        tabletop_sim::writeCameraImage(
            out, cam.name, f, renderer.render(std::uint64_t(seed) * 1000003 + 1000 * f + rig.findCamera(cam.name)));
      std::printf("[render_desk_marker] %s: %d images\n", cam.name.c_str(), frames);
      std::fflush(stdout);
    }
    tabletop_capture::saveRigYaml(rig, out + "/truth_rig.yaml");
    std::ofstream(out + "/marker_layout.yaml") << tabletop_capture::markerLayoutToYaml(layout);
    const Eigen::Matrix3d R =
        Eigen::AngleAxisd(2.1, Eigen::Vector3d(0.3, -0.5, 0.8).normalized()).toRotationMatrix();
    auto similar = tabletop_capture::transformRig(rig, 0.6, R, Eigen::Vector3d(0.7, -1.9, 3.2));
    similar.name = rig.name + "_up_to_similarity";
    tabletop_capture::saveRigYaml(similar, out + "/rig_up_to_similarity.yaml");
    std::printf("[render_desk_marker] %zu markers of %s on the desk, %zu cameras; truth in %s/truth_rig.yaml, "
                "layout in %s/marker_layout.yaml\n", layout.markers.size(), layout.dictionary.c_str(),
                rig.cameras.size(), out.c_str(), out.c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "render_desk_marker: %s\n", e.what());
    return 1;
  }
  return 0;
}
