#include "proto/bridge/json_fields.h"

#include <algorithm>
#include <cctype>
#include <optional>

#include <google/protobuf/util/json_util.h>
#include <nlohmann/json.hpp>

#include "solver/config/removed_fields.h"
#include "solver/core/nearest_names.h"

namespace systole::bridge {
namespace {

using google::protobuf::Descriptor;
using google::protobuf::FieldDescriptor;
using json = nlohmann::ordered_json;  // the document's order, for the messages

bool is_well_known(const Descriptor& type) { return type.file()->package() == "google.protobuf"; }

const FieldDescriptor* find_field(const Descriptor& type, const std::string& key) {
  if (const FieldDescriptor* f = type.FindFieldByName(key)) return f;
  for (int i = 0; i < type.field_count(); ++i)
    if (type.field(i)->json_name() == key) return type.field(i);
  return nullptr;
}

// "unknown field 'a.b'; did you mean 'c'? allowed: ..." (suggestions in the key's own style:
// lowerCamel json names for a key with capitals, field names otherwise).
std::string unknown_field_message(const std::string& path, const std::string& key, const Descriptor& type) {
  const bool camel = std::any_of(key.begin(), key.end(), [](char c) { return std::isupper(static_cast<unsigned char>(c)); });
  std::vector<std::string> names, styled;
  for (int i = 0; i < type.field_count(); ++i) {
    names.push_back(type.field(i)->name());
    styled.push_back(camel ? type.field(i)->json_name() : type.field(i)->name());
  }
  std::sort(names.begin(), names.end());
  return "unknown field '" + path + "'; " + did_you_mean(key, styled) + "allowed: " + join_names(names);
}

// A key's snake_case field name ("forcingKernel" -> "forcing_kernel"): a removed field has no
// descriptor left to give its json_name.
std::string snake_case(const std::string& key) {
  std::string out;
  for (char c : key) {
    if (std::isupper(static_cast<unsigned char>(c))) {
      out += '_';
      out += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    } else {
      out += c;
    }
  }
  return out;
}

// The message for an unknown key: a field of a systole.v1.Scenario that was removed or moved
// (solver/config/removed_fields.h) says so and why; any other gets the nearest allowed names.
// `scenario_path`: the key's path inside the nearest enclosing Scenario ("fsei.forcing_kernel"),
// empty outside one.
std::string unknown_key_message(const std::string& at, const std::string& key, const Descriptor& type,
                                 const std::string& scenario_path) {
  if (!scenario_path.empty())
    if (const config::RemovedField* gone = config::find_removed_field(scenario_path)) {
      const std::string m = config::removed_field_message(*gone);
      return at == gone->path ? m : at + ": " + m;
    }
  return unknown_field_message(at, key, type);
}

bool is_scenario(const Descriptor& type) { return type.full_name() == "systole.v1.Scenario"; }

json known_fields_only(const json& object, const Descriptor& type, const std::string& path,
                       const std::optional<std::string>& scenario_prefix, std::vector<std::string>& problems);

// A field's value with the unknown keys of the messages inside it removed (and reported).
// `scenario_path`: the field's path inside the enclosing Scenario, if any.
json known_value(const FieldDescriptor& field, const json& value, const std::string& path,
                 const std::optional<std::string>& scenario_path, std::vector<std::string>& problems) {
  const Descriptor* type = field.message_type();
  if (type == nullptr || is_well_known(*type)) return value;
  if (field.is_map()) {
    const Descriptor* value_type = type->map_value()->message_type();
    if (value_type == nullptr || is_well_known(*value_type) || !value.is_object()) return value;
    json out = json::object();
    for (auto it = value.begin(); it != value.end(); ++it)
      out[it.key()] = it.value().is_object()
                          ? known_fields_only(it.value(), *value_type, path + "." + it.key(), std::nullopt, problems)
                          : it.value();
    return out;
  }
  if (field.is_repeated()) {
    if (!value.is_array()) return value;
    json out = json::array();
    for (std::size_t i = 0; i < value.size(); ++i)
      out.push_back(value[i].is_object()
                        ? known_fields_only(value[i], *type, path + "[" + std::to_string(i) + "]", std::nullopt, problems)
                        : value[i]);
    return out;
  }
  return value.is_object() ? known_fields_only(value, *type, path, scenario_path, problems) : value;
}

// `object` without its unknown keys, each reported in `problems` with its path.
// `scenario_prefix`: the object's path inside the enclosing Scenario ("" for the Scenario
// itself), none outside one.
json known_fields_only(const json& object, const Descriptor& type, const std::string& path,
                       const std::optional<std::string>& scenario_prefix, std::vector<std::string>& problems) {
  const std::optional<std::string> prefix = is_scenario(type) ? std::optional<std::string>("") : scenario_prefix;
  json out = json::object();
  for (auto it = object.begin(); it != object.end(); ++it) {
    const std::string at = path.empty() ? it.key() : path + "." + it.key();
    const FieldDescriptor* field = find_field(type, it.key());
    std::optional<std::string> inside;
    if (prefix) {
      const std::string name = field != nullptr ? field->name() : snake_case(it.key());
      inside = prefix->empty() ? name : *prefix + "." + name;
    }
    if (field == nullptr) {
      problems.push_back(unknown_key_message(at, it.key(), type, inside.value_or("")));
      continue;
    }
    out[it.key()] = known_value(*field, it.value(), at, inside, problems);
  }
  return out;
}

// nlohmann's "[json.exception.parse_error.101] parse error at ...": without the bracketed id.
std::string without_exception_id(const std::string& what) {
  if (what.empty() || what[0] != '[') return what;
  const auto end = what.find("] ");
  return end == std::string::npos ? what : what.substr(end + 2);
}

// protobuf's "(a.b): invalid value ..." as "a.b: invalid value ...".
std::string readable(const std::string& protobuf_message) {
  const auto end = protobuf_message.find("): ");
  if (protobuf_message.empty() || protobuf_message[0] != '(' || end == std::string::npos) return protobuf_message;
  return protobuf_message.substr(1, end - 1) + protobuf_message.substr(end + 1);
}

}  // namespace

JsonParse parse_json_message(const std::string& text, google::protobuf::Message& message) {
  JsonParse out;
  json document;
  try {
    document = json::parse(text.empty() ? std::string("{}") : text);
  } catch (const json::parse_error& e) {
    out.problems.push_back("not valid JSON: " + without_exception_id(e.what()));
    return out;
  }
  if (!document.is_object()) {
    out.problems.push_back("the document must be a JSON object (a " + message.GetDescriptor()->full_name() +
                           "), got a JSON " + document.type_name());
    return out;
  }
  const json known = known_fields_only(document, *message.GetDescriptor(), "", std::nullopt, out.problems);
  google::protobuf::util::JsonParseOptions options;
  options.ignore_unknown_fields = false;  // none are left; a value of the wrong type is still an error
  const auto status = google::protobuf::util::JsonStringToMessage(known.dump(), &message, options);
  out.parsed = status.ok();
  if (!status.ok()) out.problems.push_back(readable(std::string(status.message())));
  return out;
}

}  // namespace systole::bridge
