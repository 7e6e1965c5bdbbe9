// FrameSource without hardware: an image sequence written here plays at its fps, loops or
// ends, fails when its files vanish and opens again when they are back; a missing V4L2 device
// is refused naming why.
#include <gtest/gtest.h>

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "tabletop_capture/capture_stats.h"
#include "tabletop_capture/file_frame_source.h"
#include "tabletop_capture/frame_source.h"

using namespace tabletop_capture;

namespace {

// A temp dir with n grey 64x48 PNGs img_0000.png.. whose pixel (0,0) is 10 * index.
std::string writeSequence(int n) {
  char tmpl[] = "/tmp/test_frame_source_XXXXXX";
  const std::string dir = ::mkdtemp(tmpl);
  for (int i = 0; i < n; ++i) {
    cv::Mat m(48, 64, CV_8UC1, cv::Scalar(i * 10));
    char name[64];
    std::snprintf(name, sizeof(name), "/img_%04d.png", i);
    EXPECT_TRUE(cv::imwrite(dir + name, m));
  }
  return dir;
}

FrameSourceSettings fileSettings(const std::string& dir, bool loop) {
  FrameSourceSettings s;
  s.device = "file:" + dir + "/img_%04d.png";
  s.width = 64;
  s.height = 48;
  s.fps = 25.0;
  s.raw = true;
  s.loop = loop;
  return s;
}

}  // namespace

TEST(FrameSource, ImageSequencePlaysAtItsFpsAndLoops) {
  const std::string dir = writeSequence(5);
  auto src = makeFrameSource(fileSettings(dir, true));
  std::string why;
  ASSERT_TRUE(src->open(&why)) << why;
  EXPECT_NE(src->describe().find("image sequence"), std::string::npos);
  EXPECT_TRUE(src->differences().empty()) << src->differences().front();
  CaptureStats stats(25.0);
  double last = -1;
  for (int i = 0; i < 15; ++i) {
    CapturedFrame f;
    ASSERT_EQ(src->read(&f, &why), ReadResult::kFrame) << "frame " << i << ": " << why;
    ASSERT_EQ(f.image.type(), CV_8UC1);
    ASSERT_EQ(f.image.size(), cv::Size(64, 48));
    EXPECT_EQ(f.image.at<uint8_t>(0, 0), (i % 5) * 10) << "frame " << i;
    EXPECT_GT(f.stamp, last);
    last = f.stamp;
    stats.add(f.stamp);
  }
  // Generous: only "within 20 % of the file's fps" (the machine may be busy).
  EXPECT_NEAR(stats.rate(), 25.0, 5.0);
  std::printf("image sequence: %.2f Hz, jitter %.2f ms\n", stats.rate(), stats.jitterMs());
  std::filesystem::remove_all(dir);
}

TEST(FrameSource, WithoutLoopTheSequenceEnds) {
  const std::string dir = writeSequence(3);
  auto src = makeFrameSource(fileSettings(dir, false));
  std::string why;
  ASSERT_TRUE(src->open(&why)) << why;
  CapturedFrame f;
  for (int i = 0; i < 3; ++i) ASSERT_EQ(src->read(&f, &why), ReadResult::kFrame) << why;
  EXPECT_EQ(src->read(&f, &why), ReadResult::kEnd);
  std::filesystem::remove_all(dir);
}

TEST(FrameSource, VanishedFilesFailAndComeBack) {
  const std::string dir = writeSequence(3);
  FrameSourceSettings s = fileSettings(dir, true);
  s.width = 640;  // differs from the files: reported
  auto src = makeFrameSource(s);
  std::string why;
  ASSERT_TRUE(src->open(&why)) << why;
  ASSERT_EQ(src->differences().size(), 1u);
  EXPECT_NE(src->differences()[0].find("width: asked 640, file gives 64"), std::string::npos);
  CapturedFrame f;
  ASSERT_EQ(src->read(&f, &why), ReadResult::kFrame) << why;
  const std::string away = dir + "_away";
  ASSERT_EQ(std::rename(dir.c_str(), away.c_str()), 0);
  ReadResult r = ReadResult::kFrame;
  for (int i = 0; i < 5 && r == ReadResult::kFrame; ++i) r = src->read(&f, &why);
  EXPECT_EQ(r, ReadResult::kFailed);
  EXPECT_NE(why.find("file 2 of 3 is missing"), std::string::npos) << why;
  src->close();
  EXPECT_FALSE(src->open(&why));
  EXPECT_NE(why.find("no file matches"), std::string::npos) << why;
  ASSERT_EQ(std::rename(away.c_str(), dir.c_str()), 0);
  ASSERT_TRUE(src->open(&why)) << why;
  EXPECT_EQ(src->read(&f, &why), ReadResult::kFrame) << why;
  std::filesystem::remove_all(dir);
}

// A video file (FFmpeg) plays at the configured fps and loops; renamed, it fails at the next
// start-over and is found again once it is back.
TEST(FrameSource, VideoFileLoopsAndFailsWhenRenamed) {
  char tmpl[] = "/tmp/test_frame_source_XXXXXX";
  const std::string dir = ::mkdtemp(tmpl);
  const std::string video = dir + "/cam.avi";
  {
    cv::VideoWriter w(video, cv::CAP_FFMPEG, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 10.0, cv::Size(64, 48));
    if (!w.isOpened()) GTEST_SKIP() << "OpenCV's FFmpeg backend cannot write MJPG here";
    for (int i = 0; i < 5; ++i) w.write(cv::Mat(48, 64, CV_8UC3, cv::Scalar(40 * i, 40 * i, 40 * i)));
  }
  FrameSourceSettings s;
  s.device = "file:" + video;
  s.width = 64;
  s.height = 48;
  s.fps = 25.0;
  auto src = makeFrameSource(s);
  std::string why;
  ASSERT_TRUE(src->open(&why)) << why;
  EXPECT_NE(src->describe().find("video file"), std::string::npos);
  // The file says 10 fps; it is played at 25: reported as a difference.
  ASSERT_FALSE(src->differences().empty());
  EXPECT_NE(src->differences()[0].find("fps: the file says 10"), std::string::npos) << src->differences()[0];
  CaptureStats stats(25.0);
  for (int i = 0; i < 12; ++i) {
    CapturedFrame f;
    ASSERT_EQ(src->read(&f, &why), ReadResult::kFrame) << "frame " << i << ": " << why;
    ASSERT_EQ(f.image.type(), CV_8UC3);
    EXPECT_NEAR(f.image.at<cv::Vec3b>(10, 10)[0], 40 * (i % 5), 8) << "frame " << i;  // MJPG is lossy
    stats.add(f.stamp);
  }
  EXPECT_NEAR(stats.rate(), 25.0, 5.0);
  const std::string away = video + ".away";
  ASSERT_EQ(std::rename(video.c_str(), away.c_str()), 0);
  ReadResult r = ReadResult::kFrame;
  for (int i = 0; i < 6 && r == ReadResult::kFrame; ++i) {
    CapturedFrame f;
    r = src->read(&f, &why);
  }
  EXPECT_EQ(r, ReadResult::kFailed);
  EXPECT_NE(why.find("no such"), std::string::npos) << why;
  ASSERT_EQ(std::rename(away.c_str(), video.c_str()), 0);
  src->close();
  ASSERT_TRUE(src->open(&why)) << why;
  CapturedFrame f;
  EXPECT_EQ(src->read(&f, &why), ReadResult::kFrame) << why;
  std::filesystem::remove_all(dir);
}

TEST(FrameSource, MissingDevicesAndBadSettings) {
  FrameSourceSettings s;
  s.device = "/dev/video_does_not_exist";
  auto src = makeFrameSource(s);
  EXPECT_NE(src->describe().find("V4L2"), std::string::npos);
  std::string why;
  EXPECT_FALSE(src->open(&why));
  EXPECT_NE(why.find("no such device node"), std::string::npos) << why;
  s.device = "file:/nonexistent/video.avi";
  auto file = makeFrameSource(s);
  EXPECT_FALSE(file->open(&why));
  EXPECT_NE(why.find("no such"), std::string::npos) << why;
  s.device = "";
  EXPECT_THROW(makeFrameSource(s), std::invalid_argument);
  s.device = "file:";
  EXPECT_THROW(makeFrameSource(s), std::invalid_argument);
  s.device = "/dev/video0";
  s.fps = 0;
  EXPECT_THROW(makeFrameSource(s), std::invalid_argument);
  EXPECT_EQ(fourccToString(cv::VideoWriter::fourcc('Y', 'U', 'Y', 'V')), "YUYV");
}
