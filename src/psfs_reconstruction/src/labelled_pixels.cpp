#include "psfs_reconstruction/labelled_pixels.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <numeric>
#include <random>
#include <stdexcept>

#include "psfs_reconstruction/color_space.h"

namespace psfs {
namespace {

// Splits on commas, semicolons and whitespace; returns false if a field is not an integer.
bool parseInts(const std::string& line, std::vector<long>* out) {
  out->clear();
  const char* p = line.c_str();
  while (*p) {
    while (*p == ',' || *p == ';' || *p == ' ' || *p == '\t' || *p == '\r') ++p;
    if (!*p) break;
    char* end = nullptr;
    const long v = std::strtol(p, &end, 10);
    if (end == p) return false;
    if (*end && *end != ',' && *end != ';' && *end != ' ' && *end != '\t' && *end != '\r')
      return false;
    out->push_back(v);
    p = end;
  }
  return true;
}

}  // namespace

std::size_t LabelledPixels::countSkin() const {
  return std::size_t(std::count(skin.begin(), skin.end(), std::uint8_t(1)));
}

void LabelledPixels::append(const LabelledPixels& other) {
  rgb.insert(rgb.end(), other.rgb.begin(), other.rgb.end());
  skin.insert(skin.end(), other.skin.begin(), other.skin.end());
}

LabelledPixels loadLabelledPixels(const std::string& path, ChannelOrder order, int skin_label) {
  std::ifstream f(path);
  if (!f) throw std::runtime_error("cannot open labelled pixel file '" + path + "'");
  LabelledPixels data;
  std::string line;
  std::vector<long> v;
  std::size_t line_no = 0;
  bool seen_data = false;
  while (std::getline(f, line)) {
    ++line_no;
    const auto hash = line.find('#');
    if (hash != std::string::npos) line.erase(hash);
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    if (!parseInts(line, &v)) {
      if (!seen_data) {  // header
        seen_data = true;
        continue;
      }
      throw std::runtime_error(path + ":" + std::to_string(line_no) + ": not numeric: '" + line +
                               "'");
    }
    seen_data = true;
    if (v.size() != 4)
      throw std::runtime_error(path + ":" + std::to_string(line_no) + ": expected 4 columns (" +
                               (order == ChannelOrder::BGR ? "B,G,R,label" : "R,G,B,label") +
                               "), got " + std::to_string(v.size()));
    for (int i = 0; i < 3; ++i)
      if (v[i] < 0 || v[i] > 255)
        throw std::runtime_error(path + ":" + std::to_string(line_no) +
                                 ": colour value outside 0..255");
    std::array<std::uint8_t, 3> rgb;
    if (order == ChannelOrder::BGR)
      rgb = {std::uint8_t(v[2]), std::uint8_t(v[1]), std::uint8_t(v[0])};
    else
      rgb = {std::uint8_t(v[0]), std::uint8_t(v[1]), std::uint8_t(v[2])};
    data.rgb.push_back(rgb);
    data.skin.push_back(v[3] == skin_label ? 1 : 0);
  }
  if (data.size() == 0) throw std::runtime_error("no samples in '" + path + "'");
  return data;
}

Eigen::MatrixX2d normalizedRgOf(const LabelledPixels& data, std::uint8_t skin) {
  Eigen::MatrixX2d rg(Eigen::Index(std::count(data.skin.begin(), data.skin.end(), skin)), 2);
  Eigen::Index row = 0;
  for (std::size_t i = 0; i < data.size(); ++i) {
    if (data.skin[i] != skin) continue;
    const NormalizedRgI c = toNormalizedRgI(data.rgb[i][0], data.rgb[i][1], data.rgb[i][2]);
    rg(row, 0) = c.r;
    rg(row, 1) = c.g;
    ++row;
  }
  return rg;
}

void splitHoldout(const LabelledPixels& all, double holdout_fraction, std::uint64_t seed,
                  LabelledPixels* train, LabelledPixels* holdout) {
  if (!(holdout_fraction >= 0.0 && holdout_fraction <= 1.0))
    throw std::invalid_argument("hold-out fraction must be in [0, 1]");
  std::mt19937_64 rng(seed);
  // Compare raw 64-bit draws with a threshold (distributions are not portable across
  // standard libraries, the engine is).
  const auto threshold =
      std::uint64_t(holdout_fraction * double(std::numeric_limits<std::uint64_t>::max()));
  LabelledPixels tr, ho;
  for (std::size_t i = 0; i < all.size(); ++i) {
    LabelledPixels& dst = (rng() < threshold) ? ho : tr;
    dst.rgb.push_back(all.rgb[i]);
    dst.skin.push_back(all.skin[i]);
  }
  if (train) *train = std::move(tr);
  if (holdout) *holdout = std::move(ho);
}

double rocAuc(const std::vector<double>& scores, const std::vector<std::uint8_t>& positive) {
  if (scores.size() != positive.size()) throw std::invalid_argument("rocAuc: size mismatch");
  std::vector<std::size_t> order(scores.size());
  std::iota(order.begin(), order.end(), std::size_t(0));
  std::sort(order.begin(), order.end(),
            [&](std::size_t a, std::size_t b) { return scores[a] < scores[b]; });
  // Mann-Whitney U with mid-ranks for ties.
  double rank_sum_pos = 0.0;
  std::size_t n_pos = 0;
  for (std::size_t i = 0; i < order.size();) {
    std::size_t j = i;
    while (j < order.size() && scores[order[j]] == scores[order[i]]) ++j;
    const double mid_rank = 0.5 * double(i + 1 + j);  // ranks i+1 .. j
    for (std::size_t k = i; k < j; ++k)
      if (positive[order[k]]) {
        rank_sum_pos += mid_rank;
        ++n_pos;
      }
    i = j;
  }
  const std::size_t n_neg = scores.size() - n_pos;
  if (n_pos == 0 || n_neg == 0) return std::numeric_limits<double>::quiet_NaN();
  const double u = rank_sum_pos - double(n_pos) * double(n_pos + 1) / 2.0;
  return u / (double(n_pos) * double(n_neg));
}

}  // namespace psfs
