#include "solver/config/scenario.h"

#include <cmath>
#include <set>
#include <sstream>
#include <stdexcept>

#include "solver/config/fsei_rules.h"
#include "solver/config/geometry_rules.h"
#include "solver/config/parameter_table.h"
#include "solver/config/removed_fields.h"
#include "solver/core/errors.h"
#include "solver/core/nearest_names.h"

namespace systole::config {

const std::vector<std::string>& known_scenes() {
  static const std::vector<std::string> scenes{"lumped", "analytic", "geometry", "electro", "mechanics",
                                               "electromechanics", "fluid", "fsi", "fsei", "ibm"};
  return scenes;
}

// Updated as each scene lands (its issue); see solver/scene/.
const std::vector<std::string>& implemented_scenes() {
  static const std::vector<std::string> scenes{"lumped", "analytic", "fluid", "electro", "mechanics", "ibm",
                                                "electromechanics", "fsi", "fsei"};
  return scenes;
}

void check_mechanics_rules(const Scenario& s, std::vector<std::string>& errors) {
  const Structure& st = s.structure;
  if (st.protocol == "pv_relations") {
    if (st.body != "lv")
      errors.push_back("structure.protocol = \"pv_relations\" is not allowed with structure.body = \"" + st.body +
                       "\"; allowed body: lv");
    if (!(st.espvr_max_mmhg > st.espvr_min_mmhg) && st.active_tension_kpa > 0)
      errors.push_back("structure.espvr_max_mmhg = " + std::to_string(st.espvr_max_mmhg) +
                       " must exceed structure.espvr_min_mmhg = " + std::to_string(st.espvr_min_mmhg));
    if (st.edpvr_max_mmhg <= 0 && !(st.active_tension_kpa > 0))
      errors.push_back("structure.protocol = \"pv_relations\" has nothing to do: structure.edpvr_max_mmhg = 0 and "
                       "structure.active_tension_kpa = 0; set either");
  }
  if (st.walls == "chamber" && st.body != "lv" && st.body != "left_heart")
    errors.push_back("structure.walls = \"chamber\" is not allowed with structure.body = \"" + st.body +
                     "\"; allowed bodies: lv, left_heart (it builds the LV and LA walls as the coupled scenes do)");
}

namespace {

std::string show(const nlohmann::json& value) {
  std::string s = value.dump();
  if (s.size() > 80) s = s.substr(0, 77) + "...";
  return s;
}

bool is_integral(double v) { return std::isfinite(v) && std::floor(v) == v; }

bool in_range(const Param& p, double v) {
  if (!std::isfinite(v)) return false;
  if (p.min_exclusive ? !(v > p.min) : !(v >= p.min)) return false;
  if (p.max_exclusive ? !(v < p.max) : !(v <= p.max)) return false;
  return true;
}

// Stores `value` into the field described by `p`, or appends a message to `errors`.
void assign(const Param& p, const nlohmann::json& value, Scenario& s,
            std::vector<std::string>& errors) {
  const std::string field(p.path);
  auto out_of_range = [&](const nlohmann::json& v) {
    errors.push_back(field + " = " + show(v) + " is out of range " + describe_allowed(p));
  };
  switch (p.kind) {
    case Kind::kReal: {
      if (!value.is_number()) {
        errors.push_back(field + " = " + show(value) + " is not a number; allowed " +
                         describe_allowed(p));
        return;
      }
      const double v = value.get<double>();
      if (!in_range(p, v)) return out_of_range(value);
      p.real(s) = v;
      return;
    }
    case Kind::kInt: {
      if (!value.is_number() || !is_integral(value.get<double>())) {
        errors.push_back(field + " = " + show(value) + " is not an integer; allowed " +
                         describe_allowed(p));
        return;
      }
      const double v = value.get<double>();
      if (!in_range(p, v)) return out_of_range(value);
      p.integer(s) = static_cast<int>(v);
      return;
    }
    case Kind::kBool:
      if (!value.is_boolean()) {
        errors.push_back(field + " = " + show(value) + " is not a boolean; allowed true or false");
        return;
      }
      p.boolean(s) = value.get<bool>();
      return;
    case Kind::kChoice: {
      if (!value.is_string()) {
        errors.push_back(field + " = " + show(value) + " is not a string; allowed " +
                         describe_allowed(p));
        return;
      }
      const std::string v = value.get<std::string>();
      for (auto c : p.choices)
        if (c == v) {
          p.choice(s) = v;
          return;
        }
      errors.push_back("unknown " + field + " '" + v + "'; known: " +
                       describe_allowed(p).substr(std::string("one of: ").size()));
      return;
    }
    case Kind::kString:
      if (!value.is_string()) {
        errors.push_back(field + " = " + show(value) + " is not a string");
        return;
      }
      p.choice(s) = value.get<std::string>();
      return;
    case Kind::kRealList: {
      if (!value.is_array()) {
        errors.push_back(field + " = " + show(value) + " is not a list of numbers");
        return;
      }
      std::vector<double> list;
      for (const auto& e : value) {
        if (!e.is_number() || !in_range(p, e.get<double>())) {
          errors.push_back(field + " element " + show(e) + " is out of range " + describe_allowed(p));
          return;
        }
        list.push_back(e.get<double>());
      }
      p.real_list(s) = list;
      return;
    }
    case Kind::kChoiceList: {
      if (!value.is_array()) {
        errors.push_back(field + " = " + show(value) + " is not a list of strings");
        return;
      }
      std::vector<std::string> list;
      for (const auto& e : value) {
        bool ok = false;
        if (e.is_string())
          for (auto c : p.choices) ok = ok || c == e.get<std::string>();
        if (!ok) {
          errors.push_back(field + " element " + show(e) + " is not allowed; " + describe_allowed(p));
          return;
        }
        list.push_back(e.get<std::string>());
      }
      p.choice_list(s) = list;
      return;
    }
  }
}

// Known child names of an object path (sorted), for "unknown field" messages.
std::vector<std::string> child_names(const std::string& prefix) {
  std::set<std::string> names;
  for (const Param& p : parameter_table()) {
    std::string_view path = p.path;
    if (!prefix.empty()) {
      if (path.substr(0, prefix.size() + 1) != prefix + ".") continue;
      path.remove_prefix(prefix.size() + 1);
    }
    names.insert(std::string(path.substr(0, path.find('.'))));
  }
  return {names.begin(), names.end()};
}

std::string known_children(const std::string& prefix) { return join_names(child_names(prefix)); }

// "unknown field 'a.b'; did you mean 'c'? known fields of a: ..." (the suggestion only when
// a known name is near: nearest_names.h).
std::string unknown_field_message(const std::string& path, const std::string& prefix) {
  const std::string key = prefix.empty() ? path : path.substr(prefix.size() + 1);
  const std::vector<std::string> known = child_names(prefix);
  return "unknown field '" + path + "'; " + did_you_mean(key, known) + "known fields" +
         (prefix.empty() ? std::string("") : " of " + prefix) + ": " + join_names(known);
}

bool is_object_prefix(const std::string& path) {
  for (const Param& p : parameter_table())
    if (p.path.substr(0, path.size() + 1) == path + ".") return true;
  return false;
}

void walk(const nlohmann::json& node, const std::string& prefix, Scenario& s,
          std::vector<std::string>& errors) {
  for (auto it = node.begin(); it != node.end(); ++it) {
    const std::string path = prefix.empty() ? it.key() : prefix + "." + it.key();
    if (const Param* p = find_parameter(path)) {
      if (!it.value().is_null()) assign(*p, it.value(), s, errors);
    } else if (is_object_prefix(path)) {
      if (it.value().is_object())
        walk(it.value(), path, s, errors);
      else if (!it.value().is_null())
        errors.push_back(path + " = " + show(it.value()) + " must be an object with fields: " +
                         known_children(path));
    } else if (const RemovedField* removed = find_removed_field(path)) {
      errors.push_back(removed_field_message(*removed));
    } else {
      errors.push_back(unknown_field_message(path, prefix));
    }
  }
}

// Fluid rules (solver/fluid): the Carreau–Yasuda law must be shear thinning; scene "fluid"
// needs a case with a reference for it and a bounded number of time-series samples.
void check_fluid_rules(const Scenario& s, std::vector<std::string>& errors) {
  const Fluid& f = s.fluid;
  std::ostringstream m;
  if (f.viscosity_model == "carreau_yasuda" && f.carreau_yasuda_mu_inf_pa_s > f.carreau_yasuda_mu0_pa_s) {
    m << "fluid.carreau_yasuda_mu_inf_pa_s = " << f.carreau_yasuda_mu_inf_pa_s
      << " must not exceed fluid.carreau_yasuda_mu0_pa_s = " << f.carreau_yasuda_mu0_pa_s
      << " (the Carreau-Yasuda law is shear thinning)";
    errors.push_back(m.str());
    m.str("");
  }
  if (f.subgrid_model != "none" && f.viscosity_model != "newtonian")
    errors.push_back("fluid.subgrid_model = '" + f.subgrid_model + "' needs fluid.viscosity_model = newtonian, not '" +
                     f.viscosity_model + "' (the eddy viscosity adds to a constant molecular one)");
  if (s.scene != "fluid") return;
  if (f.viscosity_model == "carreau_yasuda" && f.verification_case != "poiseuille" && f.verification_case != "couette")
    errors.push_back("fluid.viscosity_model = 'carreau_yasuda' needs fluid.verification_case = poiseuille or couette "
                     "(the cases with a reference solution for it), not '" + f.verification_case + "'");
  const double samples = f.end_time_ms / s.outputs.time_series_interval_ms;
  if (samples > 100000) {
    m << "fluid.end_time_ms / outputs.time_series_interval_ms = " << f.end_time_ms << " / "
      << s.outputs.time_series_interval_ms << " = " << samples
      << " samples; allowed at most 100000: raise outputs.time_series_interval_ms";
    errors.push_back(m.str());
  }
}

// Scene electromechanics: the EP runs on the heart's walls, in whole steps per synchronisation step.
void check_electromechanics_rules(const Scenario& s, std::vector<std::string>& errors) {
  const double ratio = s.electromechanics.sync_step_ms / s.electro.time_step_ms;
  if (ratio < 1 - 1e-9 || std::abs(ratio - std::round(ratio)) > 1e-6 * ratio) {
    std::ostringstream m;
    m << "electromechanics.sync_step_ms = " << s.electromechanics.sync_step_ms
      << " ms must be a whole multiple of electro.time_step_ms = " << s.electro.time_step_ms << " ms";
    errors.push_back(m.str());
  }
  if (s.electro.mesh != "left_heart")
    errors.push_back("electro.mesh = \"" + s.electro.mesh +
                     "\" is not allowed in scene electromechanics; allowed: left_heart (the EP runs on the heart's walls)");
}

// Cross-field rules, after every field is individually in range.
void check_consistency(const Scenario& s, std::vector<std::string>& errors) {
  auto fail = [&](const std::string& m) { errors.push_back(m); };
  const double period_ms = s.period_ms();
  std::ostringstream m;
  if (s.av_delay_ms >= period_ms) {
    m << "av_delay_ms = " << s.av_delay_ms << " must be shorter than the cardiac period "
      << period_ms << " ms at heart_rate_bpm = " << s.heart_rate_bpm;
    fail(m.str());
    m.str("");
  }
  for (const auto& [name, c] : {std::pair{"lv", s.lumped.lv}, std::pair{"la", s.lumped.la}}) {
    if (c.emax_mmhg_per_ml <= c.emin_mmhg_per_ml) {
      m << "lumped." << name << ".emax_mmhg_per_ml = " << c.emax_mmhg_per_ml
        << " must exceed lumped." << name << ".emin_mmhg_per_ml = " << c.emin_mmhg_per_ml;
      fail(m.str());
      m.str("");
    }
    // Activation durations scale with sqrt(period / 857 ms) (solver/lumped, ours): the
    // scaled twitch must fit in one period.
    const double scale = std::sqrt(period_ms / (60000.0 / 70.0));
    const double twitch_ms = (c.contraction_ms + c.relaxation_ms) * scale;
    if (twitch_ms >= period_ms) {
      m << "lumped." << name << ".contraction_ms + relaxation_ms = "
        << c.contraction_ms + c.relaxation_ms << " ms (scaled to " << twitch_ms
        << " ms at heart_rate_bpm = " << s.heart_rate_bpm << ") must be shorter than the period "
        << period_ms << " ms";
      fail(m.str());
      m.str("");
    }
  }
  check_geometry_rules(s.geometry, errors);
  if (!s.outputs.field_phases.empty() && s.outputs.fields.empty())
    fail("outputs.field_phases is set but outputs.fields is empty: name the fields to write");
  if (s.electro.mesh == "manifest" && s.electro.mesh_manifest.empty())
    fail("electro.mesh = 'manifest' needs electro.mesh_manifest: the path of a mesh manifest (JSON) on the "
         "solver's machine");
  check_fluid_rules(s, errors);
  if (s.scene == "fsi" || s.scene == "fsei") check_fsei_rules(s, errors);
  if (s.scene == "electromechanics") check_electromechanics_rules(s, errors);
  if (s.scene == "mechanics") check_mechanics_rules(s, errors);
  // The membrane triangles carry eq 16's Fung energy only (ShellOptions::membrane).
  if (s.structure.membrane == "triangles") {
    if (s.structure.law != "fung")
      fail("structure.membrane = \"triangles\" takes structure.law = \"fung\" (the printed law); got \"" +
           s.structure.law + "\"");
    const bool walls = s.scene == "electromechanics" || s.scene == "fsi" || s.scene == "fsei" ||
                       (s.scene == "mechanics" && s.structure.walls == "chamber");
    if ((s.scene == "fsi" || s.scene == "fsei") && s.fsei.aorta.pretension == "prestress")
      fail("structure.membrane = \"triangles\" is not allowed with fsei.aorta.pretension = \"prestress\" (the "
           "pre-stress sets the springs' rest lengths, which the triangles do not use); allowed: \"outer_load\"");
    if (walls && s.electromechanics.spring_law != "fung")
      fail("structure.membrane = \"triangles\" takes electromechanics.spring_law = \"fung\" for the chamber walls; "
           "got \"" + s.electromechanics.spring_law + "\"");
  }
  bool implemented = false;
  for (const auto& n : implemented_scenes()) implemented = implemented || n == s.scene;
  if (!implemented) {
    std::string list;
    for (const auto& n : implemented_scenes()) list += (list.empty() ? "" : ", ") + n;
    fail("scene '" + s.scene + "' is not implemented yet; implemented: " + list);
  }
}

std::string join_errors(const std::vector<std::string>& errors) {
  std::string out = errors.size() == 1 ? "invalid scenario: " : "invalid scenario (" +
                                                                   std::to_string(errors.size()) +
                                                                   " problems):\n  ";
  for (size_t i = 0; i < errors.size(); ++i) out += (i ? "\n  " : "") + errors[i];
  return out;
}

// Scenes fsi/fsei take the calibrated layer unless the document asks for fsei.defaults = "seed"
// (a value that is not a known choice is reported by walk(); the layer does not matter then).
bool takes_fsei_calibrated_defaults(const nlohmann::json& document) {
  const auto scene = document.find("scene");
  if (scene == document.end() || !scene->is_string()) return false;
  if (*scene != "fsi" && *scene != "fsei") return false;
  const auto fsei = document.find("fsei");
  if (fsei == document.end() || !fsei->is_object()) return true;
  const auto choice = fsei->find("defaults");
  return choice == fsei->end() || !choice->is_string() || *choice != "seed";
}

}  // namespace

Scenario default_scenario() {
  Scenario s{};
  for (const Param& p : parameter_table()) {
    switch (p.kind) {
      case Kind::kReal: p.real(s) = p.default_number; break;
      case Kind::kInt: p.integer(s) = static_cast<int>(p.default_number); break;
      case Kind::kBool: p.boolean(s) = p.default_number != 0; break;
      case Kind::kChoice:
      case Kind::kString: p.choice(s) = std::string(p.default_choice); break;
      case Kind::kRealList: p.real_list(s).clear(); break;
      case Kind::kChoiceList: p.choice_list(s).clear(); break;
    }
  }
  return s;
}

namespace {

// parse_scenario's body: the scenario, with every problem appended to `errors`.
Scenario parse_collecting(const nlohmann::json& document, std::vector<std::string>& errors) {
  Scenario s = default_scenario();
  if (!document.is_object()) {
    errors.push_back("the document must be a JSON object, got " + show(document));
    return s;
  }
  if (takes_fsei_calibrated_defaults(document)) {
    nlohmann::json layer = nlohmann::json::object();
    const std::string scene = document.at("scene").get<std::string>();
    for (const SceneDefault& d : fsei_calibrated_defaults())
      if (d.scene.empty() || d.scene == scene) apply_override(layer, std::string(d.path) + "=" + std::string(d.value));
    walk(layer, "", s, errors);
    if (!errors.empty()) throw std::logic_error("fsei_calibrated_defaults(): " + join_errors(errors));
  }
  walk(document, "", s, errors);
  if (errors.empty()) check_consistency(s, errors);
  return s;
}

}  // namespace

Scenario parse_scenario(const nlohmann::json& document) {
  std::vector<std::string> errors;
  Scenario s = parse_collecting(document, errors);
  if (!errors.empty()) throw InputError(join_errors(errors));
  return s;
}

std::vector<std::string> scenario_problems(const nlohmann::json& document) {
  std::vector<std::string> errors;
  (void)parse_collecting(document, errors);
  return errors;
}

nlohmann::json to_json(const Scenario& scenario) {
  Scenario s = scenario;  // accessors take non-const references
  nlohmann::json out = nlohmann::json::object();
  for (const Param& p : parameter_table()) {
    std::string pointer_path = "/";  // built by appending: GCC 12's -Wrestrict misfires on "/" + string
    pointer_path += p.path;
    for (char& c : pointer_path)
      if (c == '.') c = '/';
    nlohmann::json::json_pointer ptr(pointer_path);
    switch (p.kind) {
      case Kind::kReal: out[ptr] = p.real(s); break;
      case Kind::kInt: out[ptr] = p.integer(s); break;
      case Kind::kBool: out[ptr] = p.boolean(s); break;
      case Kind::kChoice:
      case Kind::kString: out[ptr] = p.choice(s); break;
      case Kind::kRealList: out[ptr] = p.real_list(s); break;
      case Kind::kChoiceList: out[ptr] = p.choice_list(s); break;
    }
  }
  return out;
}

void apply_override(nlohmann::json& document, const std::string& assignment) {
  const auto eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0)
    throw InputError("--set '" + assignment + "': expected path.to.field=value");
  const std::string path = assignment.substr(0, eq);
  const std::string text = assignment.substr(eq + 1);
  const Param* p = find_parameter(path);
  if (p == nullptr) {
    if (const RemovedField* removed = find_removed_field(path)) throw InputError("--set: " + removed_field_message(*removed));
    const auto dot = path.rfind('.');
    const std::string prefix = dot == std::string::npos ? "" : path.substr(0, dot);
    if (prefix.empty() || is_object_prefix(prefix)) throw InputError("--set: " + unknown_field_message(path, prefix));
    std::vector<std::string> paths;
    for (const Param& q : parameter_table()) paths.emplace_back(q.path);
    throw InputError("--set: unknown field '" + path + "'; " + did_you_mean(path, paths) +
                     "known fields: " + known_children(""));
  }
  nlohmann::json value;
  auto number = [&](const std::string& t) -> nlohmann::json {
    try {
      size_t used = 0;
      const double v = std::stod(t, &used);
      if (used == t.size()) return is_integral(v) && p->kind == Kind::kInt ? nlohmann::json(static_cast<long long>(v)) : nlohmann::json(v);
    } catch (const std::exception&) {
    }
    return nlohmann::json(t);  // kept as text: parse_scenario reports the type error
  };
  auto split = [](const std::string& t) {
    std::vector<std::string> parts;
    std::string cur;
    std::istringstream in(t);
    while (std::getline(in, cur, ','))
      if (!cur.empty()) parts.push_back(cur);
    return parts;
  };
  switch (p->kind) {
    case Kind::kReal:
    case Kind::kInt: value = number(text); break;
    case Kind::kBool:
      value = text == "true" ? nlohmann::json(true)
              : text == "false" ? nlohmann::json(false)
                                : nlohmann::json(text);
      break;
    case Kind::kChoice:
    case Kind::kString: value = text; break;
    case Kind::kRealList:
      value = nlohmann::json::array();
      for (const auto& part : split(text)) value.push_back(number(part));
      break;
    case Kind::kChoiceList:
      value = nlohmann::json::array();
      for (const auto& part : split(text)) value.push_back(part);
      break;
  }
  std::string pointer = "/" + path;
  for (char& c : pointer)
    if (c == '.') c = '/';
  document[nlohmann::json::json_pointer(pointer)] = value;
}

}  // namespace systole::config
