#pragma once
// Suggestions for a misspelt name (a JSON key, a field path, a metric): the allowed names
// nearest to it. One rule for every "unknown ..." message (config, the REST gateway, campaign
// specs), so a user gets the same hints everywhere.
#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace systole {

// The names of `allowed` near `name`, nearest first (ties in the order of `allowed`), at most
// `max_count`. Near (ours): an edit distance (insertions, deletions, substitutions and swaps of
// neighbours, case ignored) of at most max(1, length / 4), or `name` with a unit suffix left
// off or added ("heart_rate" for "heart_rate_bpm").
std::vector<std::string> nearest_names(std::string_view name, const std::vector<std::string>& allowed,
                                       std::size_t max_count = 3);

// "did you mean 'a'? ", "did you mean 'a' or 'b'? ", or "" when no allowed name is near.
std::string did_you_mean(std::string_view name, const std::vector<std::string>& allowed);

// "a, b, c": the names joined for an "allowed: ..." list.
std::string join_names(const std::vector<std::string>& names);

}  // namespace systole
