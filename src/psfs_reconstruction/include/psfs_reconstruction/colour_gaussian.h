// A Gaussian over normalised rg chroma (color_space.h): the person's clothing colour as the
// skin classifier's non-skin density takes it (clothing_colour.h, pixel_classifier.h).
#pragma once

#include <Eigen/Core>

namespace psfs {

struct ColourGaussian {
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();             // normalised (r, g)
  Eigen::Matrix2d covariance = Eigen::Matrix2d::Identity();  // rg units^2
};

}  // namespace psfs
