// render_point_light: a simulated point-light sequence for the extrinsic calibration (issue 18
// step 4; tabletop_sim/point_light.h): DIR/<camera name>/NNNNN.png (the same number in every
// camera = the same instant), the true rig (truth_rig.yaml), the rig to calibrate from
// (intrinsics_rig.yaml: the true intrinsics, identity poses or the true ones disturbed) and the
// light's true path (truth_light.csv: frame,x,y,z).
//
//   render_point_light --out /tmp/light --frames 600
//   calibrate_extrinsics --rig /tmp/light/intrinsics_rig.yaml --images /tmp/light --out rig.yaml
#include <cstdio>
#include <fstream>
#include <random>
#include <string>

#include "tabletop_capture/default_rig.h"
#include "tabletop_capture/rig_description.h"
#include "tabletop_common/cli_args.h"
#include "tabletop_sim/camera_image_folders.h"
#include "tabletop_sim/point_light.h"

namespace {
void usage() {
  std::fprintf(stderr,
      "usage: render_point_light --out DIR [options]\n"
      "  --out DIR              where <camera>/NNNNN.png, truth_rig.yaml, intrinsics_rig.yaml and\n"
      "                         truth_light.csv go (created)\n"
      "  --frames N             instants (default 600: 20 s at 30 fps)\n"
      "  --seed S               path, faults and noise (default 1)\n"
      "  --cameras N            cameras of the default rig (default 8)\n"
      "  --step M               metres the light moves per frame (default 0.02)\n"
      "  --occlusion F          fraction of the time the light is hidden from each camera (default 0)\n"
      "  --outliers F           fraction of views showing a reflection instead of the light (default 0)\n"
      "  --sparse-camera I      this camera sees the light only --sparse-fraction of the time\n"
      "  --sparse-fraction F    (default 0.2)\n"
      "  --emission-angle DEG   the LED shines into a cone of this half angle about an axis that\n"
      "                         turns as the hand waves (default 180: all round)\n"
      "  --noise S              sensor noise, grey levels (default 2)\n"
      "  --rough-poses M        intrinsics_rig.yaml gets the true poses moved by about M metres and\n"
      "                         turned by M rad (a rig measured by hand; calibrate_extrinsics then\n"
      "                         keeps that world and scale). Default: identity poses, as\n"
      "                         calibrate_intrinsics writes\n");
}
}  // namespace

int main(int argc, char** argv) {
  std::string out;
  int frames = 600, cameras = 8;
  unsigned seed = 1;
  double step = 0.02, rough = 0;
  tabletop_sim::LightSequenceFaults faults;
  faults.sparse_fraction = 0.2;
  tabletop_sim::LightImageOptions image_options;
  tabletop_common::CliArgs args("render_point_light", argc, argv, usage);
  while (args.next()) {
    if (args.is("--out")) out = args.text();
    else if (args.is("--frames")) frames = static_cast<int>(args.integer(1, 1000000));
    else if (args.is("--seed")) seed = static_cast<unsigned>(args.integer(0, 1 << 30));
    else if (args.is("--cameras")) cameras = static_cast<int>(args.integer(1, 16));
    else if (args.is("--step")) step = args.number(1e-4, 1.0);
    else if (args.is("--occlusion")) faults.occlusion = args.number(0, 1);
    else if (args.is("--outliers")) faults.outliers = args.number(0, 1);
    else if (args.is("--sparse-camera")) faults.sparse_camera = static_cast<int>(args.integer(0, 15));
    else if (args.is("--sparse-fraction")) faults.sparse_fraction = args.number(0, 1);
    else if (args.is("--emission-angle")) faults.emission_half_angle_deg = args.number(1, 180);
    else if (args.is("--noise")) image_options.noise_sigma = args.number(0, 50);
    else if (args.is("--rough-poses")) rough = args.number(0, 1);
    else if (args.help()) {
      usage();
      return 0;
    } else {
      args.unknown();
    }
  }
  if (out.empty()) args.fail("--out is required");
  try {
    tabletop_capture::DefaultRigOptions rig_options;
    rig_options.num_cameras = cameras;
    const auto rig = tabletop_capture::makeDefaultRig(rig_options);
    if (faults.sparse_camera >= cameras) args.fail("--sparse-camera out of range");
    // The default rig's workspace (DESIGN.md section 3): the light is held above the desk.
    const Eigen::AlignedBox3d box(Eigen::Vector3d(-0.5, -0.5, 0.0), Eigen::Vector3d(0.5, 0.5, 0.75));
    const auto path = tabletop_sim::randomLightPath(box, frames, seed, step);
    const auto views = tabletop_sim::planLightSequence(rig, path, faults, seed + 1);
    tabletop_sim::makeCameraFolders(out, rig);
    std::vector<int> lit(rig.cameras.size(), 0);
    for (int f = 0; f < frames; ++f) {
      for (size_t c = 0; c < rig.cameras.size(); ++c) {
        const auto& cam = rig.cameras[c];
        tabletop_sim::writeCameraImage(
            out, cam.name, f,
            tabletop_sim::renderLightView(cam, views[f][c], image_options, (seed * 1000003ull + f) * 16 + c));
        lit[c] += views[f][c].light;
      }
      if ((f + 1) % 100 == 0 || f + 1 == frames)
        std::printf("[render_point_light] %d/%d frames\n", f + 1, frames);
    }
    tabletop_capture::saveRigYaml(rig, out + "/truth_rig.yaml");
    auto input = rig;
    std::mt19937_64 rng(seed + 2);
    std::normal_distribution<double> n01(0, 1);
    for (auto& cam : input.cameras) {
      if (rough <= 0) {
        cam.world_T_camera = Eigen::Isometry3d::Identity();
        continue;
      }
      const Eigen::Vector3d axis(n01(rng), n01(rng), n01(rng));
      cam.world_T_camera.translation() += rough * Eigen::Vector3d(n01(rng), n01(rng), n01(rng));
      cam.world_T_camera.linear() = cam.world_T_camera.linear() * Eigen::AngleAxisd(rough, axis.normalized()).toRotationMatrix();
    }
    input.name = rig.name + "_intrinsics";
    tabletop_capture::saveRigYaml(input, out + "/intrinsics_rig.yaml");
    std::ofstream truth(out + "/truth_light.csv");
    truth << "# frame,x,y,z (world, metres)\n";
    for (int f = 0; f < frames; ++f) truth << f << "," << path[f].x() << "," << path[f].y() << "," << path[f].z() << "\n";
    if (!truth) throw std::runtime_error("cannot write " + out + "/truth_light.csv");
    std::printf("[render_point_light] %d frames x %zu cameras in %s; the light in view of:", frames, rig.cameras.size(),
                out.c_str());
    for (size_t c = 0; c < rig.cameras.size(); ++c) std::printf(" %s %d", rig.cameras[c].name.c_str(), lit[c]);
    std::printf("\n");
  } catch (const std::exception& e) {
    std::fprintf(stderr, "render_point_light: %s\n", e.what());
    return 1;
  }
  return 0;
}
