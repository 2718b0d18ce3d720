#pragma once
// Internal: number formatting for error messages (not installed API).
#include <cmath>
#include <cstddef>
#include <sstream>
#include <string>

namespace systole::uq::detail {

inline std::string num(double x) {
  if (std::isnan(x)) return "nan";
  if (std::isinf(x)) return x > 0 ? "inf" : "-inf";
  std::ostringstream s;
  s.precision(15);
  s << x;
  return s.str();
}
inline std::string num(std::size_t x) { return std::to_string(x); }

}  // namespace systole::uq::detail
