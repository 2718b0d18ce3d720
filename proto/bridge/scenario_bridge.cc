#include "proto/bridge/scenario_bridge.h"

#include <fstream>
#include <sstream>

#include <google/protobuf/util/json_util.h>

#include "proto/bridge/json_fields.h"
#include "solver/core/errors.h"

namespace systole::bridge {

namespace {

std::string join_problems(const std::string& what, const std::vector<std::string>& problems) {
  std::string out = problems.size() == 1 ? what + ": " : what + " (" + std::to_string(problems.size()) + " problems):\n  ";
  for (std::size_t i = 0; i < problems.size(); ++i) out += (i ? "\n  " : "") + problems[i];
  return out;
}

}  // namespace

v1::Scenario scenario_proto_from_json_text(const std::string& json_text) {
  v1::Scenario message;
  JsonParse parse = parse_json_message(json_text, message);  // unknown fields are errors
  if (parse.problems.empty()) return message;
  // With only unknown keys the rest is checked too, so that one error lists every problem.
  if (parse.parsed)
    for (const auto& p : scenario_problems(message)) parse.problems.push_back(p);
  throw InputError(join_problems("invalid scenario JSON", parse.problems));
}

v1::Scenario load_scenario_file(const std::string& path, const std::vector<std::string>& overrides) {
  std::ifstream in(path);
  if (!in) throw InputError("cannot read scenario file '" + path + "'");
  std::stringstream buffer;
  buffer << in.rdbuf();
  nlohmann::json document;
  try {
    document = nlohmann::json::parse(buffer.str());
  } catch (const nlohmann::json::parse_error& e) {
    throw InputError("scenario file '" + path + "' is not valid JSON: " + e.what());
  }
  if (!document.is_object())
    throw InputError("scenario file '" + path + "' must hold a JSON object");
  for (const auto& assignment : overrides) config::apply_override(document, assignment);
  return scenario_proto_from_json_text(document.dump());
}

std::string to_json_text(const v1::Scenario& scenario) {
  google::protobuf::util::JsonPrintOptions options;
  options.preserve_proto_field_names = true;
  std::string text;
  const auto status = google::protobuf::util::MessageToJsonString(scenario, &text, options);
  if (!status.ok()) throw InputError("cannot print scenario: " + std::string(status.message()));
  return text;
}

config::Scenario validate(const v1::Scenario& scenario) {
  return config::parse_scenario(nlohmann::json::parse(to_json_text(scenario)));
}

std::vector<std::string> scenario_problems(const v1::Scenario& scenario) {
  return config::scenario_problems(nlohmann::json::parse(to_json_text(scenario)));
}

}  // namespace systole::bridge
