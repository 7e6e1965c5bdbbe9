// Labelled colour samples (skin / non-skin) for training and validating the skin model, and the
// seeded hold-out split shared by the trainer tool and the tests (so the shipped model is
// always evaluated on pixels it was not trained on).
//
// Accepted text formats, one sample per line, comma/semicolon/whitespace separated; a first
// line that is not numeric (a header) is skipped, '#' starts a comment:
//  - UCI "Skin Segmentation" (ChannelOrder::BGR, skin label 1, non-skin label 2):
//    `B,G,R,label`. The UCI file's header reads `r,g,b,skin`, but its documentation gives the
//    order as B,G,R (see shared/data/README.md).
//  - generic CSV (ChannelOrder::RGB): `R,G,B,label`, label == skin_label is skin, anything
//    else is non-skin.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace psfs {

enum class ChannelOrder { BGR, RGB };

struct LabelledPixels {
  std::vector<std::array<std::uint8_t, 3>> rgb;  // always R, G, B
  std::vector<std::uint8_t> skin;                // 1 = skin, 0 = non-skin
  std::size_t size() const { return rgb.size(); }
  std::size_t countSkin() const;
  void append(const LabelledPixels& other);
};

// Throws std::runtime_error with file and line for unreadable files or malformed lines
// (wrong column count, values outside 0..255).
LabelledPixels loadLabelledPixels(const std::string& path, ChannelOrder order = ChannelOrder::BGR,
                                  int skin_label = 1);

// Normalised rg (color_space.h) of the samples whose label equals `skin` (1 or 0), one row each.
Eigen::MatrixX2d normalizedRgOf(const LabelledPixels& data, std::uint8_t skin);

// Deterministic split: each sample goes to the held-out part with probability
// holdout_fraction, decided by a seeded std::mt19937_64 (identical on every platform).
void splitHoldout(const LabelledPixels& all, double holdout_fraction, std::uint64_t seed,
                  LabelledPixels* train, LabelledPixels* holdout);

// Default split used for config/skin_gmm.yaml and its test.
constexpr double kDefaultHoldoutFraction = 0.2;
constexpr std::uint64_t kDefaultSplitSeed = 20080101;

// ROC area under the curve for scores where higher means "positive" (ties count half:
// the Mann-Whitney statistic). Returns NaN when one class is empty.
double rocAuc(const std::vector<double>& scores, const std::vector<std::uint8_t>& positive);

}  // namespace psfs
