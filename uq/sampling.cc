#include "uq/sampling.h"

#include <algorithm>
#include <array>
#include <numeric>
#include <stdexcept>
#include <string>
#include <vector>

#include "uq/format.h"
#include "uq/random.h"

namespace systole::uq {
namespace {

using detail::num;

[[noreturn]] void bad(const std::string& message) { throw std::invalid_argument(message); }

// Primitive polynomials and initial direction numbers of Joe & Kuo, dimensions 2..40 of
// new-joe-kuo-6.21201 (S. Joe and F. Y. Kuo, "Constructing Sobol sequences with better
// two-dimensional projections", SIAM J. Sci. Comput. 30, 2635-2654 (2008);
// https://web.maths.unsw.edu.au/~fkuo/sobol/). Columns: s = degree, a = interior
// coefficients of the polynomial, m_1..m_s. Dimension 1 is the van der Corput sequence.
struct JoeKuoRow {
  unsigned s;
  unsigned a;
  std::array<unsigned, 8> m;
};
constexpr JoeKuoRow kJoeKuo[kSobolMaxDimensions - 1] = {
    {1, 0, {1}},                                 // d = 2
    {2, 1, {1, 3}},                              // 3
    {3, 1, {1, 3, 1}},                           // 4
    {3, 2, {1, 1, 1}},                           // 5
    {4, 1, {1, 1, 3, 3}},                        // 6
    {4, 4, {1, 3, 5, 13}},                       // 7
    {5, 2, {1, 1, 5, 5, 17}},                    // 8
    {5, 4, {1, 1, 5, 5, 5}},                     // 9
    {5, 7, {1, 1, 7, 11, 19}},                   // 10
    {5, 11, {1, 1, 5, 1, 1}},                    // 11
    {5, 13, {1, 1, 1, 3, 11}},                   // 12
    {5, 14, {1, 3, 5, 5, 31}},                   // 13
    {6, 1, {1, 3, 3, 9, 7, 49}},                 // 14
    {6, 13, {1, 1, 1, 15, 21, 21}},              // 15
    {6, 16, {1, 3, 1, 13, 27, 49}},              // 16
    {6, 19, {1, 1, 1, 15, 7, 5}},                // 17
    {6, 22, {1, 3, 1, 15, 13, 25}},              // 18
    {6, 25, {1, 1, 5, 5, 19, 61}},               // 19
    {7, 1, {1, 3, 7, 11, 23, 15, 103}},          // 20
    {7, 4, {1, 3, 7, 13, 13, 15, 69}},           // 21
    {7, 7, {1, 1, 3, 13, 7, 35, 63}},            // 22
    {7, 8, {1, 3, 5, 9, 1, 25, 53}},             // 23
    {7, 14, {1, 3, 1, 13, 9, 35, 107}},          // 24
    {7, 19, {1, 3, 1, 5, 27, 61, 31}},           // 25
    {7, 21, {1, 1, 5, 11, 19, 41, 61}},          // 26
    {7, 28, {1, 3, 5, 3, 3, 13, 69}},            // 27
    {7, 31, {1, 1, 7, 13, 1, 19, 1}},            // 28
    {7, 32, {1, 3, 7, 5, 13, 19, 59}},           // 29
    {7, 37, {1, 1, 3, 9, 25, 29, 41}},           // 30
    {7, 41, {1, 3, 5, 13, 23, 1, 55}},           // 31
    {7, 42, {1, 3, 7, 3, 13, 59, 17}},           // 32
    {7, 50, {1, 3, 1, 3, 5, 53, 69}},            // 33
    {7, 55, {1, 1, 5, 5, 23, 33, 13}},           // 34
    {7, 56, {1, 1, 7, 7, 1, 61, 123}},           // 35
    {7, 59, {1, 1, 7, 9, 13, 61, 49}},           // 36
    {7, 62, {1, 3, 3, 5, 3, 55, 33}},            // 37
    {8, 14, {1, 3, 1, 15, 31, 13, 49, 245}},     // 38
    {8, 21, {1, 3, 5, 15, 31, 59, 63, 97}},      // 39
    {8, 22, {1, 3, 1, 11, 11, 11, 77, 249}},     // 40
};

using DirectionVector = std::array<std::uint32_t, 32>;

// v_k (k = 0..31, left-aligned: v_k = m_{k+1} 2^(31-k)) from the recurrence of Bratley & Fox
// (1988) as written in Joe & Kuo's notes:
//   m_k = 2 a_1 m_{k-1} ^ 4 a_2 m_{k-2} ^ ... ^ 2^(s-1) a_{s-1} m_{k-s+1} ^ 2^s m_{k-s} ^ m_{k-s}.
DirectionVector direction_vector(std::size_t dim) {
  DirectionVector v{};
  if (dim == 0) {
    for (unsigned k = 0; k < 32; ++k) v[k] = std::uint32_t{1} << (31 - k);
    return v;
  }
  const JoeKuoRow& row = kJoeKuo[dim - 1];
  const unsigned s = row.s;
  for (unsigned k = 0; k < s; ++k) v[k] = row.m[k] << (31 - k);
  for (unsigned k = s; k < 32; ++k) {
    v[k] = v[k - s] ^ (v[k - s] >> s);
    for (unsigned l = 1; l < s; ++l)
      if ((row.a >> (s - 1 - l)) & 1u) v[k] ^= v[k - l];
  }
  return v;
}

// Coordinate `dim` of Sobol' point `index` (Gray-code order), as a 32-bit binary fraction.
std::uint32_t sobol_digits(const DirectionVector& v, std::uint64_t index) {
  std::uint64_t g = index ^ (index >> 1);
  std::uint32_t x = 0;
  for (unsigned k = 0; g != 0; ++k, g >>= 1)
    if (g & 1u) x ^= v[k];
  return x;
}

// Owen's nested uniform scramble of the 32 leading digits of x: digit k (from the most
// significant) is XORed with the random bit of tree node (k, leading k digits of x). Node ids
// 2^k | prefix are unique per (k, prefix). Returns the scrambled 32 digits and, in `tail`,
// 20 further random digits for the leaf reached (node id 2^32 | x).
std::uint32_t owen_scramble(std::uint32_t x, std::uint64_t key, std::uint32_t& tail) {
  std::uint32_t out = x;
  for (unsigned k = 0; k < 32; ++k) {
    const std::uint64_t prefix = k == 0 ? 0 : (x >> (32 - k));
    const std::uint64_t node = (std::uint64_t{1} << k) | prefix;
    if (mix64(key ^ mix64(node)) >> 63) out ^= std::uint32_t{1} << (31 - k);
  }
  const std::uint64_t leaf = (std::uint64_t{1} << 32) | x;
  tail = static_cast<std::uint32_t>(mix64(key ^ mix64(leaf)) >> 44);  // 20 bits
  return out;
}

void check_shape(std::string_view design, std::size_t samples, std::size_t dimensions,
                 std::size_t max_dimensions) {
  if (samples < 1) bad(std::string(design) + ": samples = " + num(samples) + " is out of range (must be >= 1)");
  if (dimensions < 1 || dimensions > max_dimensions)
    bad(std::string(design) + ": dimensions = " + num(dimensions) +
        " is out of range (must be in 1.." + num(max_dimensions) + ")");
  if (static_cast<std::uint64_t>(samples) > kMaxDesignValues / dimensions)
    bad(std::string(design) + ": samples * dimensions = " + num(samples) + " * " + num(dimensions) +
        " is out of range (must be <= " + num(static_cast<std::size_t>(kMaxDesignValues)) + ")");
}

constexpr double kBelowOne = 1.0 - 0x1p-53;  // largest double < 1

}  // namespace

std::string_view to_string(DesignKind kind) {
  switch (kind) {
    case DesignKind::monte_carlo: return "monte_carlo";
    case DesignKind::latin_hypercube: return "latin_hypercube";
    case DesignKind::sobol: return "sobol";
    case DesignKind::saltelli: return "saltelli";
  }
  return "unknown";
}

DesignKind parse_design_kind(std::string_view name) {
  for (auto k : {DesignKind::monte_carlo, DesignKind::latin_hypercube, DesignKind::sobol,
                 DesignKind::saltelli})
    if (name == to_string(k)) return k;
  bad("design = \"" + std::string(name) +
      "\" is unknown (allowed: monte_carlo, latin_hypercube, sobol, saltelli)");
}

Matrix monte_carlo(std::size_t samples, std::size_t dimensions, std::uint64_t seed) {
  check_shape("monte_carlo", samples, dimensions, static_cast<std::size_t>(kMaxDesignValues));
  Matrix out(samples, dimensions);
  for (std::size_t c = 0; c < dimensions; ++c) {
    Rng rng(derive_seed(seed, c));
    for (std::size_t r = 0; r < samples; ++r) out(r, c) = uniform01(rng);
  }
  return out;
}

Matrix latin_hypercube(std::size_t samples, std::size_t dimensions, std::uint64_t seed) {
  check_shape("latin_hypercube", samples, dimensions, static_cast<std::size_t>(kMaxDesignValues));
  Matrix out(samples, dimensions);
  std::vector<std::size_t> perm(samples);
  const double n = static_cast<double>(samples);
  for (std::size_t c = 0; c < dimensions; ++c) {
    Rng rng(derive_seed(seed, c));
    std::iota(perm.begin(), perm.end(), std::size_t{0});
    shuffle(std::span<std::size_t>(perm), rng);
    for (std::size_t r = 0; r < samples; ++r)
      out(r, c) = std::min((static_cast<double>(perm[r]) + uniform01(rng)) / n, kBelowOne);
  }
  return out;
}

Matrix sobol(std::size_t samples, std::size_t dimensions, std::uint64_t seed,
             SobolScrambling scrambling) {
  check_shape("sobol", samples, dimensions, kSobolMaxDimensions);
  if (static_cast<std::uint64_t>(samples) > kSobolMaxSamples)
    bad("sobol: samples = " + num(samples) + " is out of range (must be <= 2^32)");
  Matrix out(samples, dimensions);
  for (std::size_t c = 0; c < dimensions; ++c) {
    const DirectionVector v = direction_vector(c);
    const std::uint64_t key = derive_seed(seed, c);
    for (std::size_t r = 0; r < samples; ++r) {
      const std::uint32_t x = sobol_digits(v, r);
      if (scrambling == SobolScrambling::none) {
        out(r, c) = static_cast<double>(x) * 0x1p-32;
      } else {
        std::uint32_t tail = 0;
        const std::uint64_t digits = (std::uint64_t{owen_scramble(x, key, tail)} << 20) | tail;
        out(r, c) = (static_cast<double>(digits) + 0.5) * 0x1p-52;  // exact, in (0, 1)
      }
    }
  }
  return out;
}

Matrix unit_design(DesignKind kind, std::size_t samples, std::size_t dimensions,
                   std::uint64_t seed) {
  switch (kind) {
    case DesignKind::monte_carlo: return monte_carlo(samples, dimensions, seed);
    case DesignKind::latin_hypercube: return latin_hypercube(samples, dimensions, seed);
    case DesignKind::sobol: return sobol(samples, dimensions, seed);
    case DesignKind::saltelli: break;
  }
  bad("design = \"saltelli\" is not a plain design here (allowed: monte_carlo, latin_hypercube, "
      "sobol; use saltelli() for the Sobol'-index scheme)");
}

SaltelliLayout::SaltelliLayout(std::size_t base_samples, std::size_t dimensions)
    : n_(base_samples), d_(dimensions) {
  if (base_samples < 2)
    bad("saltelli: samples = " + num(base_samples) + " is out of range (base samples must be >= 2)");
  if (dimensions < 1)
    bad("saltelli: dimensions = " + num(dimensions) + " is out of range (must be >= 1)");
  if (static_cast<std::uint64_t>(base_samples) > kMaxDesignValues / (dimensions + 2) / dimensions)
    bad("saltelli: samples * (dimensions + 2) * dimensions = " + num(base_samples) + " * " +
        num(dimensions + 2) + " * " + num(dimensions) + " is out of range (must be <= " +
        num(static_cast<std::size_t>(kMaxDesignValues)) + ")");
}

std::size_t SaltelliLayout::evaluation(std::size_t row, std::size_t block) const {
  if (row >= n_)
    bad("saltelli: row = " + num(row) + " is out of range (must be < " + num(n_) + ")");
  if (block >= d_ + 2)
    bad("saltelli: block = " + num(block) + " is out of range (must be < " + num(d_ + 2) + ")");
  return row * (d_ + 2) + block;
}

SaltelliSlot SaltelliLayout::slot(std::size_t evaluation) const {
  if (evaluation >= evaluations())
    bad("saltelli: evaluation = " + num(evaluation) + " is out of range (must be < " +
        num(evaluations()) + ")");
  return {evaluation / (d_ + 2), evaluation % (d_ + 2)};
}

std::string SaltelliLayout::block_name(std::size_t block) const {
  if (block == kBlockA) return "A";
  if (block == kBlockB) return "B";
  if (block < d_ + 2) return "AB_" + std::to_string(block - 2);
  bad("saltelli: block = " + num(block) + " is out of range (must be < " + num(d_ + 2) + ")");
}

SaltelliDesign saltelli(std::size_t base_samples, std::size_t dimensions, std::uint64_t seed,
                        DesignKind base_kind) {
  SaltelliLayout layout(base_samples, dimensions);
  if (base_kind == DesignKind::saltelli)
    bad("saltelli: base design = \"saltelli\" is out of range (allowed: monte_carlo, "
        "latin_hypercube, sobol)");
  if (base_kind == DesignKind::sobol && 2 * dimensions > kSobolMaxDimensions)
    bad("saltelli: dimensions = " + num(dimensions) +
        " is out of range for a Sobol' base design (must be <= " + num(kSobolMaxDimensions / 2) +
        ", the base has 2 * dimensions columns; use base design monte_carlo or latin_hypercube)");
  SaltelliDesign out{layout, unit_design(base_kind, base_samples, 2 * dimensions, seed),
                     Matrix(layout.evaluations(), dimensions)};
  const std::size_t d = dimensions;
  for (std::size_t j = 0; j < base_samples; ++j) {
    const auto base = out.base.row(j);
    for (std::size_t block = 0; block < d + 2; ++block) {
      auto p = out.points.row(layout.evaluation(j, block));
      for (std::size_t c = 0; c < d; ++c) {
        const bool from_b = block == SaltelliLayout::kBlockB || block == SaltelliLayout::block_ab(c);
        p[c] = base[from_b ? d + c : c];
      }
    }
  }
  return out;
}

}  // namespace systole::uq
