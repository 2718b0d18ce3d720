#include "service/server/campaign_service.h"

#include <cmath>
#include <set>
#include <sstream>
#include <thread>

#include <google/protobuf/util/json_util.h>
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include "proto/bridge/scenario_bridge.h"
#include "solver/config/parameter_table.h"
#include "solver/core/errors.h"
#include "solver/core/nearest_names.h"
#include "solver/scene/scene.h"
#include "uq/distributions.h"
#include "uq/sampling.h"
#include "uq/sensitivity.h"
#include "uq/statistics.h"

namespace systole::service {
namespace {

using grpc::StatusCode;
using nlohmann::json;

std::string to_json_text(const google::protobuf::Message& message) {
  google::protobuf::util::JsonPrintOptions options;
  options.preserve_proto_field_names = true;
  std::string text;
  (void)google::protobuf::util::MessageToJsonString(message, &text, options);
  return text;
}

v1::CampaignSpec spec_from_json(const std::string& text) {
  v1::CampaignSpec spec;
  google::protobuf::util::JsonParseOptions options;
  options.ignore_unknown_fields = true;
  const auto status = google::protobuf::util::JsonStringToMessage(text, &spec, options);
  if (!status.ok()) throw ServiceError(StatusCode::INTERNAL, "stored campaign spec is corrupt");
  return spec;
}

std::string number(double v) {
  std::ostringstream out;
  out << v;
  return out.str();
}

// The distribution of parameters[i], or a message naming what is wrong.
uq::Distribution make_distribution(const v1::UncertainParameter& p, const std::string& where) {
  try {
    switch (p.distribution_case()) {
      case v1::UncertainParameter::kUniform: return uq::Distribution::uniform(p.uniform().min(), p.uniform().max());
      case v1::UncertainParameter::kNormal: return uq::Distribution::normal(p.normal().mean(), p.normal().std());
      case v1::UncertainParameter::kLognormal:
        return uq::Distribution::lognormal(p.lognormal().log_mean(), p.lognormal().log_std());
      case v1::UncertainParameter::kTruncatedNormal:
        return uq::Distribution::truncated_normal(p.truncated_normal().mean(), p.truncated_normal().std(),
                                                  p.truncated_normal().min(), p.truncated_normal().max());
      case v1::UncertainParameter::DISTRIBUTION_NOT_SET: break;
    }
  } catch (const std::invalid_argument& e) {
    throw InputError(where + ": " + e.what());
  }
  throw InputError(where + ": no distribution; give one of uniform, normal, lognormal, truncated_normal");
}

bool support_inside(const uq::Support& s, const config::Param& p) {
  const bool lo_ok = p.min_exclusive ? s.lo > p.min : s.lo >= p.min;
  const bool hi_ok = p.max_exclusive ? s.hi < p.max : s.hi <= p.max;
  return lo_ok && hi_ok;
}

uq::DesignKind design_kind(v1::Design design) {
  switch (design) {
    case v1::MONTE_CARLO: return uq::DesignKind::monte_carlo;
    case v1::SOBOL: return uq::DesignKind::sobol;
    case v1::SALTELLI: return uq::DesignKind::saltelli;
    default: return uq::DesignKind::latin_hypercube;
  }
}

void set_path(json& doc, const std::string& path, double value) {
  std::string pointer = "/" + path;
  for (char& c : pointer)
    if (c == '.') c = '/';
  doc[json::json_pointer(pointer)] = value;
}

std::optional<double> metric_of(const std::string& metrics_json, const std::string& name) {
  if (metrics_json.empty()) return std::nullopt;
  const json doc = json::parse(metrics_json, nullptr, false);
  if (!doc.is_object() || !doc.contains("metrics") || !doc["metrics"].contains(name)) return std::nullopt;
  const json& v = doc["metrics"][name];
  if (!v.is_number()) return std::nullopt;
  const double x = v.get<double>();
  return std::isfinite(x) ? std::optional<double>(x) : std::nullopt;
}

v1::JobState job_state(store::JobState s) {
  switch (s) {
    case store::JobState::kQueued: return v1::QUEUED;
    case store::JobState::kRunning: return v1::RUNNING;
    case store::JobState::kSucceeded: return v1::SUCCEEDED;
    case store::JobState::kFailed: return v1::FAILED;
    case store::JobState::kCancelled: return v1::CANCELLED;
  }
  return v1::JOB_STATE_UNSPECIFIED;
}

v1::Interval interval(const uq::IndexEstimate& e) {
  v1::Interval out;
  out.set_estimate(e.value);
  out.set_low(e.ci_low);
  out.set_high(e.ci_high);
  return out;
}

// A campaign spec, checked: its base scenario and each parameter's distribution, or every
// problem, each naming the offending field (and, for a misspelt name, the nearest known ones).
struct CheckedSpec {
  config::Scenario base;
  std::vector<uq::Distribution> distributions;
  std::vector<std::string> problems;
};

// The base scenario, or its problems (each prefixed with base_scenario).
void check_base_scenario(const v1::CampaignSpec& spec, CheckedSpec& out) {
  const std::vector<std::string> base = bridge::scenario_problems(spec.base_scenario());
  for (const auto& p : base) out.problems.push_back("base_scenario: " + p);
  if (base.empty()) out.base = bridge::validate(spec.base_scenario());
}

// Each uncertain parameter: a real-valued scenario field, once, with a distribution inside its range.
void check_parameters(const v1::CampaignSpec& spec, CheckedSpec& out) {
  auto add = [&](const std::string& m) { out.problems.push_back(m); };
  const int d = spec.parameters_size();
  if (d == 0) add("parameters: at least one uncertain parameter is required");
  std::set<std::string> seen;
  for (int i = 0; i < d; ++i) {
    const auto& p = spec.parameters(i);
    const std::string where = "parameters[" + std::to_string(i) + "] (" + p.path() + ")";
    const config::Param* field = config::find_parameter(p.path());
    if (field == nullptr) {
      std::vector<std::string> real_fields;
      for (const config::Param& q : config::parameter_table())
        if (q.kind == config::Kind::kReal) real_fields.emplace_back(q.path);
      add("parameters[" + std::to_string(i) + "].path '" + p.path() + "' is not a scenario field; " +
          did_you_mean(p.path(), real_fields) + "(see docs/parameters.md)");
      continue;
    }
    if (field->kind != config::Kind::kReal) {
      add(where + ": only real-valued fields can be uncertain; this one is " + config::describe_allowed(*field));
      continue;
    }
    if (!seen.insert(p.path()).second) add(where + ": the same field appears twice");
    try {
      uq::Distribution dist = make_distribution(p, where);
      const uq::Support sup = dist.support();
      if (!support_inside(sup, *field))
        add(where + ": " + dist.describe() + " has support [" + number(sup.lo) + ", " + number(sup.hi) +
            "], outside the allowed range " + config::describe_allowed(*field) + " of " + p.path() +
            "; narrow it or use truncated_normal");
      out.distributions.push_back(dist);
    } catch (const InputError& e) {
      add(e.what());
    }
  }
}

// The sample counts, the design's limits, the bootstrap and the priority.
void check_sizes(const v1::CampaignSpec& spec, const CampaignLimits& limits, CheckedSpec& out) {
  auto add = [&](const std::string& m) { out.problems.push_back(m); };
  const int d = spec.parameters_size();
  if (spec.samples() < 1 || spec.samples() > limits.max_samples)
    add("samples = " + std::to_string(spec.samples()) + " is out of range [1, " + std::to_string(limits.max_samples) + "]");
  const uq::DesignKind kind = design_kind(spec.design());
  if (kind == uq::DesignKind::saltelli) {
    if (spec.samples() == 1) add("samples = 1: the SALTELLI design needs at least 2 base samples");
    if (2 * d > static_cast<int>(uq::kSobolMaxDimensions))
      add("SALTELLI with " + std::to_string(d) + " parameters needs " + std::to_string(2 * d) +
          " Sobol' dimensions; at most " + std::to_string(uq::kSobolMaxDimensions / 2) + " parameters");
  }
  const long long jobs_total = kind == uq::DesignKind::saltelli ? static_cast<long long>(spec.samples()) * (d + 2)
                                                                 : spec.samples();
  if (jobs_total > limits.max_jobs)
    add("the campaign would run " + std::to_string(jobs_total) + " jobs; at most " + std::to_string(limits.max_jobs));
  if (spec.bootstrap_resamples() < 0 || spec.bootstrap_resamples() > 100000)
    add("bootstrap_resamples = " + std::to_string(spec.bootstrap_resamples()) + " is out of range [0, 100000]");
  if (spec.priority() < store::JobStore::kMinPriority || spec.priority() > store::JobStore::kMaxPriority)
    add("priority = " + std::to_string(spec.priority()) + " is out of range [-1000, 1000]");
}

// Each quantity of interest: a metric of the base scenario's scene (when that scene exists).
void check_quantities(const v1::CampaignSpec& spec, CheckedSpec& out) {
  if (spec.quantities_of_interest_size() == 0)
    out.problems.push_back("quantities_of_interest: name at least one metric, e.g. ejection_fraction_percent");
  const std::string scene =
      spec.base_scenario().has_scene() ? spec.base_scenario().scene() : config::default_scenario().scene;
  const auto& implemented = config::implemented_scenes();
  if (std::find(implemented.begin(), implemented.end(), scene) == implemented.end()) return;  // base_scenario says so
  const auto& known = scene::metric_names(scene);
  for (int i = 0; i < spec.quantities_of_interest_size(); ++i) {
    const std::string& q = spec.quantities_of_interest(i);
    if (std::find(known.begin(), known.end(), q) == known.end())
      out.problems.push_back("quantities_of_interest[" + std::to_string(i) + "] '" + q + "' is not a metric of scene '" +
                             scene + "'; " + did_you_mean(q, known) + "known: " + join_names(known));
  }
}

CheckedSpec check_spec(const v1::CampaignSpec& spec, const CampaignLimits& limits) {
  CheckedSpec out;
  check_base_scenario(spec, out);
  check_parameters(spec, out);
  check_sizes(spec, limits, out);
  check_quantities(spec, out);
  return out;
}

}  // namespace

CampaignService::CampaignService(store::JobStore& store, ChangeNotifier& notifier, ServiceOptions options,
                                 CampaignLimits limits)
    : store_(store), notifier_(notifier), options_(std::move(options)), limits_(limits) {}

std::vector<std::string> CampaignService::problems(const v1::SubmitCampaignRequest& request) const {
  if (!request.has_spec()) return {"spec is required"};
  return check_spec(request.spec(), limits_).problems;
}

v1::SubmitCampaignResponse CampaignService::submit(const v1::SubmitCampaignRequest& request) {
  if (!request.has_spec()) throw ServiceError(StatusCode::INVALID_ARGUMENT, "spec is required");
  const v1::CampaignSpec& spec = request.spec();
  CheckedSpec checked = check_spec(spec, limits_);
  if (!checked.problems.empty()) {
    const auto& errors = checked.problems;
    std::string message = errors.size() == 1 ? "invalid campaign: " : "invalid campaign (" + std::to_string(errors.size()) + " problems):\n  ";
    for (size_t i = 0; i < errors.size(); ++i) message += (i ? "\n  " : "") + errors[i];
    throw InputError(message);
  }
  const config::Scenario& base = checked.base;
  const std::vector<uq::Distribution>& distributions = checked.distributions;
  const int d = spec.parameters_size();
  const uq::DesignKind kind = design_kind(spec.design());

  // The design, in the unit cube, then mapped through each distribution's quantile.
  uq::Matrix unit;
  if (kind == uq::DesignKind::saltelli) {
    unit = uq::saltelli(static_cast<size_t>(spec.samples()), static_cast<size_t>(d), spec.seed()).points;
  } else {
    unit = uq::unit_design(kind, static_cast<size_t>(spec.samples()), static_cast<size_t>(d), spec.seed());
  }
  const uq::Matrix physical = uq::to_physical(unit, distributions);

  const json base_json = json::parse(bridge::to_json_text(spec.base_scenario()));
  std::vector<store::NewJob> jobs;
  std::vector<std::string> inputs;
  jobs.reserve(physical.rows());
  int invalid = 0;
  for (size_t r = 0; r < physical.rows(); ++r) {
    json doc = base_json;
    json row = json::object();
    for (int c = 0; c < d; ++c) {
      set_path(doc, spec.parameters(c).path(), physical(r, static_cast<size_t>(c)));
      row[spec.parameters(c).path()] = physical(r, static_cast<size_t>(c));
    }
    store::NewJob job;
    job.scene = base.scene;
    job.priority = spec.priority();
    job.max_attempts = options_.default_max_attempts;
    const v1::Scenario message = bridge::scenario_proto_from_json_text(doc.dump());
    job.scenario_json = bridge::to_json_text(message);
    try {
      // A draw that breaks a cross-field rule still becomes a job: the worker rejects it and the
      // sample is reported FAILED with the message (not fatal to the campaign).
      const config::Scenario sample = bridge::validate(message);
      if (!spec.no_cache()) job.cache_key = cache_key(sample);
    } catch (const InputError&) {
      ++invalid;
    }
    jobs.push_back(std::move(job));
    inputs.push_back(row.dump());
  }
  const auto outcome = store_.create_campaign(request.request_id(), to_json_text(spec), jobs, inputs, now_ms());
  if (outcome.created) {
    notifier_.notify();
    spdlog::info("campaign {}: {} jobs ({} design, {} parameters, {} cached, {} draws violate a rule)",
                 outcome.campaign.id, outcome.campaign.jobs_total, uq::to_string(kind), d,
                 outcome.campaign.jobs_cached, invalid);
  }
  v1::SubmitCampaignResponse response;
  *response.mutable_campaign() = campaign_proto(outcome.campaign);
  response.set_created(outcome.created);
  return response;
}

store::CampaignRecord CampaignService::require(const std::string& id) {
  if (id.empty()) throw ServiceError(StatusCode::INVALID_ARGUMENT, "id is required");
  auto record = store_.get_campaign(id);
  if (!record) throw ServiceError(StatusCode::NOT_FOUND, "campaign '" + id + "' not found");
  return *record;
}

v1::Campaign CampaignService::campaign_proto(const store::CampaignRecord& r) const {
  v1::Campaign c;
  c.set_id(r.id);
  c.set_request_id(r.request_id);
  *c.mutable_spec() = spec_from_json(r.spec_json);
  c.set_created_ms(r.created_ms);
  c.set_jobs_total(static_cast<int>(r.jobs_total));
  c.set_jobs_cached(static_cast<int>(r.jobs_cached));
  c.set_cancelled(r.cancelled);
  int64_t terminal = 0;
  for (const auto& [state, n] : r.jobs_by_state) {
    (*c.mutable_jobs_by_state())[std::string(store::to_string(state))] = static_cast<int>(n);
    if (store::is_terminal(state)) terminal += n;
  }
  c.set_finished(terminal == r.jobs_total);
  return c;
}

v1::CampaignStatistics CampaignService::statistics(const v1::CampaignSpec& spec,
                                                   const std::vector<store::CampaignSampleRow>& rows) const {
  v1::CampaignStatistics out;
  const size_t n = rows.size();
  const size_t d = static_cast<size_t>(spec.parameters_size());
  out.set_samples_total(static_cast<int>(n));
  uq::Matrix inputs(n, d, std::nan(""));
  int succeeded = 0, failed = 0;
  for (size_t r = 0; r < n; ++r) {
    const json in = json::parse(rows[r].inputs_json, nullptr, false);
    for (size_t c = 0; c < d; ++c)
      if (in.is_object() && in.contains(spec.parameters(static_cast<int>(c)).path()))
        inputs(r, c) = in[spec.parameters(static_cast<int>(c)).path()].get<double>();
    if (rows[r].state == store::JobState::kSucceeded) ++succeeded;
    if (rows[r].state == store::JobState::kFailed || rows[r].state == store::JobState::kCancelled) {
      ++failed;
      auto* f = out.add_failed();
      f->set_index(static_cast<int>(rows[r].index));
      f->set_job_id(rows[r].job_id);
      f->set_state(job_state(rows[r].state));
      f->set_error(rows[r].error);
    }
  }
  out.set_samples_succeeded(succeeded);
  out.set_samples_failed(failed);
  const bool saltelli = spec.design() == v1::SALTELLI;
  std::optional<uq::SaltelliLayout> layout;
  if (saltelli && d > 0 && n == static_cast<size_t>(spec.samples()) * (d + 2))
    layout.emplace(static_cast<size_t>(spec.samples()), d);
  const int resamples = spec.bootstrap_resamples() == 0 ? 200 : spec.bootstrap_resamples();
  out.set_confidence_level(0.95);

  for (const std::string& name : spec.quantities_of_interest()) {
    std::vector<std::optional<double>> y(n);
    for (size_t r = 0; r < n; ++r)
      if (rows[r].state == store::JobState::kSucceeded) y[r] = metric_of(rows[r].metrics_json, name);
    // Means, percentiles and correlations use independent draws: every sample, or with
    // SALTELLI only the A and B blocks.
    std::vector<size_t> use;
    for (size_t r = 0; r < n; ++r)
      if (!layout || layout->is_base_evaluation(r)) use.push_back(r);
    std::vector<std::optional<double>> y_use;
    for (size_t r : use) y_use.push_back(y[r]);
    const uq::QoiSummary s = uq::summarize(std::span<const std::optional<double>>(y_use));
    auto* q = out.add_qoi();
    q->set_name(name);
    q->set_samples_used(static_cast<int>(s.used));
    q->set_mean(s.mean);
    q->set_std(s.std_dev);
    if (s.percentiles.size() == 5) {
      q->mutable_percentiles()->set_p5(s.percentiles[0].value);
      q->mutable_percentiles()->set_p25(s.percentiles[1].value);
      q->mutable_percentiles()->set_p50(s.percentiles[2].value);
      q->mutable_percentiles()->set_p75(s.percentiles[3].value);
      q->mutable_percentiles()->set_p95(s.percentiles[4].value);
    }
    for (double e : s.histogram.edges) q->mutable_histogram()->add_edges(e);
    for (size_t c : s.histogram.counts) q->mutable_histogram()->add_counts(static_cast<int>(c));
    // Correlations over the samples with a value.
    std::vector<size_t> finite;
    for (size_t r : use)
      if (y[r]) finite.push_back(r);
    std::vector<uq::Correlation> correlations(d);
    if (finite.size() >= 3) {
      uq::Matrix x(finite.size(), d);
      std::vector<double> v(finite.size());
      for (size_t k = 0; k < finite.size(); ++k) {
        for (size_t c = 0; c < d; ++c) x(k, c) = inputs(finite[k], c);
        v[k] = *y[finite[k]];
      }
      correlations = uq::input_correlations(x, v);
    }
    std::optional<uq::SobolIndices> sobol;
    if (layout) {
      uq::SobolIndicesOptions options;
      options.bootstrap_resamples = static_cast<size_t>(resamples);
      options.seed = spec.seed();
      sobol = uq::sobol_indices(*layout, std::span<const std::optional<double>>(y), options);
      out.set_sobol_rows_used(static_cast<int>(sobol->rows_used));
    }
    for (size_t c = 0; c < d; ++c) {
      auto* p = q->add_sensitivities();
      p->set_path(spec.parameters(static_cast<int>(c)).path());
      p->set_pearson(correlations[c].pearson);
      p->set_spearman(correlations[c].spearman);
      if (sobol && c < sobol->first_order.size()) {
        *p->mutable_sobol_first() = interval(sobol->first_order[c]);
        *p->mutable_sobol_total() = interval(sobol->total[c]);
      }
    }
  }
  return out;
}

v1::GetCampaignResponse CampaignService::get(const std::string& id) {
  const store::CampaignRecord record = require(id);
  v1::GetCampaignResponse response;
  *response.mutable_campaign() = campaign_proto(record);
  *response.mutable_statistics() = statistics(response.campaign().spec(), store_.campaign_samples(id));
  return response;
}

void CampaignService::watch(const std::string& id, const std::function<bool(const v1::GetCampaignResponse&)>& send,
                            const std::function<bool()>& keep_going) {
  std::string last_counts;
  while (keep_going()) {
    const uint64_t seen = notifier_.version();
    const store::CampaignRecord record = require(id);
    v1::GetCampaignResponse response;
    *response.mutable_campaign() = campaign_proto(record);
    const std::string counts = to_json_text(response.campaign());
    const bool finished = response.campaign().finished();
    if (counts != last_counts || finished) {
      if (finished) *response.mutable_statistics() = statistics(response.campaign().spec(), store_.campaign_samples(id));
      if (!send(response)) return;
      last_counts = counts;
      if (finished) return;
      std::this_thread::sleep_for(std::chrono::milliseconds(500));  // rate limit
    }
    notifier_.wait_for_change(seen, std::chrono::milliseconds(1000));
  }
}

v1::Campaign CampaignService::cancel(const std::string& id) {
  require(id);
  const auto record = store_.cancel_campaign(id, now_ms());
  notifier_.notify();
  return campaign_proto(record);
}

v1::Campaign CampaignService::retry_failed(const std::string& id) {
  require(id);
  const auto record = store_.retry_failed(id, now_ms());
  notifier_.notify();
  return campaign_proto(record);
}

v1::ListCampaignsResponse CampaignService::list(const v1::ListCampaignsRequest& request) {
  const auto page = store_.list_campaigns(request.page_size(), request.page_token());
  v1::ListCampaignsResponse response;
  for (const auto& c : page.campaigns) *response.add_campaigns() = campaign_proto(c);
  response.set_next_page_token(page.next_page_token);
  return response;
}

v1::GetCampaignSamplesResponse CampaignService::samples(const std::string& id) {
  const store::CampaignRecord record = require(id);
  const v1::CampaignSpec spec = spec_from_json(record.spec_json);
  v1::GetCampaignSamplesResponse response;
  for (const auto& row : store_.campaign_samples(id)) {
    auto* s = response.add_samples();
    s->set_index(static_cast<int>(row.index));
    s->set_job_id(row.job_id);
    s->set_state(job_state(row.state));
    s->set_cached_from(row.cached_from);
    s->set_error(row.error);
    const json in = json::parse(row.inputs_json, nullptr, false);
    if (in.is_object())
      for (auto it = in.begin(); it != in.end(); ++it)
        if (it.value().is_number()) (*s->mutable_inputs())[it.key()] = it.value().get<double>();
    for (const std::string& q : spec.quantities_of_interest())
      if (auto v = metric_of(row.metrics_json, q)) (*s->mutable_outputs())[q] = *v;
  }
  return response;
}

}  // namespace systole::service
