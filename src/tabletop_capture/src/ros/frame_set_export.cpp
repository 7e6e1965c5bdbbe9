#include "tabletop_capture/ros/frame_set_export.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <stdexcept>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <ros/message_traits.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <tabletop_msgs/MultiViewFrame.h>

#include "tabletop_capture/image_conversion.h"

namespace fs = std::filesystem;

namespace tabletop_capture {
namespace {

std::string indexName(int index) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%05d", index);
  return buf;
}

std::string stampText(const ros::Time& t) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%u.%09u", t.sec, t.nsec);
  return buf;
}

// A camera name that is a plain folder name (no path separators, not "." or "..").
bool validFolderName(const std::string& name) {
  return !name.empty() && name != "." && name != ".." && name.find('/') == std::string::npos &&
         name.find('\0') == std::string::npos;
}

// "  /a  tabletop_msgs/X  (12 messages)" per topic of the bag.
std::string listTopics(rosbag::Bag& bag) {
  rosbag::View all(bag);
  std::map<std::string, std::pair<std::string, int>> topics;
  for (const rosbag::ConnectionInfo* c : all.getConnections()) topics[c->topic].first = c->datatype;
  for (const rosbag::MessageInstance& m : all) ++topics[m.getTopic()].second;
  if (topics.empty()) return "\n  (the bag holds no topic)";
  std::string s;
  for (const auto& t : topics)
    s += "\n  " + t.first + "  " + t.second.first + "  (" + std::to_string(t.second.second) +
         " messages)";
  return s;
}

}  // namespace

FrameSetExportResult exportFrameSets(const std::string& bag_path, const std::string& out_dir,
                                     const FrameSetExportOptions& options,
                                     const std::function<void(const std::string&)>& log) {
  if (options.every < 1) throw std::runtime_error("every must be >= 1");
  if (options.max_sets < 0) throw std::runtime_error("max_sets must be >= 0");
  const auto say = [&](const std::string& line) {
    if (log) log(line);
  };
  FrameSetExportResult result;
  const auto warn = [&](const std::string& w) {
    result.warnings.push_back(w);
    say("WARNING: " + w);
  };

  rosbag::Bag bag;
  try {
    bag.open(bag_path, rosbag::bagmode::Read);
  } catch (const std::exception& e) {
    throw std::runtime_error("cannot read bag '" + bag_path + "': " + e.what());
  }

  // The topic must be there with the message type (and definition) this build knows.
  const std::string type = ros::message_traits::DataType<tabletop_msgs::MultiViewFrame>::value();
  const std::string md5 = ros::message_traits::MD5Sum<tabletop_msgs::MultiViewFrame>::value();
  rosbag::View view(bag, rosbag::TopicQuery(options.topic));
  bool found = false;
  for (const rosbag::ConnectionInfo* c : view.getConnections()) {
    if (c->datatype != type)
      throw std::runtime_error(bag_path + ": topic " + options.topic + " is of type " + c->datatype +
                               ", not " + type + "; the bag's topics:" + listTopics(bag));
    if (c->md5sum != md5)
      throw std::runtime_error(bag_path + ": topic " + options.topic + " has another definition of " +
                               type + " (md5 " + c->md5sum + ", this build " + md5 +
                               "): recorded with an older version of tabletop_msgs?");
    found = true;
  }
  if (!found)
    throw std::runtime_error(bag_path + ": no topic " + options.topic + "; the bag's topics:" +
                             listTopics(bag) +
                             "\n(record the synchroniser's frame sets: rosbag record /tabletop/frames)");
  if (view.size() == 0)
    throw std::runtime_error(bag_path + ": no frame sets on " + options.topic);

  // The camera filter must name cameras of the sets (checked on the first set, before writing).
  const std::set<std::string> wanted(options.cameras.begin(), options.cameras.end());
  if (!wanted.empty()) {
    const auto first = view.begin()->instantiate<tabletop_msgs::MultiViewFrame>();
    if (first) {
      std::string names;
      for (const auto& n : first->camera_names) names += (names.empty() ? "" : ", ") + n;
      for (const auto& w : wanted)
        if (std::find(first->camera_names.begin(), first->camera_names.end(), w) ==
            first->camera_names.end())
          throw std::runtime_error("no camera '" + w + "' in the frame sets of " + options.topic +
                                   " (cameras: " + names + ")");
    }
  }

  std::error_code ec;
  fs::create_directories(out_dir, ec);
  if (ec || !fs::is_directory(out_dir))
    throw std::runtime_error("cannot create output folder '" + out_dir + "': " +
                             (ec ? ec.message() : std::string("not a folder")));
  const std::string csv_path = (fs::path(out_dir) / "stamps.csv").string();
  std::ofstream csv(csv_path);
  if (!csv) throw std::runtime_error("cannot write '" + csv_path + "' (output folder not writable?)");
  csv << "index,stamp,cameras\n";

  std::map<std::string, size_t> count_of;  // camera name -> index in result.cameras
  std::set<std::string> bad_names;
  int index = -1;
  for (const rosbag::MessageInstance& m : view) {
    if (options.max_sets > 0 && result.sets_written >= options.max_sets) break;
    const auto set = m.instantiate<tabletop_msgs::MultiViewFrame>();
    if (!set) continue;
    ++index;
    ++result.sets_read;
    if (index % options.every != 0) continue;
    ++result.sets_written;

    const size_t n = std::min(set->camera_names.size(), set->images.size());
    if (set->camera_names.size() != set->images.size())
      warn("set " + std::to_string(index) + ": " + std::to_string(set->camera_names.size()) +
           " camera names but " + std::to_string(set->images.size()) + " images; using the first " +
           std::to_string(n));
    std::string present;
    for (size_t i = 0; i < n; ++i) {
      const std::string& name = set->camera_names[i];
      if (!wanted.empty() && !wanted.count(name)) continue;
      if (!validFolderName(name)) {
        if (bad_names.insert(name).second)
          warn("camera name '" + name + "' is not a folder name; its images are left out");
        continue;
      }
      auto it = count_of.find(name);
      if (it == count_of.end()) {
        it = count_of.emplace(name, result.cameras.size()).first;
        result.cameras.push_back(CameraExportCount{name});
        const fs::path dir = fs::path(out_dir) / name;
        fs::create_directories(dir, ec);
        if (ec) throw std::runtime_error("cannot create '" + dir.string() + "': " + ec.message());
        int old = 0;
        for (const auto& e : fs::directory_iterator(dir, ec))
          if (e.path().extension() == ".png") ++old;
        if (old > 0)
          warn(dir.string() + " already holds " + std::to_string(old) +
               " PNG files from before; the calibration tools will read those too");
      }
      CameraExportCount& count = result.cameras[it->second];
      const sensor_msgs::Image& img = set->images[i];
      if (img.width == 0 || img.height == 0) {  // degraded set: this camera delivered nothing
        ++count.missing;
        continue;
      }
      RawImageView raw;
      raw.encoding = img.encoding;
      raw.width = static_cast<int>(img.width);
      raw.height = static_cast<int>(img.height);
      raw.step = img.step;
      raw.data = img.data.data();
      raw.size = img.data.size();
      const ImageConversionResult conv = convertToRgb8(raw, 0, 0, name);
      if (!conv.ok) {
        ++count.failed;
        ++result.conversion_failures;
        warn("set " + std::to_string(index) + ", camera " + name + ": " + conv.error +
             "; no file written");
        continue;
      }
      cv::Mat bgr;
      cv::cvtColor(conv.rgb, bgr, cv::COLOR_RGB2BGR);
      const std::string file = (fs::path(out_dir) / name / (indexName(index) + ".png")).string();
      bool written = false;
      try {
        written = cv::imwrite(file, bgr);
      } catch (const cv::Exception& e) {
        throw std::runtime_error("cannot write '" + file + "': " + e.what());
      }
      if (!written) throw std::runtime_error("cannot write '" + file + "'");
      ++count.written;
      present += (present.empty() ? "" : " ") + name;
    }
    csv << index << ',' << stampText(set->header.stamp) << ',' << present << '\n';
    if (!csv) throw std::runtime_error("cannot write '" + csv_path + "'");
    if (result.sets_written % 50 == 0)
      say(std::to_string(result.sets_written) + " sets written (" + std::to_string(result.sets_read) +
          " read)");
  }
  csv.close();
  if (!csv) throw std::runtime_error("cannot write '" + csv_path + "'");
  if (result.sets_read == 0)
    throw std::runtime_error(bag_path + ": no frame sets on " + options.topic);
  return result;
}

}  // namespace tabletop_capture
