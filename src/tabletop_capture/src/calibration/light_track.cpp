#include "tabletop_capture/calibration/light_track.h"

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <sstream>

namespace tabletop_capture {

int LightFrame::seenBy() const {
  return static_cast<int>(std::count_if(pixels.begin(), pixels.end(), [](const auto& p) { return p.has_value(); }));
}

void LightTrack::add(int frame, int camera, const Eigen::Vector2d& pixel) {
  if (camera < 0 || camera >= numCameras())
    throw std::out_of_range("LightTrack::add: camera " + std::to_string(camera) + " of " +
                            std::to_string(numCameras()));
  auto it = std::lower_bound(frames.begin(), frames.end(), frame,
                             [](const LightFrame& f, int n) { return f.frame < n; });
  if (it == frames.end() || it->frame != frame) {
    LightFrame f;
    f.frame = frame;
    f.pixels.resize(cameras.size());
    it = frames.insert(it, f);
  }
  it->pixels[camera] = pixel;
}

std::vector<int> LightTrack::detectionsPerCamera() const {
  std::vector<int> n(cameras.size(), 0);
  for (const auto& f : frames)
    for (size_t c = 0; c < f.pixels.size(); ++c) n[c] += f.pixels[c].has_value();
  return n;
}

int LightTrack::framesSeenBy(int min_cameras) const {
  return static_cast<int>(std::count_if(frames.begin(), frames.end(),
                                        [&](const LightFrame& f) { return f.seenBy() >= min_cameras; }));
}

std::string lightTrackToCsv(const LightTrack& track) {
  std::string out = "# point-light detections: frame,camera,u,v (pixels, centres at integers)\n";
  char line[160];
  for (const auto& f : track.frames)
    for (size_t c = 0; c < f.pixels.size(); ++c)
      if (f.pixels[c]) {
        std::snprintf(line, sizeof line, "%d,%s,%.6f,%.6f\n", f.frame, track.cameras[c].c_str(),
                      f.pixels[c]->x(), f.pixels[c]->y());
        out += line;
      }
  return out;
}

LightTrack parseLightTrackCsv(const std::string& text, const std::vector<std::string>& camera_names,
                              const std::string& source) {
  LightTrack track(camera_names);
  std::istringstream in(text);
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    if (line.empty() || line[0] == '#') continue;
    std::replace(line.begin(), line.end(), ',', ' ');
    std::istringstream fields(line);
    int frame = 0;
    std::string camera, rest;
    double u = 0, v = 0;
    const auto fail = [&](const std::string& why) {
      throw LightTrackError(source + ":" + std::to_string(number) + ": " + why);
    };
    if (!(fields >> frame >> camera >> u >> v) || (fields >> rest))
      fail("expected 'frame,camera,u,v'");
    const auto it = std::find(camera_names.begin(), camera_names.end(), camera);
    if (it == camera_names.end()) fail("camera '" + camera + "' is not in the rig");
    track.add(frame, static_cast<int>(it - camera_names.begin()), Eigen::Vector2d(u, v));
  }
  return track;
}

void saveLightTrackCsv(const LightTrack& track, const std::string& path) {
  std::ofstream out(path);
  out << lightTrackToCsv(track);
  if (!out) throw LightTrackError(path + ": cannot write");
}

LightTrack loadLightTrackCsv(const std::string& path, const std::vector<std::string>& camera_names) {
  std::ifstream in(path);
  if (!in) throw LightTrackError(path + ": cannot read");
  std::stringstream text;
  text << in.rdbuf();
  return parseLightTrackCsv(text.str(), camera_names, path);
}

}  // namespace tabletop_capture
