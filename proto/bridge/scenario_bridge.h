#pragma once
// The one place where the wire format (systole.v1.Scenario, proto3 JSON) meets the solver's
// typed, validated config::Scenario. The CLI, the server and the worker all go through here,
// so a scenario is validated by the same code everywhere.
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "solver/config/scenario.h"
#include "systole/v1/scenario.pb.h"

namespace systole::bridge {

// proto3 JSON text → message. Throws one InputError listing every unknown field (with its
// nearest allowed names, json_fields.h), a type error, and the scenario's other problems.
v1::Scenario scenario_proto_from_json_text(const std::string& json_text);

// Reads a scenario file, applies `path=value` overrides (config::apply_override), and parses
// it into the wire message. Throws InputError (file missing, malformed JSON, unknown field...).
v1::Scenario load_scenario_file(const std::string& path, const std::vector<std::string>& overrides);

// Wire message → validated config (defaults applied, every range and rule checked).
config::Scenario validate(const v1::Scenario& scenario);

// What validate() would throw, one message per problem (config::scenario_problems); empty
// for a valid scenario.
std::vector<std::string> scenario_problems(const v1::Scenario& scenario);

// Message → compact JSON with proto field names (snake_case); unset fields omitted.
std::string to_json_text(const v1::Scenario& scenario);

}  // namespace systole::bridge
