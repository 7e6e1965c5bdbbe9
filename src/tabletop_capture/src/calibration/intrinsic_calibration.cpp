#include "tabletop_capture/calibration/intrinsic_calibration.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace tabletop_capture {

bool detectCheckerboard(const cv::Mat& image, const CheckerboardSpec& board,
                        std::vector<Eigen::Vector2d>* corners) {
  board.validate();
  cv::Mat gray;
  if (image.channels() == 3)
    cv::cvtColor(image, gray, cv::COLOR_RGB2GRAY);  // (channel order does not matter for corners)
  else
    gray = image;
  std::vector<cv::Point2f> found;
  const cv::Size pattern(board.cols, board.rows);
  // The sector-based detector (Duda & Frese 2018) finds strongly tilted boards with small
  // squares that the classic quad detector misses (13 of 40 simulated views); its own corner
  // refinement (CALIB_CB_ACCURACY) left a scale bias of 0.7 % in the focal length there, so the
  // corners are refined by cornerSubPix as the classic detector's are (0.085 px RMS against the
  // projected truth, test_calibration_sim).
  if (!cv::findChessboardCornersSB(gray, pattern, found,
                                   cv::CALIB_CB_NORMALIZE_IMAGE | cv::CALIB_CB_EXHAUSTIVE) &&
      !cv::findChessboardCorners(gray, pattern, found,
                                 cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE))
    return false;
  // A small window: at 320x240 a square may be only ~10 px wide.
  cv::cornerSubPix(gray, found, cv::Size(3, 3), cv::Size(-1, -1),
                   cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 50, 1e-4));
  corners->clear();
  for (const auto& p : found) corners->emplace_back(p.x, p.y);
  return true;
}

IntrinsicCalibration calibrateIntrinsics(const std::vector<std::vector<Eigen::Vector2d>>& views,
                                         const CheckerboardSpec& board, int width, int height,
                                         const IntrinsicCalibrationOptions& options) {
  board.validate();
  if (views.size() < 3)
    throw std::invalid_argument("intrinsic calibration: need at least 3 views of the board, got " +
                                std::to_string(views.size()));
  if (width < 1 || height < 1) throw std::invalid_argument("intrinsic calibration: bad image size");
  std::vector<cv::Point3f> object;
  for (const auto& p : board.boardPoints()) object.emplace_back(p.x(), p.y(), p.z());
  std::vector<std::vector<cv::Point3f>> object_points;
  std::vector<std::vector<cv::Point2f>> image_points;
  const int grid = std::max(1, options.coverage_grid);
  std::vector<bool> cell(grid * grid, false);
  for (size_t v = 0; v < views.size(); ++v) {
    if (static_cast<int>(views[v].size()) != board.corners())
      throw std::invalid_argument("intrinsic calibration: view " + std::to_string(v) + " has " +
                                  std::to_string(views[v].size()) + " corners, the board " +
                                  std::to_string(board.corners()));
    std::vector<cv::Point2f> pts;
    for (const auto& c : views[v]) {
      pts.emplace_back(c.x(), c.y());
      const int gx = std::clamp(static_cast<int>(c.x() * grid / width), 0, grid - 1);
      const int gy = std::clamp(static_cast<int>(c.y() * grid / height), 0, grid - 1);
      cell[gy * grid + gx] = true;
    }
    image_points.push_back(pts);
    object_points.push_back(object);
  }
  int flags = 0;
  if (!options.estimate_k3) flags |= cv::CALIB_FIX_K3;
  if (!options.tangential) flags |= cv::CALIB_ZERO_TANGENT_DIST;
  cv::Mat K, D;
  std::vector<cv::Mat> rvecs, tvecs;
  IntrinsicCalibration out;
  out.rms_px = cv::calibrateCamera(object_points, image_points, cv::Size(width, height), K, D, rvecs,
                                   tvecs, flags,
                                   cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 30, 1e-10));
  out.views = static_cast<int>(views.size());
  CameraModel& cam = out.camera;
  cam.width = width;
  cam.height = height;
  cam.fx = K.at<double>(0, 0);
  cam.fy = K.at<double>(1, 1);
  cam.cx = K.at<double>(0, 2);
  cam.cy = K.at<double>(1, 2);
  for (int i = 0; i < 5 && i < D.cols * D.rows; ++i) cam.distortion[i] = D.at<double>(i);
  for (size_t v = 0; v < views.size(); ++v) {
    std::vector<cv::Point2f> projected;
    cv::projectPoints(object, rvecs[v], tvecs[v], K, D, projected);
    double sum = 0;
    for (size_t k = 0; k < projected.size(); ++k) {
      const double dx = projected[k].x - image_points[v][k].x, dy = projected[k].y - image_points[v][k].y;
      sum += dx * dx + dy * dy;
    }
    out.view_rms_px.push_back(std::sqrt(sum / projected.size()));
  }
  out.coverage = std::count(cell.begin(), cell.end(), true) / double(cell.size());
  char text[200];
  if (views.size() < 10) {
    std::snprintf(text, sizeof text, "only %zu views: 10-20 at varied tilts give a stable result",
                  views.size());
    out.warnings.push_back(text);
  }
  if (out.coverage < 0.75) {
    std::snprintf(text, sizeof text, "the corners covered %.0f %% of the image (%dx%d cells): move "
                  "the board into the corners and edges too", out.coverage * 100, grid, grid);
    out.warnings.push_back(text);
  }
  // Against the median view (one bad view pulls the overall RMS up with it).
  std::vector<double> sorted = out.view_rms_px;
  std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
  const double median = sorted[sorted.size() / 2];
  for (size_t v = 0; v < out.view_rms_px.size(); ++v)
    if (out.view_rms_px[v] > 3 * median && out.view_rms_px[v] > 0.5) {
      std::snprintf(text, sizeof text, "view %zu reprojects at %.2f px (median view %.2f px): a "
                    "blurred or misdetected view? leave it out", v, out.view_rms_px[v], median);
      out.warnings.push_back(text);
    }
  return out;
}

ImageCalibration calibrateIntrinsicsFromImages(
    const std::vector<std::string>& files, const CheckerboardSpec& board, int max_views,
    const IntrinsicCalibrationOptions& options,
    const std::function<void(int, const std::string&, bool)>& progress) {
  board.validate();
  ImageCalibration out;
  std::vector<std::vector<Eigen::Vector2d>> views;
  std::vector<std::string> view_files;
  cv::Size size;
  for (size_t i = 0; i < files.size(); ++i) {
    const cv::Mat image = cv::imread(files[i], cv::IMREAD_GRAYSCALE);
    if (image.empty()) throw std::runtime_error(files[i] + ": cannot read the image");
    if (size.area() == 0) size = image.size();
    if (image.size() != size)
      throw std::runtime_error(files[i] + ": " + std::to_string(image.cols) + "x" +
                               std::to_string(image.rows) + ", the first image was " +
                               std::to_string(size.width) + "x" + std::to_string(size.height) +
                               " (one camera per run)");
    std::vector<Eigen::Vector2d> corners;
    const bool found = detectCheckerboard(image, board, &corners);
    if (found) {
      views.push_back(corners);
      view_files.push_back(files[i]);
    }
    ++out.images;
    if (progress) progress(static_cast<int>(i), files[i], found);
  }
  out.boards_found = static_cast<int>(views.size());
  if (views.size() < 3)
    throw std::runtime_error("the board (" + std::to_string(board.cols) + "x" +
                             std::to_string(board.rows) + " inner corners) was found in " +
                             std::to_string(views.size()) + " of " + std::to_string(files.size()) +
                             " images; at least 3 are needed");
  std::vector<std::vector<Eigen::Vector2d>> kept;
  const size_t n = views.size(), keep = std::min(n, static_cast<size_t>(std::max(3, max_views)));
  for (size_t k = 0; k < keep; ++k) {
    const size_t i = k * n / keep;  // evenly spread over the sequence
    kept.push_back(views[i]);
    out.used.push_back(view_files[i]);
  }
  out.calibration = calibrateIntrinsics(kept, board, size.width, size.height, options);
  return out;
}

}  // namespace tabletop_capture
