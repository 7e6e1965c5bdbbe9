#include "log_term_table.h"

#include <vector>

namespace psfs {
namespace detail {

const int16_t* logTermTable() {
  // Values from round(1024 ln(256 / 130560)) = -6384 to 0: int16.
  static const std::vector<int16_t> table = [] {
    std::vector<int16_t> t(kMaxMedianPair + 1);
    for (int32_t m = 0; m <= kMaxMedianPair; ++m) t[m] = static_cast<int16_t>(logTermOfPair(m));
    return t;
  }();
  return table.data();
}

}  // namespace detail
}  // namespace psfs
