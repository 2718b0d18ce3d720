#include "proto/bridge/json_fields.h"

#include <algorithm>
#include <cctype>

#include <google/protobuf/util/json_util.h>
#include <nlohmann/json.hpp>

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

json known_fields_only(const json& object, const Descriptor& type, const std::string& path,
                       std::vector<std::string>& problems);

// A field's value with the unknown keys of the messages inside it removed (and reported).
json known_value(const FieldDescriptor& field, const json& value, const std::string& path,
                 std::vector<std::string>& problems) {
  const Descriptor* type = field.message_type();
  if (type == nullptr || is_well_known(*type)) return value;
  if (field.is_map()) {
    const Descriptor* value_type = type->map_value()->message_type();
    if (value_type == nullptr || is_well_known(*value_type) || !value.is_object()) return value;
    json out = json::object();
    for (auto it = value.begin(); it != value.end(); ++it)
      out[it.key()] = it.value().is_object()
                          ? known_fields_only(it.value(), *value_type, path + "." + it.key(), problems)
                          : it.value();
    return out;
  }
  if (field.is_repeated()) {
    if (!value.is_array()) return value;
    json out = json::array();
    for (std::size_t i = 0; i < value.size(); ++i)
      out.push_back(value[i].is_object()
                        ? known_fields_only(value[i], *type, path + "[" + std::to_string(i) + "]", problems)
                        : value[i]);
    return out;
  }
  return value.is_object() ? known_fields_only(value, *type, path, problems) : value;
}

// `object` without its unknown keys, each reported in `problems` with its path.
json known_fields_only(const json& object, const Descriptor& type, const std::string& path,
                       std::vector<std::string>& problems) {
  json out = json::object();
  for (auto it = object.begin(); it != object.end(); ++it) {
    const std::string at = path.empty() ? it.key() : path + "." + it.key();
    const FieldDescriptor* field = find_field(type, it.key());
    if (field == nullptr) {
      problems.push_back(unknown_field_message(at, it.key(), type));
      continue;
    }
    out[it.key()] = known_value(*field, it.value(), at, problems);
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
  const json known = known_fields_only(document, *message.GetDescriptor(), "", out.problems);
  google::protobuf::util::JsonParseOptions options;
  options.ignore_unknown_fields = false;  // none are left; a value of the wrong type is still an error
  const auto status = google::protobuf::util::JsonStringToMessage(known.dump(), &message, options);
  out.parsed = status.ok();
  if (!status.ok()) out.problems.push_back(readable(std::string(status.message())));
  return out;
}

}  // namespace systole::bridge
