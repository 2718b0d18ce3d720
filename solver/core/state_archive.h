#pragma once
// A checkpoint's content in memory: named arrays of doubles, each module writing its evolving
// state under its own prefix ("fluid/", "shell/lv/", "ep/", ...). The scene stores an archive
// in one file and a restored module reads back exactly what it wrote, so a continued run can
// equal a straight run bitwise.
//
// Contract
// - put() replaces an entry of the same name; entries() is sorted by name.
// - get(name, size) returns the array; it throws InputError naming the checkpoint entry when it
//   is missing or, with size >= 0, when its length differs (a checkpoint of another scenario).
// - Integers (counters, flags, indices) go through doubles: exact up to 2^53.
#include <cstddef>
#include <map>
#include <string>
#include <vector>

#include "solver/core/errors.h"

namespace systole {

class StateArchive {
 public:
  void put(const std::string& name, std::vector<double> values) { entries_[name] = std::move(values); }
  void put_scalar(const std::string& name, double value) { entries_[name] = {value}; }
  bool has(const std::string& name) const { return entries_.count(name) > 0; }
  const std::vector<double>& get(const std::string& name, long expected_size = -1) const {
    const auto it = entries_.find(name);
    if (it == entries_.end()) throw InputError("checkpoint: entry '" + name + "' is missing");
    if (expected_size >= 0 && it->second.size() != static_cast<std::size_t>(expected_size))
      throw InputError("checkpoint: entry '" + name + "' has " + std::to_string(it->second.size()) +
                       " values, this run needs " + std::to_string(expected_size) +
                       " (a checkpoint of another scenario or mesh)");
    return it->second;
  }
  double scalar(const std::string& name) const { return get(name, 1)[0]; }
  // Arrays of 3-vectors (any type with v[0..2] and a (x, y, z) constructor), stored flat.
  template <class V>
  void put_vectors(const std::string& name, const std::vector<V>& v) {
    std::vector<double> flat(3 * v.size());
    for (std::size_t i = 0; i < v.size(); ++i)
      for (std::size_t c = 0; c < 3; ++c) flat[3 * i + c] = v[i][static_cast<int>(c)];
    put(name, std::move(flat));
  }
  // expected_count >= 0: the number of vectors this run needs (InputError otherwise, as get()).
  template <class V>
  std::vector<V> get_vectors(const std::string& name, long expected_count = -1) const {
    const std::vector<double>& d = get(name, expected_count >= 0 ? 3 * expected_count : -1);
    std::vector<V> out;
    out.reserve(d.size() / 3);
    for (std::size_t i = 0; i + 2 < d.size(); i += 3) out.emplace_back(d[i], d[i + 1], d[i + 2]);
    return out;
  }
  const std::map<std::string, std::vector<double>>& entries() const { return entries_; }

 private:
  std::map<std::string, std::vector<double>> entries_;
};

}  // namespace systole
