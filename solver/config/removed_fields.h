#pragma once
// Scenario fields that no longer exist: removed (refuted or unused options) or moved to another
// path. One table, as data: the JSON walk (parse_scenario), --set (apply_override), the proto
// JSON check (proto/bridge/json_fields.cc), the checkpoint fingerprints of scenes fsi/fsei
// (solver/scene/fsei/checkpoint.cc) and docs/parameters.md all read it.
#include <string>
#include <string_view>
#include <vector>

namespace systole::config {

struct RemovedField {
  std::string_view path;      // the old dotted path, as a scenario named it: "fsei.forcing_kernel"
  std::string_view moved_to;  // its new path; empty: removed
  std::string_view why;       // why it was removed or moved (a fact, a test or a decision note)
  // Removed only: the one value every run used, as a checkpoint's fingerprint writes it ("1",
  // "false", "mean_edge"). A checkpoint written with it resumes (the field's behaviour is the
  // code's now); empty: the field had no such value.
  std::string_view only_value = {};
};

// Every removed and moved field, in the order they went.
const std::vector<RemovedField>& removed_fields();

// nullptr if `path` is not a removed or moved field.
const RemovedField* find_removed_field(std::string_view path);

// The error for a scenario that names the field: "fsei.forcing_row_sum_scaling was removed: <why>;
// remove it from the scenario" or "fsei.forcing_kernel moved to fsei.forcing.kernel (<why>);
// rename it in the scenario".
std::string removed_field_message(const RemovedField& field);

// Markdown table of the removed and moved fields (a section of docs/parameters.md).
std::string removed_fields_markdown();

}  // namespace systole::config
