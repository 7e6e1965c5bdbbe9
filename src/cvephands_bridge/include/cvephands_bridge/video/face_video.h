// The face video of a participant (thesis 7.5: the user study showed each remote user's face on
// a video plane beside their 3-D hands): a small JPEG crop around the tracked head from the
// camera that looks most directly at the user's face, sent through the room like the hands.
//
// Wire format ("face message"), version 1, all fields little endian, offsets in bytes:
//   0  u8[4] magic "CVVF"
//   4  u8    version (1)
//   5  u8    format: 1 = JPEG (baseline, 3 channels)
//   6  u16   reserved, 0
//   8  u32   stamp seconds      (the frame set's capture stamp)
//  12  u32   stamp nanoseconds  (< 10^9)
//  16  u16   width, 18 u16 height of the picture (1..1024 each)
//  20  u32   N: bytes of the JPEG data (1..kMaxFaceJpegBytes)
//  24  u8[N] the JPEG file
//  24+N u32  CRC-32 (zlib / PNG polynomial) of bytes [0, 24 + N)
// A client tells it from a hand message (magic "CVHS", hand_stream_codec.h) by the magic.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "tabletop_capture/camera_model.h"

namespace cvephands {

constexpr size_t kFaceHeaderSize = 24;
constexpr size_t kMaxFaceJpegBytes = 512 * 1024;
constexpr int kMaxFaceSide = 1024;

struct FaceVideoOptions {
  int size = 128;           // side of the square picture (pixels)
  double head_size = 0.28;  // m: side of the square around the head centre that is cropped
  int jpeg_quality = 80;    // 1..100 (80: ~4-6 kB at 128 px)
  void validate() const;    // throws std::invalid_argument naming the field
};

// The camera that sees the face best: among the cameras that see the head centre in their
// image, the one whose optical axis points most nearly against `facing` (the direction the
// user looks: world +y, towards the screen). -1 if none sees it.
int pickFaceCamera(const std::vector<tabletop_capture::CameraModel>& cameras,
                   const Eigen::Vector3d& head, const Eigen::Vector3d& facing = Eigen::Vector3d::UnitY());

// The square around the head (head_size at the head's distance), clipped to the image,
// resized to size x size. rgb: the camera's rgb8 image (CV_8UC3). False (face untouched) when
// the head is not in front of the camera, the square misses the image, or the square would be
// under 2 px or wider than the image (a head at the lens).
bool cropFace(const cv::Mat& rgb, const tabletop_capture::CameraModel& camera,
              const Eigen::Vector3d& head, const FaceVideoOptions& options, cv::Mat* face);

// A face message from an rgb8 picture (JPEG-encoded here).
std::vector<uint8_t> encodeFaceMessage(uint32_t stamp_sec, uint32_t stamp_nsec,
                                       const cv::Mat& face_rgb, int jpeg_quality);

struct FaceMessage {
  uint32_t stamp_sec = 0, stamp_nsec = 0;
  int width = 0, height = 0;
  const uint8_t* jpeg = nullptr;  // into the parsed buffer
  size_t jpeg_bytes = 0;
};

// True if `data` starts with the face message magic (the rest unchecked).
bool isFaceMessage(const uint8_t* data, size_t size);
// Checks the whole layout and the checksum (not the JPEG itself); false with a reason.
bool parseFaceMessage(const uint8_t* data, size_t size, FaceMessage* out, std::string* reason);

}  // namespace cvephands
