#include "solver/core/errors.h"

#include <sstream>

namespace systole {

namespace {
std::string describe(const std::string& module, const std::string& place, double time_s,
                     const std::string& what) {
  std::ostringstream out;
  out << "unstable run in module '" << module << "' at " << place << ", t = " << time_s
      << " s: " << what;
  return out.str();
}
}  // namespace

InstabilityError::InstabilityError(std::string module, std::string place, double time_s,
                                   const std::string& what)
    : std::runtime_error(describe(module, place, time_s, what)),
      module_(std::move(module)),
      place_(std::move(place)),
      time_s_(time_s) {}

}  // namespace systole
