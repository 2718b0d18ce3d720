#pragma once
// The parameter table: every scenario field once, as data — path, kind, unit, default,
// allowed range or choices, documentation, and an accessor into config::Scenario.
// parse_scenario(), default_scenario(), to_json(), apply_override() and the generated
// docs/parameters.md all read this one table.
#include <string>
#include <string_view>
#include <vector>

#include "solver/config/scenario.h"

namespace systole::config {

// kString: free text (e.g. a server-side file path); stored through the `choice` accessor with
// its default in default_choice.
enum class Kind { kReal, kInt, kBool, kChoice, kRealList, kChoiceList, kString };

struct Param {
  std::string_view path;  // dotted, as in the proto/JSON: "tissue.lv.fung_c_pa"
  Kind kind;
  std::string_view unit;  // "" for nondimensional
  double default_number;  // kReal, kInt, kBool (0/1)
  double min, max;        // inclusive range for kReal, kInt and kRealList elements
  std::string_view default_choice;           // kChoice, kString
  std::vector<std::string_view> choices;     // kChoice, kChoiceList
  std::string_view doc;
  // Exactly the accessor matching `kind` is set.
  double& (*real)(Scenario&) = nullptr;
  int& (*integer)(Scenario&) = nullptr;
  bool& (*boolean)(Scenario&) = nullptr;
  std::string& (*choice)(Scenario&) = nullptr;  // kChoice and kString
  std::vector<double>& (*real_list)(Scenario&) = nullptr;
  std::vector<std::string>& (*choice_list)(Scenario&) = nullptr;
  // A range bound is open (exclusive) when this is set: e.g. field_phases in [0, 1).
  bool max_exclusive = false;
  bool min_exclusive = false;
};

// The table, in proto field order.
const std::vector<Param>& parameter_table();

// nullptr if no such path.
const Param* find_parameter(std::string_view path);

// Human-readable allowed values: "[20, 240]", "one of: loose, strong", ...
std::string describe_allowed(const Param& param);

// A scene's own default for one field (ours): `value` in apply_override's syntax ("true", "0.25",
// "divergence_free").
struct SceneDefault {
  std::string_view path;
  std::string_view value;
  std::string_view scene = {};  // the one scene it is for ("fsei"); empty: fsi and fsei
};

// Scenes fsi and fsei with fsei.defaults = calibrated: these replace the table's defaults before
// the scenario's own fields are read (parse_scenario), so a field the scenario sets always wins.
// An entry with a scene is that scene's only (a field the other scene does not use keeps the
// table's default there, and with it the other scene's checkpoint fingerprints).
const std::vector<SceneDefault>& fsei_calibrated_defaults();

// nullptr if the layer leaves `path` at the table's default.
const SceneDefault* find_fsei_calibrated_default(std::string_view path);

// Markdown reference of every parameter (docs/parameters.md).
std::string parameters_markdown();

}  // namespace systole::config
