#pragma once
// RunResult (solver) → systole.v1.Result (wire), at the worker's boundary.
#include "solver/core/run_result.h"
#include "systole/v1/service.pb.h"

namespace systole::worker {

inline v1::Result to_proto(const RunResult& result) {
  v1::Result out;
  for (const auto& [name, value] : result.metrics) (*out.mutable_metrics())[name] = value;
  for (size_t b = 0; b < result.beats.size(); ++b) {
    auto* beat = out.add_beats();
    beat->set_beat(static_cast<int>(b + 1));
    for (const auto& [name, value] : result.beats[b]) (*beat->mutable_metrics())[name] = value;
  }
  for (const auto& s : result.series) {
    auto* series = out.add_time_series();
    series->set_name(s.name);
    series->set_unit(s.unit);
    series->mutable_values()->Add(s.values.begin(), s.values.end());
  }
  return out;
}

}  // namespace systole::worker
