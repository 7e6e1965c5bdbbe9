// align_rig_to_marker: metric scale and world frame for a rig known up to a similarity (issue
// 18 step 3; calibration/marker_alignment.h). Reads DIR/<camera>/*.png for every camera of the
// input rig, detects the desk markers, triangulates their corners, fits the similarity onto
// the layout and writes the rig in the world frame (intrinsics unchanged). Prints progress per
// camera and a report (cameras that saw the markers, corner residuals in px and mm, scale, each
// camera's pose before and after, warnings); optionally a PNG of the camera layout.
//
//   align_rig_to_marker --rig pointlight_rig.yaml --images marker_images --out rig.yaml
//       --report marker_report.txt --layout-png rig_layout.png      (one line)
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "tabletop_capture/calibration/camera_pose_errors.h"
#include "tabletop_capture/calibration/marker_alignment.h"
#include "tabletop_capture/calibration/rig_layout_plot.h"
#include "tabletop_common/cli_args.h"

namespace {

void usage() {
  std::fprintf(stderr,
      "usage: align_rig_to_marker --rig FILE --images DIR --out FILE [options]\n"
      "  --rig FILE           the rig up to a similarity (the point-light step's output)\n"
      "  --images DIR         DIR/<camera name>/*.png: views of the desk markers (static scene;\n"
      "                       the corners are averaged over each camera's images)\n"
      "  --out FILE           the rig YAML in the world frame to write\n"
      "  --marker-layout FILE markers on the desk (YAML: dictionary, markers [{id, size, x, y}];\n"
      "                       default: five 150 mm DICT_4X4_50 markers, docs/calibration.md)\n"
      "  --marker-size M      one marker, id 0, of this size at the origin instead\n"
      "  --report FILE        also write the report there\n"
      "  --layout-png FILE    a top and side view of the aligned rig\n"
      "  --truth FILE         the true rig (simulation): also report each camera's error\n"
      "  --print-markers DIR  only write the layout's markers to print, DIR/marker_<id>.png (100 px\n"
      "                       per cell, a white margin of one cell), and DIR/marker_layout.yaml\n"
      "  --quiet              no line per camera\n");
}

std::string fmt(const char* f, double a = 0, double b = 0, double c = 0, double d = 0) {
  char buf[256];
  std::snprintf(buf, sizeof buf, f, a, b, c, d);
  return buf;
}

}  // namespace

int main(int argc, char** argv) {
  std::string rig_file, images, out, layout_file, report_file, png_file, truth_file, print_dir;
  double single = 0;
  bool quiet = false;
  tabletop_common::CliArgs args("align_rig_to_marker", argc, argv, usage);
  while (args.next()) {
    if (args.is("--rig")) rig_file = args.text();
    else if (args.is("--images")) images = args.text();
    else if (args.is("--out")) out = args.text();
    else if (args.is("--marker-layout")) layout_file = args.text();
    else if (args.is("--marker-size")) single = args.number(0.01, 2.0);
    else if (args.is("--report")) report_file = args.text();
    else if (args.is("--layout-png")) png_file = args.text();
    else if (args.is("--truth")) truth_file = args.text();
    else if (args.is("--print-markers")) print_dir = args.text();
    else if (args.is("--quiet")) quiet = true;
    else if (args.help()) {
      usage();
      return 0;
    } else {
      args.unknown();
    }
  }
  if (print_dir.empty() && (rig_file.empty() || images.empty() || out.empty()))
    args.fail("--rig, --images and --out are required");
  try {
    using namespace tabletop_capture;
    if (!print_dir.empty()) {
      MarkerLayout layout = layout_file.empty() ? defaultMarkerLayout() : loadMarkerLayoutYaml(layout_file);
      if (single > 0) layout.markers = {{0, single, Eigen::Vector2d::Zero()}};
      layout.validate();
      std::filesystem::create_directories(print_dir);
      for (const auto& m : layout.markers) {
        const cv::Mat cells = markerCells(layout.dictionary, m.id);
        cv::Mat sheet(cells.rows + 2, cells.cols + 2, CV_8UC1, cv::Scalar(255)), big;
        cells.copyTo(sheet(cv::Rect(1, 1, cells.cols, cells.rows)));
        cv::resize(sheet, big, cv::Size(), 100, 100, cv::INTER_NEAREST);
        const std::string f = print_dir + "/marker_" + std::to_string(m.id) + ".png";
        if (!cv::imwrite(f, big)) throw std::runtime_error("cannot write " + f);
        std::printf("[align_rig_to_marker] %s: print its black square %.1f mm wide, lay it at (%.3f, %.3f) m, "
                    "its top edge away from the user\n", f.c_str(), m.size * 1e3, m.centre.x(), m.centre.y());
      }
      std::ofstream(print_dir + "/marker_layout.yaml") << markerLayoutToYaml(layout);
      return 0;
    }
    const RigDescription rig = loadRigYaml(rig_file);
    MarkerLayout layout = layout_file.empty() ? defaultMarkerLayout() : loadMarkerLayoutYaml(layout_file);
    if (single > 0) layout.markers = {{0, single, Eigen::Vector2d::Zero()}};
    layout.validate();
    std::printf("[align_rig_to_marker] %s: %zu cameras; %zu markers of %s\n", rig_file.c_str(), rig.cameras.size(),
                layout.markers.size(), layout.dictionary.c_str());
    std::vector<MarkerSightings> sightings(rig.cameras.size());
    int total_images = 0;
    for (size_t c = 0; c < rig.cameras.size(); ++c) {
      const CameraModel& cam = rig.cameras[c];
      // A camera without a folder saw nothing (it may not see the desk).
      std::vector<std::string> found;
      const std::filesystem::path folder = std::filesystem::path(images) / cam.name;
      if (std::filesystem::is_directory(folder))
        for (const auto& e : std::filesystem::directory_iterator(folder))
          if (e.path().extension() == ".png") found.push_back(e.path().string());
      std::sort(found.begin(), found.end());
      for (const auto& f : found) {
        const cv::Mat img = cv::imread(f, cv::IMREAD_GRAYSCALE);
        if (img.empty()) throw std::runtime_error("cannot read " + f);
        if (img.cols != cam.width || img.rows != cam.height)
          throw std::runtime_error(f + ": " + std::to_string(img.cols) + "x" + std::to_string(img.rows) +
                                   " but the rig's " + cam.name + " is " + std::to_string(cam.width) + "x" +
                                   std::to_string(cam.height));
        std::vector<DetectedMarker> markers;
        for (const auto& m : detectMarkers(img, layout.dictionary, &cam))
          if (layout.find(m.id) >= 0) markers.push_back(m);
        sightings[c].add(markers);
      }
      total_images += static_cast<int>(found.size());
      if (!quiet) {
        std::string ids;
        for (const auto& [id, n] : sightings[c].frames()) ids += " " + std::to_string(id) + " (" + std::to_string(n) + ")";
        std::printf("[align_rig_to_marker] %s: %zu images, markers found:%s\n", cam.name.c_str(), found.size(),
                    ids.empty() ? " none" : ids.c_str());
        std::fflush(stdout);
      }
    }
    if (total_images == 0)
      throw std::runtime_error("no image found: expected " + images + "/<camera name>/*.png, e.g. " + images + "/" +
                               rig.cameras.front().name + "/00000.png");
    const MarkerAlignment a = alignRigToMarkers(rig, sightings, layout);

    std::ostringstream r;
    r << "align_rig_to_marker report\n";
    r << "input rig: " << rig_file << " (" << rig.cameras.size() << " cameras); images: " << images << "\n";
    r << "cameras that saw a marker: " << a.cameras_with_marker << " of " << rig.cameras.size() << ";";
    for (const auto& p : a.cameras) r << " " << p.camera << " (" << p.markers_seen << ")";
    r << "\nmarkers used (ids):";
    for (int id : a.markers_used) r << " " << id;
    const double angle = Eigen::AngleAxisd(a.rotation).angle() * 180 / M_PI;
    r << "\nscale: " << fmt("%.6f", a.scale) << " (input units -> m); rotation " << fmt("%.2f deg", angle)
      << "; translation " << fmt("(%.4f, %.4f, %.4f) m", a.translation.x(), a.translation.y(), a.translation.z())
      << "\n";
    r << "corner fit to the layout: " << fmt("%.2f mm RMS, %.2f mm worst", a.fit_rms * 1e3, a.fit_max * 1e3) << "\n";
    r << "corner reprojection: " << fmt("%.3f px RMS", a.reprojection_rms_px) << "\n";
    r << "per corner (id.corner: cameras, reprojection px RMS = mm at the corner, off the layout mm):\n";
    for (const auto& c : a.corners)
      r << "  " << c.marker_id << "." << c.corner << ": " << c.cameras.size()
        << fmt(" cameras, %.3f px = %.2f mm, %.2f mm\n", c.rms_px, c.rms_mm, (c.world - c.layout).norm() * 1e3);
    r << "per camera (centre in the input frame -> in world, height above the desk, distance to the origin):\n";
    for (size_t i = 0; i < a.cameras.size(); ++i) {
      const auto& p = a.cameras[i];
      r << "  " << p.camera
        << fmt(": (%.4f, %.4f, %.4f)", p.centre_before.x(), p.centre_before.y(), p.centre_before.z())
        << fmt(" -> (%.4f, %.4f, %.4f) m", p.centre_after.x(), p.centre_after.y(), p.centre_after.z())
        << fmt(", z %.3f m, %.3f m from the origin; view turned by %.2f deg\n", p.centre_after.z(),
               p.centre_after.norm(), angle);
    }
    if (!truth_file.empty()) {
      const RigDescription truth = loadRigYaml(truth_file);
      r << "against the truth " << truth_file << " (camera centre mm, orientation deg):\n";
      const auto errors = cameraPoseErrors(a.rig, truth);
      for (const auto& e : errors) r << "  " << e.camera << fmt(": %.3f mm, %.4f deg\n", e.position_m * 1e3, e.rotation_deg);
      const CameraPoseError worst = worstPoseError(errors);
      r << fmt("  worst: %.3f mm, %.4f deg\n", worst.position_m * 1e3, worst.rotation_deg);
    }
    if (a.warnings.empty()) r << "warnings: none\n";
    for (const auto& w : a.warnings) r << "WARNING: " << w << "\n";
    std::printf("%s", r.str().c_str());
    if (!report_file.empty()) {
      std::ofstream f(report_file);
      f << r.str();
      if (!f) throw std::runtime_error("cannot write " + report_file);
    }
    RigDescription aligned = a.rig;
    saveRigYaml(aligned, out);
    std::printf("[align_rig_to_marker] wrote %s\n", out.c_str());
    if (!png_file.empty()) {
      RigLayoutPlotOptions o;
      for (size_t m = 0; m < layout.markers.size(); ++m) o.markers.push_back(layout.corners(static_cast<int>(m)));
      for (const auto& c : a.corners) o.points.push_back(c.world);
      o.title = "align_rig_to_marker: " + out + fmt(" (scale %.4f, corner fit %.2f mm RMS)", a.scale, a.fit_rms * 1e3);
      if (!cv::imwrite(png_file, drawRigLayout(aligned, o))) throw std::runtime_error("cannot write " + png_file);
      std::printf("[align_rig_to_marker] wrote %s\n", png_file.c_str());
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "align_rig_to_marker: %s\n", e.what());
    return 1;
  }
  return 0;
}
