// A planar checkerboard calibration target (issue 18, thesis 3.2): its inner-corner grid and
// the corners' positions in the board's own frame (z = 0, x along the columns, y along the rows,
// origin at the first inner corner). ROS-free.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace tabletop_capture {

struct CheckerboardSpec {
  int cols = 9;          // inner corners per row (squares per row - 1)
  int rows = 6;          // inner corners per column
  double square = 0.03;  // edge of one square (m)

  // Throws std::invalid_argument naming the field for sizes OpenCV's detector cannot use.
  void validate() const {
    if (cols < 3 || rows < 3)
      throw std::invalid_argument("checkerboard: at least 3x3 inner corners, got " +
                                  std::to_string(cols) + "x" + std::to_string(rows));
    if (cols == rows)
      throw std::invalid_argument("checkerboard: cols == rows makes the board's orientation "
                                  "ambiguous; use e.g. 9x6");
    if (!(square > 0)) throw std::invalid_argument("checkerboard: square must be > 0 m");
  }
  int corners() const { return cols * rows; }
  // Corner k = r * cols + c at (c * square, r * square, 0), OpenCV's order.
  std::vector<Eigen::Vector3d> boardPoints() const {
    std::vector<Eigen::Vector3d> p;
    p.reserve(corners());
    for (int r = 0; r < rows; ++r)
      for (int c = 0; c < cols; ++c) p.emplace_back(c * square, r * square, 0.0);
    return p;
  }
};

}  // namespace tabletop_capture
