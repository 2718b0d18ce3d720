#pragma once
// NodePairLdlt: the direct solver of the bidomain block system (tissue.h), ours — a faster
// equivalent of Eigen::SimplicialLDLT on the same matrix (same equations, same solution to
// round-off; docs/electro.md "Costs").
//
// Contract
// - Input: a symmetric positive definite 2n x 2n matrix in the block layout of tissue.cc,
//   unknown k of node i at row i + k n (k = 0: v, k = 1: u_e); only the lower triangle is read.
// - Ordering: the nodes by AMD on the node graph (the union of the four n x n blocks'
//   patterns), the two unknowns of a node adjacent (node-interleaved). The permuted matrix is
//   factorised once by Eigen::SimplicialLDLT with its natural ordering (exact LDL^T, no pivoting,
//   as before); L is then stored as dense 2 x 2 blocks per (row node, column node) pair, so the
//   triangular solves read one index per four entries and run on 2-vectors (Eigen packets).
//   The block AMD ordering of the 2n-unknown matrix had the same fill (528 306 vs 530 126
//   entries of L on the default heart); the gain is the blocked solve, not the fill.
// - solve(b, x): x = A^-1 b in the input layout. Equals SimplicialLDLT(A).solve(b) to round-off
//   (another elimination order and summation order; tests/electro/tissue_test.cc).
// - Throws InstabilityError("electro", what, 0, ...) for an odd or non-square matrix or a zero
//   pivot (as SimplicialLDLT, positive definiteness is not checked further). Not thread-safe:
//   solve() uses a member workspace.
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Sparse>

namespace systole::electro {

class NodePairLdlt {
 public:
  NodePairLdlt(const Eigen::SparseMatrix<double>& a, const std::string& what);

  // x = A^-1 b (b, x of size 2n in the input layout; x is resized; b and x may not alias).
  void solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) const;

  std::size_t nodes() const { return diag_l_.size(); }
  // Stored entries of L (4 per off-diagonal block plus one per diagonal block).
  std::size_t factor_entries() const { return 4 * block_row_.size() + diag_l_.size(); }

 private:
  // position_[i]: the interleaved position of input unknown i (2 node' + k).
  std::vector<std::int32_t> position_;
  // Column node J: its diagonal block [1 0; diag_l_[J] 1]; off-diagonal blocks k in
  // [block_start_[J], block_start_[J + 1]) at row node block_row_[k] > J with the entries
  // block_value_[4k .. 4k + 3] = (L00, L10, L01, L11) (column-major 2 x 2).
  std::vector<double> diag_l_;
  std::vector<std::int64_t> block_start_;
  std::vector<std::int32_t> block_row_;
  std::vector<double> block_value_;
  std::vector<double> d_inverse_;  // 1 / D per interleaved unknown
  mutable std::vector<double> work_;
};

}  // namespace systole::electro
