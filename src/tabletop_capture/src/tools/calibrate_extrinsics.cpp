// calibrate_extrinsics: the poses of all cameras of a rig from a point light waved through the
// workspace (issue 18, step 2 of the rig calibration; calibration/point_light_calibration.h).
// Reads DIR/<camera name>/*.png (the same file name in every camera's directory = the same
// instant), finds the light in each image (calibration/light_blob.h), solves, prints progress
// and a report (per camera: points seen, inliers, reprojection error, warnings) and writes the
// rig YAML with the intrinsics unchanged and the new poses. The detections can be saved and
// solved again without the images.
//
//   calibrate_extrinsics --rig intrinsics_rig.yaml --images /tmp/light --out rig.yaml
//       --report report.txt --save-detections light.csv   (one line)
//   calibrate_extrinsics --rig intrinsics_rig.yaml --detections light.csv --out rig.yaml
#include <algorithm>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "tabletop_capture/calibration/camera_pose_errors.h"
#include "tabletop_capture/calibration/light_images.h"
#include "tabletop_capture/calibration/point_light_calibration.h"
#include "tabletop_capture/rig_description.h"
#include "tabletop_common/cli_args.h"

namespace {

using tabletop_capture::LightTrack;

void usage() {
  std::fprintf(stderr,
      "usage: calibrate_extrinsics --rig FILE (--images DIR | --detections FILE) --out FILE [options]\n"
      "  --rig FILE              rig YAML with every camera's intrinsics (calibrate_intrinsics); its\n"
      "                          poses, if not all identity, set the world frame and scale of the result\n"
      "  --images DIR            DIR/<camera name>/*.png; the same file name = the same instant\n"
      "  --detections FILE       detections saved by --save-detections (CSV frame,camera,u,v) instead\n"
      "  --out FILE              the rig YAML to write (intrinsics unchanged, new poses)\n"
      "  --report FILE           also write the report there\n"
      "  --save-detections FILE  write the detections found in the images (CSV)\n"
      "  --seed S                RANSAC seed (default 1); the same input and seed give the same rig\n"
      "  --min-cameras N         use frames where at least N >= 3 cameras saw the light (default 3)\n"
      "  --no-align              ignore the input poses: camera 0 is the world, |cam1 - cam0| = 1\n"
      "  --refine-intrinsics     also refine fx, fy, cx, cy (distortion stays)\n"
      "  --threshold G           darkest grey level a light pixel may have (default 80)\n"
      "  --max-area N            largest light spot in pixels (default 400)\n"
      "  --truth FILE            a simulated sequence's true rig: also print each camera's error\n"
      "                          after the similarity of the camera centres onto the true ones\n"
      "  --quiet                 no line per camera directory while reading\n");
}

std::string report(const tabletop_capture::PointLightCalibration& r, const LightTrack& track) {
  std::string out;
  char line[256];
  std::snprintf(line, sizeof line, "point-light extrinsic calibration: %zu frames with a detection, %d used (seen by >= 3 cameras), %zu points\n",
                track.frames.size(), r.frames_used, r.points.size());
  out += line;
  std::snprintf(line, sizeof line, "reprojection error: mean %.3f px, RMS %.3f px; %d solver iterations\n", r.mean_error_px,
                r.rms_px, r.iterations);
  out += line;
  out += "gauge: " + r.gauge + "\n";
  out += "camera      seen  inliers  outliers  RMS px  coverage  centre (world)\n";
  for (size_t c = 0; c < r.cameras.size(); ++c) {
    const auto& s = r.cameras[c];
    const Eigen::Vector3d x = r.rig.cameras[c].center();
    std::snprintf(line, sizeof line, "%-10s %5d  %7d  %8d  %6.3f  %6.0f %%  %7.3f %7.3f %7.3f\n",
                  r.rig.cameras[c].name.c_str(), s.observations, s.inliers, s.outliers, s.rms_px, 100 * s.coverage,
                  x.x(), x.y(), x.z());
    out += line;
  }
  for (const auto& w : r.warnings) out += "WARNING: " + w + "\n";
  if (r.warnings.empty()) out += "no warnings\n";
  return out;
}

// Each camera's error against a true rig after the similarity (Umeyama, with scale) of the
// camera centres onto the true ones: what a simulated sequence's calibration is judged by.
std::string compareWithTruth(const tabletop_capture::RigDescription& rig, const tabletop_capture::RigDescription& truth) {
  const Eigen::Matrix4d m = tabletop_capture::cameraCentreSimilarity(rig, truth);
  std::string out = "against the truth (similarity of the camera centres, scale " +
                    std::to_string(m.block<3, 1>(0, 0).norm()) + "):\n";
  char line[160];
  for (const auto& e : tabletop_capture::cameraPoseErrors(rig, truth, m)) {
    std::snprintf(line, sizeof line, "  %-10s position %.2f mm, orientation %.4f deg\n", e.camera.c_str(),
                  e.position_m * 1e3, e.rotation_deg);
    out += line;
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  std::string rig_file, images, detections, out, report_file, save_detections, truth_file;
  bool quiet = false;
  tabletop_capture::PointLightCalibrationOptions options;
  tabletop_capture::LightBlobOptions blob_options;
  tabletop_common::CliArgs args("calibrate_extrinsics", argc, argv, usage);
  while (args.next()) {
    if (args.is("--rig")) rig_file = args.text();
    else if (args.is("--images")) images = args.text();
    else if (args.is("--detections")) detections = args.text();
    else if (args.is("--out")) out = args.text();
    else if (args.is("--report")) report_file = args.text();
    else if (args.is("--save-detections")) save_detections = args.text();
    else if (args.is("--seed")) options.seed = static_cast<unsigned>(args.integer(0, 1 << 30));
    else if (args.is("--min-cameras")) options.min_cameras_per_frame = static_cast<int>(args.integer(3, 64));
    else if (args.is("--no-align")) options.align_to_input_poses = false;
    else if (args.is("--refine-intrinsics")) options.refine_intrinsics = true;
    else if (args.is("--threshold")) blob_options.min_threshold = args.number(1, 254);
    else if (args.is("--max-area")) blob_options.max_area = static_cast<int>(args.integer(1, 1 << 20));
    else if (args.is("--truth")) truth_file = args.text();
    else if (args.is("--quiet")) quiet = true;
    else if (args.help()) {
      usage();
      return 0;
    } else {
      args.unknown();
    }
  }
  if (rig_file.empty() || out.empty()) args.fail("--rig and --out are required");
  if (images.empty() == detections.empty()) args.fail("give either --images or --detections");
  try {
    const auto rig = tabletop_capture::loadRigYaml(rig_file);
    std::vector<std::string> names;
    for (const auto& c : rig.cameras) names.push_back(c.name);
    const LightTrack track =
        images.empty() ? tabletop_capture::loadLightTrackCsv(detections, names)
                       : tabletop_capture::detectLightInImages(
                             names, images, blob_options,
                             [&](int c, const tabletop_capture::LightImagesCamera& s) {
                               std::string why;
                               for (const auto& [reason, n] : s.rejected)
                                 why += (why.empty() ? "; none: " : ", ") + reason + " " + std::to_string(n);
                               if (!quiet || s.images == 0)
                                 std::printf("[calibrate_extrinsics] %s: %d images, light found in %d%s\n",
                                             names[c].c_str(), s.images, s.found, why.c_str());
                               std::fflush(stdout);
                             })
                             .track;
    const auto per_camera = track.detectionsPerCamera();
    std::printf("[calibrate_extrinsics] %zu cameras, %zu frames with a detection, %d seen by >= %d cameras\n",
                names.size(), track.frames.size(), track.framesSeenBy(options.min_cameras_per_frame),
                options.min_cameras_per_frame);
    if (!save_detections.empty()) {
      tabletop_capture::saveLightTrackCsv(track, save_detections);
      std::printf("[calibrate_extrinsics] wrote the detections to %s\n", save_detections.c_str());
    }
    const auto result = tabletop_capture::calibrateFromPointLight(rig, track, options, [](const std::string& line) {
      std::printf("[calibrate_extrinsics] %s\n", line.c_str());
      std::fflush(stdout);
    });
    std::string text = report(result, track);
    if (!truth_file.empty()) text += compareWithTruth(result.rig, tabletop_capture::loadRigYaml(truth_file));
    std::printf("%s", text.c_str());
    if (!report_file.empty()) {
      std::ofstream file(report_file);
      file << text;
      if (!file) throw std::runtime_error("cannot write " + report_file);
    }
    tabletop_capture::saveRigYaml(result.rig, out);
    std::printf("[calibrate_extrinsics] wrote %s\n", out.c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "calibrate_extrinsics: %s\n", e.what());
    return 1;
  }
  return 0;
}
