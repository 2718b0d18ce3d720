#pragma once
// Latency summaries and Markdown helpers for service_bench.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <string>
#include <vector>

namespace systole::bench {

struct Summary {
  size_t n = 0;
  double mean = 0, p50 = 0, p90 = 0, p99 = 0, max = 0, min = 0, sum = 0;
};

// Nearest-rank percentiles.
inline Summary summarize(std::vector<double> v) {
  Summary s;
  s.n = v.size();
  if (v.empty()) return s;
  std::sort(v.begin(), v.end());
  auto pct = [&](double p) {
    const auto rank = static_cast<size_t>(std::ceil(p / 100.0 * static_cast<double>(v.size())));
    return v[std::clamp<size_t>(rank, 1, v.size()) - 1];
  };
  s.sum = std::accumulate(v.begin(), v.end(), 0.0);
  s.mean = s.sum / static_cast<double>(v.size());
  s.p50 = pct(50);
  s.p90 = pct(90);
  s.p99 = pct(99);
  s.max = v.back();
  s.min = v.front();
  return s;
}

inline std::string fmt(const char* format, double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, format, value);
  return buffer;
}
inline std::string f1(double v) { return fmt("%.1f", v); }
inline std::string f2(double v) { return fmt("%.2f", v); }
inline std::string f3(double v) { return fmt("%.3f", v); }

// "| p50 | p90 | p99 | max |" cells of a summary, in ms with 2 decimals.
inline std::string latency_cells(const Summary& s) {
  return f2(s.p50) + " | " + f2(s.p90) + " | " + f2(s.p99) + " | " + f2(s.max);
}

}  // namespace systole::bench
