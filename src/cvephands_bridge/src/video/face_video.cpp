#include "cvephands_bridge/video/face_video.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "../stream/hand_stream_format.h"

namespace cvephands {
namespace {

constexpr uint8_t kMagic[4] = {'C', 'V', 'V', 'F'};
constexpr uint8_t kVersion = 1;
constexpr uint8_t kFormatJpeg = 1;

uint32_t getU32(const uint8_t* p) {
  return uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24;
}
uint16_t getU16(const uint8_t* p) { return uint16_t(p[0] | p[1] << 8); }
void putU16(uint8_t* p, uint16_t v) {
  p[0] = uint8_t(v);
  p[1] = uint8_t(v >> 8);
}

}  // namespace

void FaceVideoOptions::validate() const {
  if (size < 8 || size > kMaxFaceSide) throw std::invalid_argument("face video size must be in 8..1024");
  if (!(head_size > 0.0 && head_size < 2.0))
    throw std::invalid_argument("face video head_size must be in (0, 2) m");
  if (jpeg_quality < 1 || jpeg_quality > 100)
    throw std::invalid_argument("face video jpeg_quality must be in 1..100");
}

int pickFaceCamera(const std::vector<tabletop_capture::CameraModel>& cameras,
                   const Eigen::Vector3d& head, const Eigen::Vector3d& facing) {
  if (!head.allFinite() || !(facing.norm() > 0)) return -1;
  const Eigen::Vector3d f = facing.normalized();
  int best = -1;
  double best_score = -2.0;
  for (size_t i = 0; i < cameras.size(); ++i) {
    Eigen::Vector2d px;
    if (!cameras[i].projectWorld(head, &px) || !cameras[i].inImage(px)) continue;
    // The optical axis (camera z) in world; a camera the user faces looks along -facing.
    const Eigen::Vector3d axis = cameras[i].world_T_camera.linear().col(2);
    const double score = -axis.dot(f);
    if (score > best_score) best_score = score, best = static_cast<int>(i);
  }
  return best;
}

bool cropFace(const cv::Mat& rgb, const tabletop_capture::CameraModel& camera,
              const Eigen::Vector3d& head, const FaceVideoOptions& options, cv::Mat* face) {
  if (rgb.empty() || rgb.type() != CV_8UC3 || !head.allFinite()) return false;
  const Eigen::Vector3d pc = camera.cameraTWorld() * head;
  Eigen::Vector2d centre;
  if (!camera.projectCamera(pc, &centre)) return false;
  // Pinhole size of the square at the head's depth (distortion is mild over a head). A head
  // (estimate) closer to the camera than the square is wide is no face picture: refuse it
  // rather than allocate a huge canvas.
  const double half = 0.5 * options.head_size * camera.fx / pc.z();
  if (!(half >= 1.0 && half <= std::max(rgb.cols, rgb.rows))) return false;
  const cv::Rect want(static_cast<int>(std::lround(centre.x() - half)),
                      static_cast<int>(std::lround(centre.y() - half)),
                      static_cast<int>(std::lround(2 * half)), static_cast<int>(std::lround(2 * half)));
  const cv::Rect r = want & cv::Rect(0, 0, rgb.cols, rgb.rows);
  if (r.width < 2 || r.height < 2) return false;
  // Keep the head centred and the picture square: pad what lies outside the image with black.
  cv::Mat square(want.height, want.width, CV_8UC3, cv::Scalar(0, 0, 0));
  rgb(r).copyTo(square(cv::Rect(r.x - want.x, r.y - want.y, r.width, r.height)));
  cv::resize(square, *face, cv::Size(options.size, options.size), 0, 0, cv::INTER_AREA);
  return true;
}

std::vector<uint8_t> encodeFaceMessage(uint32_t stamp_sec, uint32_t stamp_nsec,
                                       const cv::Mat& face_rgb, int jpeg_quality) {
  if (face_rgb.empty() || face_rgb.type() != CV_8UC3 || face_rgb.cols > kMaxFaceSide ||
      face_rgb.rows > kMaxFaceSide)
    throw std::invalid_argument("encodeFaceMessage: the picture must be rgb8, 1..1024 px a side");
  if (stamp_nsec >= 1000000000u) throw std::invalid_argument("encodeFaceMessage: nsec >= 10^9");
  cv::Mat bgr;
  cv::cvtColor(face_rgb, bgr, cv::COLOR_RGB2BGR);  // imencode takes OpenCV's channel order
  std::vector<uint8_t> jpeg;
  cv::imencode(".jpg", bgr, jpeg, {cv::IMWRITE_JPEG_QUALITY, std::clamp(jpeg_quality, 1, 100)});
  if (jpeg.empty() || jpeg.size() > kMaxFaceJpegBytes)
    throw std::runtime_error("encodeFaceMessage: JPEG encoding failed or too large");
  std::vector<uint8_t> m(kFaceHeaderSize + jpeg.size() + 4, 0);
  std::memcpy(m.data(), kMagic, 4);
  m[4] = kVersion;
  m[5] = kFormatJpeg;
  wire::putU32(&m[8], stamp_sec);
  wire::putU32(&m[12], stamp_nsec);
  putU16(&m[16], uint16_t(face_rgb.cols));
  putU16(&m[18], uint16_t(face_rgb.rows));
  wire::putU32(&m[20], uint32_t(jpeg.size()));
  std::memcpy(&m[kFaceHeaderSize], jpeg.data(), jpeg.size());
  wire::putU32(&m[kFaceHeaderSize + jpeg.size()], wire::crc32(m.data(), kFaceHeaderSize + jpeg.size()));
  return m;
}

bool isFaceMessage(const uint8_t* data, size_t size) {
  return data && size >= 4 && std::memcmp(data, kMagic, 4) == 0;
}

bool parseFaceMessage(const uint8_t* data, size_t size, FaceMessage* out, std::string* reason) {
  auto fail = [reason](const std::string& why) {
    if (reason) *reason = why;
    return false;
  };
  if (!isFaceMessage(data, size)) return fail("not a face message (magic)");
  if (size < kFaceHeaderSize + 4) return fail("truncated header");
  if (data[4] != kVersion) return fail("unsupported version " + std::to_string(data[4]));
  if (data[5] != kFormatJpeg) return fail("unsupported format " + std::to_string(data[5]));
  if (getU16(data + 6) != 0) return fail("reserved field not 0");
  const uint32_t nsec = getU32(data + 12);
  if (nsec >= 1000000000u) return fail("nanoseconds >= 10^9");
  const int w = getU16(data + 16), h = getU16(data + 18);
  if (w < 1 || h < 1 || w > kMaxFaceSide || h > kMaxFaceSide) return fail("picture size out of range");
  const uint32_t n = getU32(data + 20);
  if (n < 1 || n > kMaxFaceJpegBytes) return fail("JPEG size out of range");
  if (size != kFaceHeaderSize + n + 4) return fail("size does not match the JPEG size");
  if (getU32(data + kFaceHeaderSize + n) != wire::crc32(data, kFaceHeaderSize + n))
    return fail("checksum mismatch");
  out->stamp_sec = getU32(data + 8);
  out->stamp_nsec = nsec;
  out->width = w;
  out->height = h;
  out->jpeg = data + kFaceHeaderSize;
  out->jpeg_bytes = n;
  return true;
}

}  // namespace cvephands
