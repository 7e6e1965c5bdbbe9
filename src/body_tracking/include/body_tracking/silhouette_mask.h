// Analytic silhouettes of the quadric body model in one camera (thesis 3.3.4-3.3.6). A pixel
// belongs to a part's silhouette when its viewing ray X(l) = c + l d meets the truncated quadric
// in front of the camera. Along the ray the quadric reads a l^2 + 2 h l + k <= 0 (with Q in the
// camera frame = [A b; b^T k]: a = d^T A d, h = d^T b), which has real roots where
// h^2 - a k = d^T (b b^T - k A) d >= 0: C = b b^T - k A is the image conic of the quadric's
// contour generator, the conic projection of thesis eq. 3.16. Instead of drawing the conic's
// arches or lines between their end points (3.3.6), every pixel of the part's projected box is
// tested: the conic first, then the root interval against the clipping planes' slab and l > 0.
// The pixel rays are undistorted once, so the silhouettes are exact under lens distortion.
// The drawing methods keep no state: one projector may serve several threads.
#pragma once

#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "body_tracking/body_parts.h"
#include "body_tracking/truncated_quadric.h"
#include "tabletop_capture/camera_model.h"

namespace body_tracking {

class SilhouetteProjector {
 public:
  // Precomputes, per pixel, the undistorted viewing ray (cameras are static), so lens
  // distortion is exact and each pixel test is a few dot products.
  explicit SilhouetteProjector(const tabletop_capture::CameraModel& camera);
  const tabletop_capture::CameraModel& camera() const { return camera_; }

  // Sets to 255 the pixels whose ray (through the pixel centre; integer pixel coordinates are
  // centres, as in CameraModel) hits `part` in front of the camera. Draws over *mask without
  // clearing it, so successive calls build a union; *mask is (re)allocated zeroed first if it
  // is not CV_8UC1 of the camera's size.
  void drawPart(const TruncatedQuadric& part, cv::Mat* mask) const;
  // Clears *mask (allocating as above), draws the union of all parts, then dilates it by
  // margin_px: a disc (elliptic) kernel of that radius, so pixels within margin_px of a drawn
  // one are added; margin_px < 1 adds nothing.
  void draw(const BodyParts& parts, double margin_px, cv::Mat* mask) const;

  // The pixels drawPart may set for `part` (it draws nothing outside): the part's world box
  // projected, padded by 2 px and clipped to the image; the whole image if the box straddles
  // the camera plane, empty if it lies behind it or off the image.
  cv::Rect projectedBox(const TruncatedQuadric& part) const;

 private:
  void drawInBox(const TruncatedQuadric& part, const cv::Rect& box, cv::Mat* mask) const;

  tabletop_capture::CameraModel camera_;
  Eigen::Isometry3d camera_T_world_;
  // Undistorted normalised coordinates (x, y) of each pixel's ray (x, y, 1), row-major.
  std::vector<float> rays_;
};

}  // namespace body_tracking
