#include "solver/electro/ionic/cell_model.h"

#include <sstream>

#include "solver/core/errors.h"
#include "solver/electro/ionic/models.h"

namespace systole::electro::ionic {

CellModel::CellModel(std::size_t nodes, std::vector<ParamInfo> params)
    : nodes_(nodes), params_(std::move(params)) {}

void CellModel::allocate_state() {
  state_.assign(state_names().size(), std::vector<double>(nodes_, 0.0));
  reset();
}

void CellModel::reset() {
  const std::vector<double> init = initial_state();
  for (std::size_t k = 0; k < state_.size(); ++k) state_[k].assign(nodes_, init[k]);
}

double CellModel::parameter(std::string_view name) const {
  for (const ParamInfo& q : params_)
    if (q.name == name) return q.value;
  std::ostringstream os;
  os << "cell model '" << this->name() << "' has no parameter '" << name << "'; known:";
  for (const ParamInfo& q : params_) os << ' ' << q.name;
  throw InputError(os.str());
}

void CellModel::set_parameter(std::string_view name, double value) {
  for (ParamInfo& q : params_) {
    if (q.name == name) {
      q.value = value;
      on_parameters_changed();
      reset();
      return;
    }
  }
  (void)parameter(name);  // throws the listing error
}

std::size_t CellModel::state_index(std::string_view name) const {
  const std::vector<std::string> names = state_names();
  for (std::size_t k = 0; k < names.size(); ++k)
    if (names[k] == name) return k;
  std::ostringstream os;
  os << "cell model '" << this->name() << "' has no state '" << name << "'; known:";
  for (const auto& n : names) os << ' ' << n;
  throw InputError(os.str());
}

const std::vector<std::string>& cell_model_names() {
  static const std::vector<std::string> names{"aliev_panfilov", "mitchell_schaeffer", "fhn",      "fhn_atrial",
                                              "ttp06",          "ttp06_endo",         "ttp06_mid", "ttp06_epi"};
  return names;
}

std::unique_ptr<CellModel> make_cell_model(std::string_view name, std::size_t nodes) {
  if (name == "aliev_panfilov") return make_aliev_panfilov(nodes);
  if (name == "mitchell_schaeffer") return make_mitchell_schaeffer(nodes);
  if (name == "fhn") return make_fitzhugh_nagumo(nodes);
  if (name == "fhn_atrial") return make_fitzhugh_nagumo_atrial(nodes);
  if (name == "ttp06" || name == "ttp06_epi") return make_ttp06(nodes, Ttp06Cell::kEpi);
  if (name == "ttp06_endo") return make_ttp06(nodes, Ttp06Cell::kEndo);
  if (name == "ttp06_mid") return make_ttp06(nodes, Ttp06Cell::kMid);
  std::ostringstream os;
  os << "unknown cell model '" << name << "'; known:";
  for (const auto& n : cell_model_names()) os << ' ' << n;
  throw InputError(os.str());
}

}  // namespace systole::electro::ionic
