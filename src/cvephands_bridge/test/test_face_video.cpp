// The face video (face_video.h) on the simulated rig: the camera chosen looks at the user's
// face, the crop is centred on the face (skin-coloured in the middle, against the black pad /
// background around it), and the face message round-trips and rejects malformed input.
#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "cvephands_bridge/video/face_video.h"
#include "tabletop_sim/simulated_rig.h"

namespace cvephands {
namespace {

using tabletop_sim::SimFrame;
using tabletop_sim::SimOptions;
using tabletop_sim::SimulatedRig;

// Skin as the renderer draws it under the rig's lights: red-dominant, warm.
bool skinLike(const cv::Vec3b& p) { return p[0] > 90 && p[0] > p[1] && p[1] > p[2] && p[0] - p[2] > 25; }

double skinFraction(const cv::Mat& rgb, const cv::Rect& r) {
  int n = 0, s = 0;
  for (int y = r.y; y < r.y + r.height; ++y)
    for (int x = r.x; x < r.x + r.width; ++x, ++n) s += skinLike(rgb.at<cv::Vec3b>(y, x));
  return n ? double(s) / n : 0.0;
}

struct Scene {
  SimulatedRig rig;
  SimFrame frame;
  Scene() : rig([] {
      SimOptions o;
      o.script = "head_turn";
      return o;
    }()) {
    frame = rig.render(rig.options().empty_frames + 5);  // the person is seated, facing forward
  }
};

Scene& scene() {
  static Scene s;
  return s;
}

TEST(FaceVideo, PicksACameraInFrontOfTheUserAndCropsTheFace) {
  Scene& s = scene();
  const auto& cams = s.rig.rig().cameras;
  const Eigen::Vector3d head = s.frame.truth.head;
  ASSERT_TRUE(head.allFinite());
  const int c = pickFaceCamera(cams, head);
  ASSERT_GE(c, 0);
  // It looks against the user's viewing direction (+y): its axis has a clearly negative y.
  const Eigen::Vector3d axis = cams[c].world_T_camera.linear().col(2);
  std::printf("[ figures  ] face camera %s, axis (%.2f, %.2f, %.2f)\n", cams[c].name.c_str(),
              axis.x(), axis.y(), axis.z());
  EXPECT_LT(axis.y(), -0.5);
  FaceVideoOptions o;
  cv::Mat face;
  ASSERT_TRUE(cropFace(s.frame.images[c], cams[c], head, o, &face));
  ASSERT_EQ(face.cols, o.size);
  ASSERT_EQ(face.rows, o.size);
  // A 28 cm square around the head centre: the face fills the middle (skin), the corners are
  // hair, background or padding.
  const int q = o.size / 4;
  const double centre = skinFraction(face, cv::Rect(q + q / 2, q + q / 2, q, q));
  const double corners = 0.25 * (skinFraction(face, cv::Rect(0, 0, q / 2, q / 2)) +
                                 skinFraction(face, cv::Rect(o.size - q / 2, 0, q / 2, q / 2)) +
                                 skinFraction(face, cv::Rect(0, o.size - q / 2, q / 2, q / 2)) +
                                 skinFraction(face, cv::Rect(o.size - q / 2, o.size - q / 2, q / 2, q / 2)));
  std::printf("[ figures  ] skin in the centre %.2f, in the corners %.2f\n", centre, corners);
  EXPECT_GT(centre, 0.5);
  EXPECT_LT(corners, 0.2);
}

TEST(FaceVideo, NoCameraOrCropWithoutAHead) {
  Scene& s = scene();
  const auto& cams = s.rig.rig().cameras;
  const Eigen::Vector3d nan = Eigen::Vector3d::Constant(std::nan(""));
  EXPECT_EQ(pickFaceCamera(cams, nan), -1);
  EXPECT_EQ(pickFaceCamera(cams, Eigen::Vector3d(0, 0, 50)), -1);  // above every camera's view
  cv::Mat face;
  EXPECT_FALSE(cropFace(s.frame.images[0], cams[0], nan, FaceVideoOptions(), &face));
  // Behind the camera.
  const Eigen::Vector3d behind = cams[0].world_T_camera * Eigen::Vector3d(0, 0, -1);
  EXPECT_FALSE(cropFace(s.frame.images[0], cams[0], behind, FaceVideoOptions(), &face));
  EXPECT_FALSE(cropFace(cv::Mat(), cams[0], s.frame.truth.head, FaceVideoOptions(), &face));
  EXPECT_TRUE(face.empty());
}

TEST(FaceVideo, MessageRoundTripsAndKeepsThePicture) {
  cv::Mat face(96, 128, CV_8UC3);
  cv::randu(face, 0, 255);
  cv::GaussianBlur(face, face, cv::Size(9, 9), 3);  // JPEG-friendly content
  const std::vector<uint8_t> m = encodeFaceMessage(1796150000u, 123456789u, face, 90);
  EXPECT_TRUE(isFaceMessage(m.data(), m.size()));
  FaceMessage f;
  std::string why;
  ASSERT_TRUE(parseFaceMessage(m.data(), m.size(), &f, &why)) << why;
  EXPECT_EQ(f.stamp_sec, 1796150000u);
  EXPECT_EQ(f.stamp_nsec, 123456789u);
  EXPECT_EQ(f.width, 128);
  EXPECT_EQ(f.height, 96);
  cv::Mat bgr = cv::imdecode(std::vector<uint8_t>(f.jpeg, f.jpeg + f.jpeg_bytes), cv::IMREAD_COLOR);
  ASSERT_EQ(bgr.cols, 128);
  cv::Mat rgb;
  cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
  // JPEG at quality 90 on a smooth picture: a few grey levels off on average.
  EXPECT_LT(cv::norm(rgb, face, cv::NORM_L1) / (128.0 * 96 * 3), 4.0);
}

TEST(FaceVideo, MalformedMessagesAreRejectedWithAReason) {
  cv::Mat face(32, 32, CV_8UC3, cv::Scalar(200, 150, 120));
  const std::vector<uint8_t> good = encodeFaceMessage(1, 2, face, 80);
  auto rejects = [](std::vector<uint8_t> m, const std::string& expected) {
    FaceMessage f;
    std::string why;
    EXPECT_FALSE(parseFaceMessage(m.data(), m.size(), &f, &why)) << expected;
    EXPECT_NE(why.find(expected), std::string::npos) << "got: " << why;
  };
  auto with = [&good](size_t at, uint8_t v) {
    std::vector<uint8_t> m = good;
    m[at] = v;
    return m;
  };
  rejects(with(0, 'X'), "magic");
  rejects(std::vector<uint8_t>(good.begin(), good.begin() + 20), "truncated");
  rejects(with(4, 2), "version");
  rejects(with(5, 7), "format");
  rejects(with(6, 1), "reserved");
  rejects(with(15, 0xFF), "nanoseconds");
  rejects(with(16, 0), "size out of range");  // width 0 (32 -> 0)
  rejects(with(22, 0x10), "JPEG size");       // N far above the limit
  rejects(std::vector<uint8_t>(good.begin(), good.end() - 1), "size does not match");
  rejects(with(30, good[30] ^ 1), "checksum");
  FaceMessage f;
  std::string why;
  EXPECT_FALSE(parseFaceMessage(nullptr, 0, &f, &why));
  EXPECT_THROW(encodeFaceMessage(0, 1000000000u, face, 80), std::invalid_argument);
  EXPECT_THROW(encodeFaceMessage(0, 0, cv::Mat(), 80), std::invalid_argument);
}

}  // namespace
}  // namespace cvephands
