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
  const std::map<std::string, std::vector<double>>& entries() const { return entries_; }

 private:
  std::map<std::string, std::vector<double>> entries_;
};

}  // namespace systole
