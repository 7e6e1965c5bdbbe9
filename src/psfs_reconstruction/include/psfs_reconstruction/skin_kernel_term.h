// One skin GMM component, pre-multiplied for the per-pixel classifier (pixel_classifier.h): the
// CPU row loops, the GPU kernel (passed by value, i.e. in constant memory) and its host
// emulation evaluate p(c|S) from these. Plain floats, usable from g++ and nvcc alike.
#pragma once

namespace psfs {
namespace detail {

// density = weight * exp(-(a dr^2 + b2 dr dg + c dg^2)), [a, b2/2; b2/2, c] = covariance^-1 / 2,
// weight = w / (2 pi sqrt(det covariance)).
struct SkinKernelTerm {
  float mean_r, mean_g, a, b2, c, weight;
};

}  // namespace detail
}  // namespace psfs
