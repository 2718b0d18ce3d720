#include "solver/core/nearest_names.h"

#include <algorithm>
#include <cctype>

namespace systole {
namespace {

char lower(char c) { return static_cast<char>(std::tolower(static_cast<unsigned char>(c))); }

// Optimal string alignment distance (Damerau-Levenshtein without repeated edits of a
// substring), case ignored.
std::size_t edit_distance(std::string_view a, std::string_view b) {
  const std::size_t n = a.size(), m = b.size();
  std::vector<std::vector<std::size_t>> d(n + 1, std::vector<std::size_t>(m + 1));
  for (std::size_t i = 0; i <= n; ++i) d[i][0] = i;
  for (std::size_t j = 0; j <= m; ++j) d[0][j] = j;
  for (std::size_t i = 1; i <= n; ++i)
    for (std::size_t j = 1; j <= m; ++j) {
      const std::size_t cost = lower(a[i - 1]) == lower(b[j - 1]) ? 0 : 1;
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
      if (i > 1 && j > 1 && lower(a[i - 1]) == lower(b[j - 2]) && lower(a[i - 2]) == lower(b[j - 1]))
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  return d[n][m];
}

// `longer` is `shorter` followed by a suffix that starts a new word ("_mm", "Ms").
bool extends(std::string_view longer, std::string_view shorter) {
  if (shorter.empty() || longer.size() <= shorter.size()) return false;
  for (std::size_t i = 0; i < shorter.size(); ++i)
    if (lower(longer[i]) != lower(shorter[i])) return false;
  const char next = longer[shorter.size()];
  return next == '_' || std::isupper(static_cast<unsigned char>(next));
}

}  // namespace

std::vector<std::string> nearest_names(std::string_view name, const std::vector<std::string>& allowed,
                                       std::size_t max_count) {
  const std::size_t limit = std::max<std::size_t>(1, name.size() / 4);
  struct Candidate {
    std::size_t distance, order;
  };
  std::vector<Candidate> near;
  for (std::size_t k = 0; k < allowed.size(); ++k) {
    const std::string& a = allowed[k];
    if (a == name) continue;
    const std::size_t distance = edit_distance(name, a);
    if (distance <= limit || extends(a, name) || extends(name, a)) near.push_back({distance, k});
  }
  std::stable_sort(near.begin(), near.end(),
                   [](const Candidate& x, const Candidate& y) { return x.distance < y.distance; });
  std::vector<std::string> out;
  for (const Candidate& c : near) {
    if (out.size() == max_count) break;
    if (std::find(out.begin(), out.end(), allowed[c.order]) == out.end()) out.push_back(allowed[c.order]);
  }
  return out;
}

std::string did_you_mean(std::string_view name, const std::vector<std::string>& allowed) {
  const std::vector<std::string> near = nearest_names(name, allowed);
  if (near.empty()) return "";
  std::string out = "did you mean ";
  for (std::size_t i = 0; i < near.size(); ++i)
    out += (i == 0 ? "" : i + 1 == near.size() ? " or " : ", ") + ("'" + near[i] + "'");
  return out + "? ";
}

std::string join_names(const std::vector<std::string>& names) {
  std::string out;
  for (const auto& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

}  // namespace systole
