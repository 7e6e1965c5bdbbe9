// mesh_eval: accuracy of the hand meshes on the simulated rig (hand_mesh_evaluation.h): mean and
// 95th-percentile distances (mm) from the mesh to the true hand surface and back, for the
// probabilistic and the binary marching cubes, printed and written to <out>/mesh_accuracy.txt,
// plus <out>/hand_meshes.png (both hands of one frame: probabilistic meshes above, binary below).
//
//   mesh_eval [--script NAME] [--frames N] [--every K] [--seed N] [--iso P] [--out DIR]
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <ros/package.h>

#include "cvephands_bridge/eval/hand_mesh_evaluation.h"
#include "cvephands_bridge/mesh/mesh_render.h"
#include "tabletop_common/cli_args.h"

namespace {

void usage() {
  std::fprintf(stderr,
               "usage: mesh_eval [--scenario NAME] [--script NAME] [--frames N] [--every K] [--seed N] [--iso P] "
               "[--min-component N] [--keep-radius M] [--no-floor-clip] [--out DIR]\n"
               "  --scenario  simulated world: default, a preset or random-SEED (default default)\n"
               "  --script  simulated motion script (default reach_targets)\n"
               "  --frames  script frames after the 25 background frames (default: whole script)\n"
               "  --every   score every K-th frame (default 5)\n"
               "  --seed    sensor noise seed (default 1)\n"
               "  --iso     iso-surface probability (default 0.6)\n"
               "  --min-component  drop mesh components under N triangles (default 64)\n"
               "  --keep-radius    drop mesh components no nearer than M metres to the hand (default\n"
               "                   0.08, as config/hand_mesher.yaml; 0 keeps them)\n"
               "  --no-floor-clip  hand cubes keep what lies below the desk top (psfs.yaml\n"
               "                   hand_volumes/clip_below_floor: false)\n"
               "  --out     output folder (default ./output)\n");
}

// Both hands of the picture frame, each framed on its own (seen from the user's side of the
// desk, looking forward and down): probabilistic meshes in the top row, binary below, so the
// two variants of one hand compare pixel for pixel.
cv::Mat picture(const cvephands::HandMeshEvalResult& r) {
  using cvephands::RenderItem;
  const Eigen::Vector3d dir(0.0, 0.75, -0.66);
  const char* rows[2] = {"probabilistic", "binary"};
  const char* sides[2] = {"left hand", "right hand"};
  cv::Mat grid[2][2];
  for (int s = 0; s < 2; ++s) {
    const cvephands::RenderCamera cam = cvephands::framingCamera(
        {RenderItem{&r.picture[0][s]}, RenderItem{&r.picture[1][s]}}, dir, 480, 360);
    for (int m = 0; m < 2; ++m) {
      grid[m][s] = cvephands::renderMeshes({RenderItem{&r.picture[m][s]}}, cam);
      cv::putText(grid[m][s], std::string(rows[m]) + ", " + sides[s], cv::Point(10, 24),
                  cv::FONT_HERSHEY_SIMPLEX, 0.6, cv::Scalar(40, 40, 40), 1, cv::LINE_AA);
      cv::rectangle(grid[m][s], cv::Rect(0, 0, 480, 360), cv::Scalar(200, 200, 200), 1);
    }
  }
  cv::Mat top, bottom, out;
  cv::hconcat(grid[0][0], grid[0][1], top);
  cv::hconcat(grid[1][0], grid[1][1], bottom);
  cv::vconcat(top, bottom, out);
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  cvephands::HandMeshEvalOptions o;
  std::string out = "output";
  tabletop_common::CliArgs args("mesh_eval", argc, argv, usage);
  while (args.next()) {
    if (args.is("--script")) o.script = args.text();
    else if (args.is("--scenario")) o.scenario = args.text();
    else if (args.is("--frames")) o.frames = static_cast<int>(args.integer(0));
    else if (args.is("--every")) o.every = static_cast<int>(args.integer(1));
    else if (args.is("--seed")) o.seed = static_cast<int>(args.integer(0));
    else if (args.is("--iso")) o.iso = args.number(0.0, 1.0);
    else if (args.is("--min-component")) o.min_component_triangles = static_cast<int>(args.integer(0));
    else if (args.is("--keep-radius")) o.keep_radius = args.number(0.0, 1.0);
    else if (args.is("--no-floor-clip")) o.clip_floor = false;
    else if (args.is("--out")) out = args.text();
    else if (args.help()) {
      usage();
      return 0;
    } else {
      args.unknown();
    }
  }
  const std::string pkg = ros::package::getPath("psfs_reconstruction");
  if (pkg.empty()) {
    std::fprintf(stderr, "mesh_eval: package psfs_reconstruction not found (source devel/setup.bash)\n");
    return 1;
  }
  o.skin_model = pkg + "/config/skin_gmm.yaml";
  o.progress = [](int done, int total) {
    std::fprintf(stderr, "\r[mesh_eval] %d/%d frames scored", done, total);
  };
  cvephands::HandMeshEvalResult r;
  try {
    r = cvephands::evaluateHandMeshes(o);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "\nmesh_eval: %s\n", e.what());
    return 1;
  }
  std::fprintf(stderr, "\n");
  const std::string text = "==== hand meshes vs the true hand surface ====\nsimulated rig, script '" +
                           o.script + "', seed " + std::to_string(o.seed) + ", iso " +
                           std::to_string(o.iso).substr(0, 4) + ", 83^3 / 30 cm hand volumes, " +
                           "components within " + std::to_string(o.keep_radius).substr(0, 4) +
                           " m of the hand, " + (o.clip_floor ? "" : "no floor clip, ") + "every " +
                           std::to_string(o.every) + ". frame\n" +
                           r.summary();
  std::printf("%s", text.c_str());
  if (std::system(("mkdir -p '" + out + "'").c_str()) != 0) {
    std::fprintf(stderr, "mesh_eval: cannot create %s\n", out.c_str());
    return 1;
  }
  std::ofstream(out + "/mesh_accuracy.txt") << text;
  if (r.picture_frame >= 0) {
    const std::string png = out + "/hand_meshes.png";
    if (cv::imwrite(png, picture(r)))
      std::printf("  picture (frame %d): %s\n", r.picture_frame, png.c_str());
  } else {
    std::printf("  no frame with both hands meshed: no picture\n");
  }
  return 0;
}
