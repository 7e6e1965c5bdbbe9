#include "tabletop_capture/calibration/marker_alignment.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <Eigen/Dense>
#include <Eigen/Geometry>

#include "tabletop_capture/calibration/triangulation.h"

namespace tabletop_capture {
namespace {

std::string format(const char* fmt, double a, double b = 0, double c = 0) {
  char buf[256];
  std::snprintf(buf, sizeof buf, fmt, a, b, c);
  return buf;
}

}  // namespace

RigDescription transformRig(const RigDescription& rig, double scale, const Eigen::Matrix3d& rotation,
                            const Eigen::Vector3d& translation) {
  RigDescription out = rig;
  for (auto& c : out.cameras) {
    const Eigen::Isometry3d T = c.world_T_camera;
    c.world_T_camera.linear() = rotation * T.linear();
    c.world_T_camera.translation() = scale * rotation * T.translation() + translation;
    // Re-orthonormalise against rounding so the rig file passes the loader's rotation check.
    const Eigen::Quaterniond q(c.world_T_camera.linear());
    c.world_T_camera.linear() = q.normalized().toRotationMatrix();
  }
  return out;
}

MarkerAlignment alignRigToMarkers(const RigDescription& rig, const std::vector<MarkerSightings>& sightings,
                                  const MarkerLayout& layout, const MarkerAlignmentOptions& options) {
  layout.validate();
  if (sightings.size() != rig.cameras.size())
    throw std::invalid_argument("alignRigToMarkers: " + std::to_string(sightings.size()) + " sightings for " +
                                std::to_string(rig.cameras.size()) + " cameras");
  MarkerAlignment a;
  std::vector<std::map<int, MarkerCorners>> means;
  std::vector<std::string> seen_by;
  for (size_t i = 0; i < sightings.size(); ++i) {
    means.push_back(sightings[i].mean());
    bool any = false;
    for (const auto& kv : means.back()) any = any || layout.find(kv.first) >= 0;
    if (any) seen_by.push_back(rig.cameras[i].name);
  }
  a.cameras_with_marker = static_cast<int>(seen_by.size());
  if (seen_by.size() < 2) {
    std::string who = seen_by.empty() ? "none" : seen_by[0];
    throw MarkerAlignmentError("a marker of the layout (" + layout.dictionary + ") was found in " +
                               std::to_string(seen_by.size()) + " camera(s) (" + who +
                               "); triangulating its corners needs >= 2 cameras");
  }

  // Triangulate every corner of every layout marker seen by >= 2 cameras.
  std::vector<Eigen::Vector3d> src, dst;
  for (size_t m = 0; m < layout.markers.size(); ++m) {
    const int id = layout.markers[m].id;
    std::vector<const CameraModel*> cams;
    std::vector<const MarkerCorners*> obs;
    std::vector<std::string> names;
    for (size_t i = 0; i < means.size(); ++i) {
      auto it = means[i].find(id);
      if (it == means[i].end()) continue;
      cams.push_back(&rig.cameras[i]);
      obs.push_back(&it->second);
      names.push_back(rig.cameras[i].name);
    }
    if (cams.size() == 1) a.warnings.push_back("marker id " + std::to_string(id) + " was seen by " + names[0] +
                                               " only: not used");
    if (cams.size() < 2) continue;
    const auto truth = layout.corners(static_cast<int>(m));
    std::vector<AlignedCorner> corners;
    for (int k = 0; k < 4; ++k) {
      std::vector<Eigen::Vector2d> px;
      for (const auto* o : obs) px.push_back((*o)[k]);
      const Triangulation t = triangulatePoint(cams, px, options.refine_iterations);
      if (!t.ok) break;
      AlignedCorner c;
      c.marker_id = id;
      c.corner = k;
      c.cameras = names;
      c.triangulated = t.point;
      c.layout = truth[k];
      c.residuals_px = t.residuals_px;
      c.rms_px = t.rms_px;
      corners.push_back(c);
    }
    if (corners.size() != 4) {
      a.warnings.push_back("marker id " + std::to_string(id) + ": a corner could not be triangulated "
                           "(behind a camera: is the input rig right?): not used");
      continue;
    }
    a.markers_used.push_back(id);
    for (auto& c : corners) {
      src.push_back(c.triangulated);
      dst.push_back(c.layout);
      a.corners.push_back(c);
    }
  }
  if (a.markers_used.empty())
    throw MarkerAlignmentError("no marker of the layout was seen by >= 2 cameras (each camera saw other "
                               "markers); nothing to triangulate");

  // world = s R p + t (Umeyama with scale; a proper rotation, det +1).
  Eigen::Matrix3Xd S(3, src.size()), D(3, dst.size());
  for (size_t i = 0; i < src.size(); ++i) {
    S.col(i) = src[i];
    D.col(i) = dst[i];
  }
  const Eigen::Matrix4d T = Eigen::umeyama(S, D, true);
  a.scale = T.block<3, 1>(0, 0).norm();
  a.rotation = T.block<3, 3>(0, 0) / a.scale;
  a.translation = T.block<3, 1>(0, 3);
  a.rig = transformRig(rig, a.scale, a.rotation, a.translation);

  double fit2 = 0, rep2 = 0;
  size_t rep_n = 0;
  for (auto& c : a.corners) {
    c.world = a.scale * a.rotation * c.triangulated + a.translation;
    const double e = (c.world - c.layout).norm();
    fit2 += e * e;
    a.fit_max = std::max(a.fit_max, e);
    // Pixel residual -> metres at the corner: px * depth / f, averaged over its cameras.
    double mm2 = 0;
    for (size_t j = 0; j < c.cameras.size(); ++j) {
      const CameraModel& cam = a.rig.cameras[a.rig.findCamera(c.cameras[j])];
      const double depth = (cam.cameraTWorld() * c.world).z();
      const double mm = c.residuals_px[j] * depth / cam.fx * 1e3;
      mm2 += mm * mm;
      rep2 += c.residuals_px[j] * c.residuals_px[j];
      ++rep_n;
    }
    c.rms_mm = std::sqrt(mm2 / c.cameras.size());
    if (c.rms_px > options.max_reprojection_px)
      a.warnings.push_back("marker id " + std::to_string(c.marker_id) + " corner " + std::to_string(c.corner) +
                           format(": reprojection error %.2f px RMS (a wrong detection, or a poor input rig)", c.rms_px));
  }
  a.fit_rms = std::sqrt(fit2 / a.corners.size());
  a.reprojection_rms_px = std::sqrt(rep2 / std::max<size_t>(rep_n, 1));
  if (a.fit_rms > options.max_fit_rms)
    a.warnings.push_back(format("the markers do not fit the layout: %.1f mm RMS, %.1f mm worst (limit %.1f mm): "
                                "wrong ids, positions or sizes in the layout?",
                                a.fit_rms * 1e3, a.fit_max * 1e3, options.max_fit_rms * 1e3));

  // Shape of each marker in world: square, of the layout's size, flat on the desk.
  for (size_t m = 0; m < a.markers_used.size(); ++m) {
    const AlignedCorner* c = &a.corners[4 * m];
    const int id = c->marker_id;
    const double size = layout.markers[layout.find(id)].size;
    double side[4], mean = 0;
    for (int k = 0; k < 4; ++k) mean += (side[k] = (c[(k + 1) % 4].world - c[k].world).norm()) / 4;
    const double d0 = (c[2].world - c[0].world).norm(), d1 = (c[3].world - c[1].world).norm();
    double worst = std::max(std::abs(d0 / (mean * std::sqrt(2.0)) - 1), std::abs(d1 / (mean * std::sqrt(2.0)) - 1));
    for (double s : side) worst = std::max(worst, std::abs(s / mean - 1));
    if (worst > options.square_tolerance)
      a.warnings.push_back("marker id " + std::to_string(id) +
                           format(" is not square: its sides and diagonals differ by up to %.1f %% (limit %.1f %%)",
                                  worst * 100, options.square_tolerance * 100));
    if (a.markers_used.size() > 1 && std::abs(mean / size - 1) > options.square_tolerance)
      a.warnings.push_back("marker id " + std::to_string(id) +
                           format(" measures %.1f mm, the layout says %.1f mm: is its size right?", mean * 1e3,
                                  size * 1e3));
  }
  double off_desk = 0;
  for (const auto& c : a.corners) off_desk = std::max(off_desk, std::abs(c.world.z()));
  if (off_desk > options.planar_tolerance)
    a.warnings.push_back(format("the marker corners are up to %.1f mm off the desk plane (limit %.1f mm): "
                                "a bent sheet, or a wrong layout?", off_desk * 1e3, options.planar_tolerance * 1e3));

  for (size_t i = 0; i < rig.cameras.size(); ++i) {
    CameraPoseChange p;
    p.camera = rig.cameras[i].name;
    p.centre_before = rig.cameras[i].center();
    p.centre_after = a.rig.cameras[i].center();
    for (const auto& kv : means[i]) p.markers_seen += layout.find(kv.first) >= 0 ? 1 : 0;
    a.cameras.push_back(p);
    if (p.centre_after.z() < 0)
      a.warnings.push_back("camera " + p.camera + format(" is below the desk after the alignment (z = %.3f m): "
                                                         "the input rig sees the desk from underneath (mirrored?)",
                                                         p.centre_after.z()));
  }
  return a;
}

}  // namespace tabletop_capture
