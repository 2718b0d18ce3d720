#pragma once
// A small dense row-major matrix of doubles: the currency of the uq/ library (a design is a
// matrix of samples x dimensions). Deliberately not Eigen, so that the public API of systole_uq
// depends on the standard library only.
#include <cstddef>
#include <span>
#include <vector>

namespace systole::uq {

class Matrix {
 public:
  Matrix() = default;
  Matrix(std::size_t rows, std::size_t cols, double fill = 0.0)
      : rows_(rows), cols_(cols), values_(rows * cols, fill) {}

  std::size_t rows() const { return rows_; }
  std::size_t cols() const { return cols_; }
  bool empty() const { return values_.empty(); }

  double& operator()(std::size_t r, std::size_t c) { return values_[r * cols_ + c]; }
  double operator()(std::size_t r, std::size_t c) const { return values_[r * cols_ + c]; }

  std::span<double> row(std::size_t r) { return {values_.data() + r * cols_, cols_}; }
  std::span<const double> row(std::size_t r) const { return {values_.data() + r * cols_, cols_}; }
  // A copy of column c (columns are strided in row-major storage).
  std::vector<double> column(std::size_t c) const {
    std::vector<double> out(rows_);
    for (std::size_t r = 0; r < rows_; ++r) out[r] = values_[r * cols_ + c];
    return out;
  }

  // Row-major storage: element (r, c) is data()[r * cols() + c].
  const std::vector<double>& data() const { return values_; }
  std::vector<double>& data() { return values_; }

  bool operator==(const Matrix&) const = default;

 private:
  std::size_t rows_ = 0;
  std::size_t cols_ = 0;
  std::vector<double> values_;
};

}  // namespace systole::uq
