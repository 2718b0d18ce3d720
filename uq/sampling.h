#pragma once
// Designs over the unit hypercube (0, 1)^d, reproducible from a 64-bit seed: the same
// (kind, samples, dimensions, seed) gives bit-identical designs on every platform. Rows are
// samples, columns are inputs; map them to physical values with to_physical()
// (uq/distributions.h).
//
//  - Monte Carlo: i.i.d. uniform points; column c uses its own std::mt19937_64 stream
//    (seeded with derive_seed(seed, c)), so a column does not change when inputs are added.
//  - Latin hypercube (McKay, Beckman & Conover 1979): per column an independent random
//    permutation pi of 0..n-1 and u_ic = (pi_i + U_ic) / n with U_ic ~ U(0, 1) ("jittered"):
//    every one of the n equal strata of every column holds exactly one point.
//  - Sobol' (Sobol' 1967) in Gray-code order (Antonov & Saleev 1979) with the direction
//    numbers of Joe & Kuo (2008), file new-joe-kuo-6.21201, embedded for the first
//    kSobolMaxDimensions dimensions; 32-bit digits. Randomised by Owen's nested uniform
//    scrambling (Owen 1995): digit k of a coordinate is flipped by a random bit drawn for the
//    node (k, first k digits) of the binary tree, per dimension; the random bits come from a
//    counter-based hash (SplitMix64) of (seed, dimension, node), i.e. the random tree is drawn
//    lazily. Digits below the 32nd are filled with random bits (as the infinite-digit
//    scramble would), so each scrambled point is uniform on (0, 1)^d and the set keeps the
//    (t, m, s)-net structure. The first point is NOT dropped (Owen 2022, "On dropping the first
//    Sobol' point"). Balance properties hold for n a power of two, which is recommended;
//    other n are accepted. SobolScrambling::none gives the raw sequence (first point 0) for
//    checking against published values: do not map it through unbounded quantiles.
//  - Saltelli scheme (Saltelli 2002, Saltelli et al. 2010) for Sobol' indices: a base design
//    of n rows and 2d columns (Sobol' by default) split into A (columns 0..d-1) and
//    B (columns d..2d-1), and for each input i the matrix AB_i = A with column i taken from
//    B: n (d + 2) model evaluations. Evaluation order is row-major over (row, block):
//        evaluation e = row * (d + 2) + block,  block 0 = A, 1 = B, 2 + i = AB_i,
//    so the evaluations of one base row are contiguous (a partially finished campaign has
//    complete row groups, and a failed evaluation removes exactly one group).
//
// Errors: std::invalid_argument naming the parameter, its value and the allowed range.
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "uq/matrix.h"

namespace systole::uq {

enum class DesignKind { monte_carlo, latin_hypercube, sobol, saltelli };
// "monte_carlo", "latin_hypercube", "sobol", "saltelli".
std::string_view to_string(DesignKind kind);
DesignKind parse_design_kind(std::string_view name);

enum class SobolScrambling { none, owen };

inline constexpr std::size_t kSobolMaxDimensions = 40;
inline constexpr std::uint64_t kSobolMaxSamples = std::uint64_t{1} << 32;
// Upper bound on samples * columns of any one design (2^28 doubles = 2 GiB).
inline constexpr std::uint64_t kMaxDesignValues = std::uint64_t{1} << 28;

Matrix monte_carlo(std::size_t samples, std::size_t dimensions, std::uint64_t seed);
Matrix latin_hypercube(std::size_t samples, std::size_t dimensions, std::uint64_t seed);
Matrix sobol(std::size_t samples, std::size_t dimensions, std::uint64_t seed,
             SobolScrambling scrambling = SobolScrambling::owen);
// One of monte_carlo / latin_hypercube / sobol (owen); DesignKind::saltelli is rejected here
// (use saltelli()).
Matrix unit_design(DesignKind kind, std::size_t samples, std::size_t dimensions,
                   std::uint64_t seed);

// Where an evaluation sits in the Saltelli scheme.
struct SaltelliSlot {
  std::size_t row = 0;    // base sample j in 0..n-1
  std::size_t block = 0;  // 0 = A, 1 = B, 2 + i = AB_i
  bool operator==(const SaltelliSlot&) const = default;
};

class SaltelliLayout {
 public:
  static constexpr std::size_t kBlockA = 0;
  static constexpr std::size_t kBlockB = 1;
  static constexpr std::size_t block_ab(std::size_t input) { return 2 + input; }

  // base_samples >= 2, dimensions >= 1.
  SaltelliLayout(std::size_t base_samples, std::size_t dimensions);

  std::size_t base_samples() const { return n_; }
  std::size_t dimensions() const { return d_; }
  std::size_t blocks_per_row() const { return d_ + 2; }
  std::size_t evaluations() const { return n_ * (d_ + 2); }

  std::size_t evaluation(std::size_t row, std::size_t block) const;  // throws if out of range
  std::size_t evaluation(SaltelliSlot slot) const { return evaluation(slot.row, slot.block); }
  SaltelliSlot slot(std::size_t evaluation) const;                    // throws if out of range
  // "A", "B", "AB_0", "AB_1", ... (inputs numbered from 0, like design columns).
  std::string block_name(std::size_t block) const;
  // True for A and B evaluations: together 2n independent (or RQMC) draws from the input
  // distribution, the natural sample for means, percentiles and correlations.
  bool is_base_evaluation(std::size_t evaluation) const { return evaluation % (d_ + 2) < 2; }

  bool operator==(const SaltelliLayout&) const = default;

 private:
  std::size_t n_;
  std::size_t d_;
};

struct SaltelliDesign {
  SaltelliLayout layout;
  Matrix base;    // n x 2d: columns 0..d-1 are A, d..2d-1 are B
  Matrix points;  // n(d+2) x d, in evaluation order (see SaltelliLayout)
};

// base_kind: monte_carlo, latin_hypercube or sobol (default; requires 2d <= kSobolMaxDimensions).
SaltelliDesign saltelli(std::size_t base_samples, std::size_t dimensions, std::uint64_t seed,
                        DesignKind base_kind = DesignKind::sobol);

}  // namespace systole::uq
