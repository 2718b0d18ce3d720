#pragma once
// proto3 JSON in, with every problem named at once. protobuf's own parser stops at the first
// unknown key and names no alternative; these walk the document against the message's
// descriptor first, so a body with three misspelt keys gets three messages, each with the
// key's full path, the nearest allowed names (solver/core/nearest_names.h) and all of them.
// Used by the REST gateway, scenario files (scenario_bridge.h) and the CLI's campaign specs.
#include <string>
#include <vector>

#include <google/protobuf/message.h>

namespace systole::bridge {

// What parse_json_message() found.
struct JsonParse {
  std::vector<std::string> problems;  // one message per problem; empty: parsed and nothing unknown
  bool parsed = false;                // the message holds every known field of the document
};

// proto3 JSON text → `message` ("" is {}), collecting problems instead of stopping at the first:
// malformed JSON or a document that is not an object (then nothing else), every unknown key at
// any depth, in the document's order (proto3 JSON accepts a field's name and its lowerCamel
// json_name; message fields, repeated messages and maps of messages are walked, protobuf's
// well-known types left to protobuf), and protobuf's first error on the document without those
// keys (a value of the wrong type). With only unknown keys, `parsed` is true and the caller can
// check the rest of the message to report its problems in the same error.
JsonParse parse_json_message(const std::string& text, google::protobuf::Message& message);

}  // namespace systole::bridge
