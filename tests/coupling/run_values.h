#pragma once
// A run's series points and metrics as one flat name -> value map, written with 17 digits and
// compared value by value: the coupled scenes' "the same run two ways" tests (np 1 vs np 2:
// fsei_ranks_test.cc; straight vs resumed: fsei_restart_test.cc).
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <map>
#include <stdexcept>
#include <string>

#include "solver/core/run_result.h"

namespace systole::test {

using RunValues = std::map<std::string, double>;

// "series[i]" for every series point, "metric:name" for every metric.
inline RunValues values_of(const RunResult& r) {
  RunValues values;
  for (const auto& series : r.series)
    for (std::size_t i = 0; i < series.values.size(); ++i)
      values[series.name + "[" + std::to_string(i) + "]"] = series.values[i];
  for (const auto& [name, v] : r.metrics) values["metric:" + name] = v;
  return values;
}

inline void write_values(const std::string& file, const RunValues& values) {
  std::ofstream out(file);
  out.precision(17);
  for (const auto& [name, v] : values) out << name << ' ' << v << '\n';
  if (!out) throw std::runtime_error("cannot write " + file);
}

inline RunValues read_values(const std::string& file) {
  std::ifstream in(file);
  if (!in) throw std::runtime_error("no reference file " + file);
  RunValues values;
  std::string name;
  double v = 0;
  while (in >> name >> v) values[name] = v;
  return values;
}

struct Comparison {
  int compared = 0, bad = 0;
  double worst = 0;  // largest |a - b| / (|a| + 1)
  std::string worst_name;
};

// Compares every value of `ref` with `values` (the same names, else std::runtime_error), except
// those `skip` names; a value is bad when not finite or when |a - b| / (|a| + 1) > tolerance.
// Prints each bad value (and each skipped one when print_skipped) with the two labels.
inline Comparison compare_values(const RunValues& ref, const RunValues& values, double tolerance,
                                 const std::function<bool(const std::string&)>& skip, const std::string& ref_label,
                                 const std::string& label, bool print_skipped = false) {
  if (ref.size() != values.size())
    throw std::runtime_error(ref_label + " gave " + std::to_string(ref.size()) + " values, " + label + " " +
                             std::to_string(values.size()));
  Comparison c;
  for (const auto& [key, a] : ref) {
    const auto it = values.find(key);
    if (it == values.end()) throw std::runtime_error(label + " lacks " + key);
    const double b = it->second;
    if (skip(key)) {
      if (print_skipped) std::printf("  %s: %s %.17g, %s %.17g (not compared)\n", key.c_str(), ref_label.c_str(), a, label.c_str(), b);
      continue;
    }
    ++c.compared;
    const double rel = std::abs(a - b) / (std::abs(a) + 1);
    if (!std::isfinite(a) || !std::isfinite(b) || rel > tolerance) {
      ++c.bad;
      std::printf("  %s: %s %.17g, %s %.17g (rel %.3g > %.0e)\n", key.c_str(), ref_label.c_str(), a, label.c_str(), b,
                  rel, tolerance);
    }
    if (rel > c.worst) c.worst = rel, c.worst_name = key;
  }
  return c;
}

}  // namespace systole::test
