#include "tabletop_capture/ros/published_frames.h"

#include <algorithm>
#include <deque>
#include <mutex>

namespace tabletop_capture {
namespace {
// Lives in the shared tabletop_capture_ros library, so the synchroniser plugin and an
// in-process test see the same registry.
std::mutex g_mutex;
std::deque<const void*> g_published;
}  // namespace

void notePublishedFrame(const void* message) {
  std::lock_guard<std::mutex> lock(g_mutex);
  g_published.push_back(message);
  while (g_published.size() > 64) g_published.pop_front();
}

bool wasPublishedFrame(const void* message) {
  std::lock_guard<std::mutex> lock(g_mutex);
  return std::find(g_published.begin(), g_published.end(), message) != g_published.end();
}

}  // namespace tabletop_capture
