#pragma once
// Error types shared by every layer. Contract: an InputError is the user's fault and its
// message names the field, the value and what is allowed; an InstabilityError is the
// solver's diagnosis of a run that blew up (module, place, time). Neither is ever swallowed.
#include <stdexcept>
#include <string>

namespace systole {

class InputError : public std::runtime_error {
 public:
  explicit InputError(const std::string& message) : std::runtime_error(message) {}
};

class InstabilityError : public std::runtime_error {
 public:
  InstabilityError(std::string module, std::string place, double time_s, const std::string& what);
  const std::string& module() const { return module_; }
  const std::string& place() const { return place_; }
  double time_s() const { return time_s_; }

 private:
  std::string module_;
  std::string place_;
  double time_s_;
};

}  // namespace systole
