#include "solver/electro/node_pair_ldlt.h"

#include <algorithm>
#include <cstdint>

#include <Eigen/OrderingMethods>
#include <Eigen/SparseCholesky>

#include "solver/core/errors.h"

namespace systole::electro {

NodePairLdlt::NodePairLdlt(const Eigen::SparseMatrix<double>& a, const std::string& what) {
  using Sparse = Eigen::SparseMatrix<double>;
  using Triplet = Eigen::Triplet<double>;
  const Eigen::Index size = a.rows();
  if (a.cols() != size || size % 2 != 0)
    throw InstabilityError("electro", what, 0.0, "node-pair LDLT needs a square matrix of even size");
  const Eigen::Index n = size / 2;

  // Node graph: the union of the four blocks' patterns (both triangles), AMD on it.
  std::vector<Triplet> t;
  t.reserve(static_cast<std::size_t>(2 * a.nonZeros()));
  for (Eigen::Index c = 0; c < a.outerSize(); ++c)
    for (Sparse::InnerIterator it(a, c); it; ++it) {
      const Eigen::Index i = it.row() % n, j = it.col() % n;
      t.emplace_back(i, j, 1.0);
      t.emplace_back(j, i, 1.0);
    }
  Sparse graph(n, n);
  graph.setFromTriplets(t.begin(), t.end());
  Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> order;  // order[k]: node at k
  Eigen::AMDOrdering<int>()(graph, order);
  std::vector<std::int32_t> node_position(static_cast<std::size_t>(n));
  for (Eigen::Index k = 0; k < n; ++k) node_position[static_cast<std::size_t>(order.indices()[k])] = static_cast<std::int32_t>(k);
  position_.resize(static_cast<std::size_t>(size));
  for (Eigen::Index i = 0; i < size; ++i)
    position_[static_cast<std::size_t>(i)] = 2 * node_position[static_cast<std::size_t>(i % n)] + static_cast<std::int32_t>(i / n);

  // The permuted lower triangle, factorised without a further reordering.
  t.clear();
  for (Eigen::Index c = 0; c < a.outerSize(); ++c)
    for (Sparse::InnerIterator it(a, c); it; ++it) {
      if (it.row() < it.col()) continue;
      const auto r = position_[static_cast<std::size_t>(it.row())], q = position_[static_cast<std::size_t>(it.col())];
      t.emplace_back(std::max(r, q), std::min(r, q), it.value());
    }
  Sparse permuted(size, size);
  permuted.setFromTriplets(t.begin(), t.end());
  const Eigen::SimplicialLDLT<Sparse, Eigen::Lower, Eigen::NaturalOrdering<int>> f(permuted);
  if (f.info() != Eigen::Success) throw InstabilityError("electro", what, 0.0, "sparse LDLT factorisation failed");

  // Pack L (strictly lower, unit diagonal, sorted rows per column) into 2 x 2 blocks.
  const Sparse& l = f.matrixL().nestedExpression();
  const auto* lp = l.outerIndexPtr();
  const auto* li = l.innerIndexPtr();
  const auto* lx = l.valuePtr();
  diag_l_.assign(static_cast<std::size_t>(n), 0.0);
  block_start_.assign(static_cast<std::size_t>(n) + 1, 0);
  block_row_.clear();
  block_value_.clear();
  for (Eigen::Index node = 0; node < n; ++node) {
    auto p0 = lp[2 * node], e0 = lp[2 * node + 1];  // column 2 node
    auto p1 = lp[2 * node + 1], e1 = lp[2 * node + 2];  // column 2 node + 1
    if (p0 < e0 && li[p0] == 2 * node + 1) diag_l_[static_cast<std::size_t>(node)] = lx[p0++];
    while (p0 < e0 || p1 < e1) {
      const int r0 = p0 < e0 ? li[p0] / 2 : INT32_MAX, r1 = p1 < e1 ? li[p1] / 2 : INT32_MAX;
      const int row = std::min(r0, r1);
      double v[4] = {0, 0, 0, 0};
      for (; p0 < e0 && li[p0] / 2 == row; ++p0) v[li[p0] % 2] = lx[p0];
      for (; p1 < e1 && li[p1] / 2 == row; ++p1) v[2 + li[p1] % 2] = lx[p1];
      block_row_.push_back(row);
      block_value_.insert(block_value_.end(), v, v + 4);
    }
    block_start_[static_cast<std::size_t>(node) + 1] = static_cast<std::int64_t>(block_row_.size());
  }
  d_inverse_.resize(static_cast<std::size_t>(size));
  for (Eigen::Index i = 0; i < size; ++i) d_inverse_[static_cast<std::size_t>(i)] = 1.0 / f.vectorD()[i];
  work_.assign(static_cast<std::size_t>(size), 0.0);
}

void NodePairLdlt::solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) const {
  using V2 = Eigen::Vector2d;
  using Map2 = Eigen::Map<V2>;
  using ConstMap2 = Eigen::Map<const V2>;
  const std::size_t size = position_.size();
  const auto nodes = static_cast<std::int64_t>(diag_l_.size());
  double* y = work_.data();
  const double* val = block_value_.data();
  const std::int32_t* row = block_row_.data();
  for (std::size_t i = 0; i < size; ++i) y[position_[i]] = b[static_cast<Eigen::Index>(i)];
  // L y = P b, column node by column node: y_I -= L_IJ y_J.
  for (std::int64_t j = 0; j < nodes; ++j) {
    y[2 * j + 1] -= diag_l_[static_cast<std::size_t>(j)] * y[2 * j];
    const double y0 = y[2 * j], y1 = y[2 * j + 1];
    for (std::int64_t k = block_start_[static_cast<std::size_t>(j)]; k < block_start_[static_cast<std::size_t>(j) + 1]; ++k)
      Map2(y + 2 * row[k]) -= ConstMap2(val + 4 * k) * y0 + ConstMap2(val + 4 * k + 2) * y1;
  }
  for (std::size_t i = 0; i < size; ++i) y[i] *= d_inverse_[i];
  // L^T x = y, column node by column node from the last: x_J = y_J - sum_I L_IJ^T x_I.
  for (std::int64_t j = nodes - 1; j >= 0; --j) {
    // Two accumulator pairs (even and odd blocks) for instruction-level parallelism.
    V2 s0 = V2::Zero(), s1 = V2::Zero(), u0 = V2::Zero(), u1 = V2::Zero();
    std::int64_t k = block_start_[static_cast<std::size_t>(j)];
    const std::int64_t end = block_start_[static_cast<std::size_t>(j) + 1];
    for (; k + 1 < end; k += 2) {
      const ConstMap2 xa(y + 2 * row[k]), xb(y + 2 * row[k + 1]);
      s0 += ConstMap2(val + 4 * k).cwiseProduct(xa);
      s1 += ConstMap2(val + 4 * k + 2).cwiseProduct(xa);
      u0 += ConstMap2(val + 4 * k + 4).cwiseProduct(xb);
      u1 += ConstMap2(val + 4 * k + 6).cwiseProduct(xb);
    }
    if (k < end) {
      const ConstMap2 xa(y + 2 * row[k]);
      s0 += ConstMap2(val + 4 * k).cwiseProduct(xa);
      s1 += ConstMap2(val + 4 * k + 2).cwiseProduct(xa);
    }
    s0 += u0;
    s1 += u1;
    const double x1 = y[2 * j + 1] - s1.sum();
    y[2 * j + 1] = x1;
    y[2 * j] = y[2 * j] - s0.sum() - diag_l_[static_cast<std::size_t>(j)] * x1;
  }
  x.resize(static_cast<Eigen::Index>(size));
  for (std::size_t i = 0; i < size; ++i) x[static_cast<Eigen::Index>(i)] = y[position_[i]];
}

}  // namespace systole::electro
