#include "service/server/umbridge_gateway.h"

#include <httplib.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <charconv>
#include <cmath>

#include "proto/bridge/scenario_bridge.h"
#include "service/server/sha256.h"
#include "solver/config/parameter_table.h"
#include "solver/core/errors.h"
#include "solver/core/nearest_names.h"

namespace systole::service {
namespace {

using nlohmann::json;

constexpr size_t kMaxBodyBytes = size_t{16} << 20;
constexpr double kMaxTimeoutS = 86400;
// How many times an Evaluate may start a fresh job for a point whose earlier job was
// CANCELLED or failed for a transient reason (each one gets the next request_id).
constexpr int kMaxGenerations = 100;
const char* const kConfigKeys[] = {"inputs", "outputs", "base_scenario", "priority", "timeout_s"};

// An error in the protocol's format: {"error": {"type": type, "message": what()}}.
class UmError : public std::runtime_error {
 public:
  UmError(std::string type, int status, const std::string& message)
      : std::runtime_error(message), type_(std::move(type)), status_(status) {}
  const std::string& type() const { return type_; }
  int status() const { return status_; }

 private:
  std::string type_;
  int status_;
};

[[noreturn]] void invalid_input(const std::string& message) { throw UmError("InvalidInput", 400, message); }

void send_json(httplib::Response& res, int status, const json& body) {
  res.status = status;
  res.set_content(body.dump(), "application/json");
}

void send_error(httplib::Response& res, int status, const std::string& type, const std::string& message) {
  send_json(res, status, {{"error", {{"type", type}, {"message", message}}}});
}

// Runs a handler; every exception becomes a protocol error.
template <class Body>
void handle(httplib::Response& res, Body&& body) {
  try {
    body();
  } catch (const UmError& e) {
    send_error(res, e.status(), e.type(), e.what());
  } catch (const InputError& e) {
    send_error(res, 400, "InvalidInput", e.what());
  } catch (...) {
    const grpc::Status status = to_status(std::current_exception());
    switch (status.error_code()) {
      case grpc::StatusCode::INVALID_ARGUMENT:
      case grpc::StatusCode::OUT_OF_RANGE:
      case grpc::StatusCode::FAILED_PRECONDITION:
        send_error(res, 400, "InvalidInput", status.error_message());
        break;
      default:
        spdlog::error("UM-Bridge: {}", status.error_message());
        send_error(res, 500, "ModelError", status.error_message());
    }
  }
}

json parse_body(const httplib::Request& req) {
  json body = json::parse(req.body, nullptr, /*allow_exceptions=*/false);
  if (body.is_discarded()) invalid_input("the request body is not valid JSON");
  if (!body.is_object()) invalid_input("the request body must be a JSON object, got " + std::string(body.type_name()));
  return body;
}

// The "name" of the model a request addresses: it must be "forward".
void require_model(const json& body) {
  const auto it = body.find("name");
  if (it == body.end()) invalid_input("\"name\" is required: the model name, \"forward\"");
  if (!it->is_string()) invalid_input("\"name\" must be a string, got " + it->dump());
  if (it->get<std::string>() != UmBridgeGateway::kModelName)
    throw UmError("ModelNotFound", 400,
                  "model '" + it->get<std::string>() + "' not found; this server provides: [\"forward\"]");
}

std::string format_number(double value) {
  char buffer[64];
  const auto [end, error] = std::to_chars(buffer, buffer + sizeof buffer, value);
  return error == std::errc() ? std::string(buffer, end) : std::to_string(value);
}

std::string join(const std::vector<std::string>& items) {
  std::string out;
  for (const auto& item : items) out += (out.empty() ? "" : ", ") + item;
  return out;
}

// The nearest real-valued fields (nearest_names.h), then those next to an unknown path (same
// parent object), to suggest in an error.
std::string real_fields_near(const std::string& path) {
  const auto dot = path.rfind('.');
  const std::string prefix = dot == std::string::npos ? "" : path.substr(0, dot + 1);
  std::vector<std::string> real, near;
  for (const auto& p : config::parameter_table()) {
    if (p.kind != config::Kind::kReal) continue;
    const std::string candidate(p.path);
    real.push_back(candidate);
    if (prefix.empty() ? candidate.find('.') == std::string::npos : candidate.rfind(prefix, 0) == 0)
      near.push_back(candidate);
  }
  const std::string suggestion = did_you_mean(path, real);
  return (suggestion.empty() ? "" : "; " + suggestion.substr(0, suggestion.size() - 1)) +
         (near.empty()
             ? ""
             : "; real-valued fields" +
                   (prefix.empty() ? std::string(" at the top level") : " of " + prefix.substr(0, prefix.size() - 1)) +
                   ": " + join(near));
}

// A FAILED job that is not worth running again: the worker reported a final (not retryable)
// failure -- the store only ends a job FAILED before max_attempts for those -- or rejected the
// scenario. Anything else (retries used up, leases lost) is the model's side.
bool failed_at_this_input(const v1::Job& job) {
  return job.state() == v1::FAILED &&
         (job.attempts() < job.max_attempts() || job.error().rfind("invalid scenario:", 0) == 0);
}

bool is_terminal(v1::JobState state) { return state == v1::SUCCEEDED || state == v1::FAILED || state == v1::CANCELLED; }

}  // namespace

struct UmBridgeGateway::Model {
  std::vector<std::string> inputs;   // scenario field paths, kReal
  std::vector<std::string> outputs;  // metric names
  json base;                         // proto3 JSON scenario (an object)
  std::string scene;                 // of the validated base scenario
  int priority = 0;
  std::chrono::milliseconds timeout{0};
};

json UmBridgeGateway::default_config() {
  return {{"inputs", {"lumped.lv.emax_mmhg_per_ml", "heart_rate_bpm", "lumped.systemic_resistance_mmhg_s_per_ml"}},
          {"outputs", {"ejection_fraction_percent", "cardiac_output_l_min"}},
          {"base_scenario", {{"scene", "lumped"}}},
          {"priority", 0}};
}

UmBridgeGateway::Model UmBridgeGateway::resolve(const json& request_config) const {
  if (!request_config.is_null() && !request_config.is_object())
    invalid_input("\"config\" must be a JSON object, got " + request_config.dump());
  // Defaults, then the server's preset, then the request: key by key (a key's value replaces
  // the one below it whole; null means "not given").
  json merged = default_config();
  for (const json* layer : {&preset_, &request_config}) {
    if (!layer->is_object()) continue;
    for (const auto& [key, value] : layer->items()) {
      if (std::find(std::begin(kConfigKeys), std::end(kConfigKeys), key) == std::end(kConfigKeys))
        invalid_input("unknown config key '" + key + "'; known: inputs, outputs, base_scenario, priority, timeout_s");
      if (!value.is_null()) merged[key] = value;
    }
  }

  Model model;
  // inputs
  const json& inputs = merged["inputs"];
  if (!inputs.is_array() || inputs.empty())
    invalid_input("config.inputs must be a non-empty array of scenario field paths, got " + inputs.dump());
  for (size_t i = 0; i < inputs.size(); ++i) {
    const std::string where = "config.inputs[" + std::to_string(i) + "]";
    if (!inputs[i].is_string()) invalid_input(where + " must be a string, got " + inputs[i].dump());
    const std::string path = inputs[i].get<std::string>();
    const config::Param* param = config::find_parameter(path);
    if (param == nullptr) invalid_input(where + ": unknown scenario field '" + path + "'" + real_fields_near(path));
    if (param->kind != config::Kind::kReal)
      invalid_input(where + ": field '" + path +
                    "' is not real-valued; an input vector maps only onto real-valued fields (docs/parameters.md)");
    if (std::find(model.inputs.begin(), model.inputs.end(), path) != model.inputs.end())
      invalid_input(where + ": field '" + path + "' is listed twice");
    model.inputs.push_back(path);
  }
  // outputs
  const json& outputs = merged["outputs"];
  if (!outputs.is_array() || outputs.empty())
    invalid_input("config.outputs must be a non-empty array of metric names, got " + outputs.dump());
  for (size_t i = 0; i < outputs.size(); ++i) {
    const std::string where = "config.outputs[" + std::to_string(i) + "]";
    if (!outputs[i].is_string() || outputs[i].get<std::string>().empty())
      invalid_input(where + " must be a metric name, got " + outputs[i].dump());
    const std::string name = outputs[i].get<std::string>();
    if (std::find(model.outputs.begin(), model.outputs.end(), name) != model.outputs.end())
      invalid_input(where + ": metric '" + name + "' is listed twice");
    model.outputs.push_back(name);
  }
  // base scenario: must be a valid scenario on its own (the inputs then change some fields)
  model.base = merged["base_scenario"];
  if (!model.base.is_object())
    invalid_input("config.base_scenario must be a scenario object (proto3 JSON), got " + model.base.dump());
  try {
    model.scene = bridge::validate(bridge::scenario_proto_from_json_text(model.base.dump())).scene;
  } catch (const InputError& e) {
    invalid_input(std::string("config.base_scenario is not a valid scenario: ") + e.what());
  }
  if (known_metrics_) {
    const std::vector<std::string> known = known_metrics_(model.scene);
    if (!known.empty())
      for (size_t i = 0; i < model.outputs.size(); ++i)
        if (std::find(known.begin(), known.end(), model.outputs[i]) == known.end())
          invalid_input("config.outputs[" + std::to_string(i) + "]: '" + model.outputs[i] +
                        "' is not a metric of scene '" + model.scene + "'; it reports: " + join(known));
  }
  // priority
  const json& priority = merged["priority"];
  if (!priority.is_number_integer() || priority.get<int64_t>() < store::JobStore::kMinPriority ||
      priority.get<int64_t>() > store::JobStore::kMaxPriority)
    invalid_input("config.priority must be an integer in [-1000, 1000], got " + priority.dump());
  model.priority = static_cast<int>(priority.get<int64_t>());
  // timeout
  model.timeout = timeout_;
  if (merged.contains("timeout_s")) {
    const json& t = merged["timeout_s"];
    if (!t.is_number() || !(t.get<double>() > 0) || t.get<double>() > kMaxTimeoutS)
      invalid_input("config.timeout_s must be a number of seconds in (0, 86400], got " + t.dump());
    model.timeout = std::chrono::milliseconds(static_cast<int64_t>(std::ceil(t.get<double>() * 1000)));
  }
  return model;
}

json UmBridgeGateway::evaluate(const json& body, std::vector<std::pair<std::string, std::string>>& headers) {
  require_model(body);
  const Model model = resolve(body.contains("config") ? body["config"] : json());

  // input: one vector of size d
  const auto it = body.find("input");
  if (it == body.end()) invalid_input("\"input\" is required: [[" + join(model.inputs) + "]]");
  if (!it->is_array() || std::any_of(it->begin(), it->end(), [](const json& v) { return !v.is_array(); }))
    invalid_input("\"input\" must be an array of arrays of numbers, got " + it->dump().substr(0, 200));
  if (it->size() != 1)
    invalid_input("\"input\" has " + std::to_string(it->size()) + " vectors; the model takes 1 (inputSizes [" +
                  std::to_string(model.inputs.size()) + "])");
  const json& vector = (*it)[0];
  if (vector.size() != model.inputs.size())
    invalid_input("input vector 0 has length " + std::to_string(vector.size()) + ", expected " +
                  std::to_string(model.inputs.size()) + " (" + join(model.inputs) + ")");

  // scenario = base + inputs
  json document = model.base;
  for (size_t i = 0; i < vector.size(); ++i) {
    if (!vector[i].is_number())
      invalid_input("input[0][" + std::to_string(i) + "] (" + model.inputs[i] + ") must be a number, got " +
                    vector[i].dump());
    try {
      config::apply_override(document, model.inputs[i] + "=" + format_number(vector[i].get<double>()));
    } catch (const json::exception& e) {  // the base scenario has a non-object on the path
      invalid_input("cannot set " + model.inputs[i] + " in config.base_scenario: " + e.what());
    }
  }
  v1::SubmitJobRequest request;
  try {
    *request.mutable_scenario() = bridge::scenario_proto_from_json_text(document.dump());
    (void)bridge::validate(request.scenario());
  } catch (const InputError& e) {
    invalid_input(std::string("the scenario built from the input is invalid: ") + e.what());
  }
  request.set_priority(model.priority);

  // Submit. The request_id is derived from the exact scenario and priority, so identical
  // Evaluates share one job (in flight or finished); a point whose job was CANCELLED or
  // failed transiently gets a fresh job under the next generation's request_id.
  Sha256 hash;
  hash.update(bridge::to_json_text(request.scenario()));
  hash.update("|priority=" + std::to_string(model.priority));
  const std::string request_base = "umbridge-" + hash.hex_digest();
  v1::Job job;
  for (int generation = 0;; ++generation) {
    if (generation < kMaxGenerations)
      request.set_request_id(request_base + "-" + std::to_string(generation));
    else
      request.clear_request_id();
    v1::SubmitJobResponse response;
    const grpc::Status status = guarded([&] { response = jobs_.submit(request); });
    if (status.error_code() == grpc::StatusCode::ALREADY_EXISTS && !request.request_id().empty()) {
      generation = kMaxGenerations - 1;  // someone else used the id: submit without one
      continue;
    }
    if (!status.ok()) {
      if (status.error_code() == grpc::StatusCode::INVALID_ARGUMENT)
        invalid_input("the job service rejected the scenario: " + status.error_message());
      throw UmError("ModelError", 500, "cannot submit the job: " + status.error_message());
    }
    job = response.job();
    const bool stale = !response.created() &&
                       (job.state() == v1::CANCELLED || (job.state() == v1::FAILED && !failed_at_this_input(job)));
    if (!stale || request.request_id().empty()) break;
  }
  const std::string id = job.id();
  headers.emplace_back("X-Systole-Job-Id", id);

  // Wait for the job to end.
  const auto deadline = std::chrono::steady_clock::now() + model.timeout;
  while (!is_terminal(job.state())) {
    const uint64_t seen = notifier_.version();
    job = jobs_.get(id);
    if (is_terminal(job.state())) break;
    if (stopping_)
      throw UmError("ModelError", 503,
                    "the server is shutting down; job " + id + " is " + v1::JobState_Name(job.state()) +
                        " and stays queued: repeat the Evaluate later to collect its result");
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0)
      throw UmError("Timeout", 504,
                    "job " + id + " did not finish within " + format_number(model.timeout.count() / 1000.0) +
                        " s; it is " + v1::JobState_Name(job.state()) +
                        " and goes on: repeat the same Evaluate to wait for it again, raise config.timeout_s, "
                        "or follow it at GET /v1/jobs/" +
                        id);
    notifier_.wait_for_change(seen, std::min(left, std::chrono::milliseconds(1000)));
  }
  if (!job.cached_from().empty()) headers.emplace_back("X-Systole-Cached-From", job.cached_from());

  switch (job.state()) {
    case v1::SUCCEEDED:
      break;
    case v1::FAILED:
      if (failed_at_this_input(job))
        invalid_input("job " + id + " failed and was not retried: the model cannot run at this input: " + job.error());
      throw UmError("ModelError", 500,
                    "job " + id + " failed after " + std::to_string(job.attempts()) + " attempt(s): " + job.error());
    default:
      throw UmError("ModelError", 500, "job " + id + " was " + v1::JobState_Name(job.state()) + " before it finished");
  }

  const v1::Result result = jobs_.result(id);
  json output = json::array();
  for (const auto& name : model.outputs) {
    const auto found = result.metrics().find(name);
    if (found == result.metrics().end()) {
      std::vector<std::string> known;
      for (const auto& [metric, value] : result.metrics()) known.push_back(metric);
      std::sort(known.begin(), known.end());
      invalid_input("output '" + name + "' is not a metric of scene '" + model.scene + "' (job " + id +
                    "); it reports: " + join(known));
    }
    if (!std::isfinite(found->second))
      throw UmError("InvalidOutput", 500,
                    "job " + id + " reported " + name + " = " + format_number(found->second) + ", not a finite number");
    output.push_back(found->second);
  }
  spdlog::debug("UM-Bridge Evaluate → job {}{}", id, job.cached_from().empty() ? "" : " (cached)");
  return {{"output", json::array({output})}};
}

UmBridgeGateway::UmBridgeGateway(JobService& jobs, ChangeNotifier& notifier, const std::string& host, int port,
                                 const nlohmann::json& preset, std::chrono::milliseconds timeout,
                                 MetricCatalog known_metrics)
    : jobs_(jobs),
      notifier_(notifier),
      preset_(preset.is_null() ? json::object() : preset),
      timeout_(timeout),
      known_metrics_(std::move(known_metrics)),
      server_(std::make_unique<httplib::Server>()) {
  if (!preset_.is_object())
    throw std::invalid_argument("UM-Bridge preset must be a JSON object, got " + preset_.dump());
  if (timeout_.count() <= 0)
    throw std::invalid_argument("UM-Bridge timeout must be positive, got " + std::to_string(timeout_.count()) + " ms");
  try {
    (void)resolve(json());  // a bad preset fails here, at start-up, not on the first request
  } catch (const UmError& e) {
    throw std::invalid_argument(std::string("UM-Bridge preset: ") + e.what());
  }

  auto& s = *server_;
  s.new_task_queue = [] { return new httplib::ThreadPool(32); };
  s.set_payload_max_length(kMaxBodyBytes);
  s.set_error_handler([](const httplib::Request& req, httplib::Response& res) {
    if (!res.body.empty()) return;
    if (res.status == 404)
      send_error(res, 404, "UnsupportedFeature",
                 "no endpoint " + req.method + " " + req.path +
                     "; UM-Bridge 1.0 here: GET /Info, POST /ModelInfo, /InputSizes, /OutputSizes, /Evaluate");
    else if (res.status == 413)
      send_error(res, 413, "InvalidInput", "request body larger than " + std::to_string(kMaxBodyBytes) + " bytes");
    else if (res.status >= 400 && res.status < 500)
      send_error(res, res.status, "InvalidInput", "bad HTTP request (" + std::to_string(res.status) + ")");
    else
      send_error(res, res.status, "ModelError", "HTTP " + std::to_string(res.status));
  });
  s.set_exception_handler([](const httplib::Request&, httplib::Response& res, std::exception_ptr error) {
    handle(res, [&] { std::rethrow_exception(error); });
  });

  s.Get("/Info", [](const httplib::Request&, httplib::Response& res) {
    send_json(res, 200, {{"protocolVersion", 1.0}, {"models", json::array({kModelName})}});
  });
  s.Post("/ModelInfo", [](const httplib::Request& req, httplib::Response& res) {
    handle(res, [&] {
      require_model(parse_body(req));
      send_json(
          res, 200,
          {{"support", {{"Evaluate", true}, {"Gradient", false}, {"ApplyJacobian", false}, {"ApplyHessian", false}}}});
    });
  });
  s.Post("/InputSizes", [this](const httplib::Request& req, httplib::Response& res) {
    handle(res, [&] {
      const json body = parse_body(req);
      require_model(body);
      const Model model = resolve(body.contains("config") ? body["config"] : json());
      send_json(res, 200, {{"inputSizes", json::array({model.inputs.size()})}});
    });
  });
  s.Post("/OutputSizes", [this](const httplib::Request& req, httplib::Response& res) {
    handle(res, [&] {
      const json body = parse_body(req);
      require_model(body);
      const Model model = resolve(body.contains("config") ? body["config"] : json());
      send_json(res, 200, {{"outputSizes", json::array({model.outputs.size()})}});
    });
  });
  s.Post("/Evaluate", [this](const httplib::Request& req, httplib::Response& res) {
    std::vector<std::pair<std::string, std::string>> headers;
    handle(res, [&] { send_json(res, 200, evaluate(parse_body(req), headers)); });
    for (const auto& [name, value] : headers) res.set_header(name, value);
  });
  for (const char* feature : {"Gradient", "ApplyJacobian", "ApplyHessian"}) {
    s.Post(std::string("/") + feature, [feature](const httplib::Request& req, httplib::Response& res) {
      handle(res, [&] {
        require_model(parse_body(req));
        throw UmError(
            "UnsupportedFeature", 400,
            std::string(feature) + " is not supported by model 'forward' (see POST /ModelInfo); only Evaluate is");
      });
    });
  }

  if (port == 0) {
    port_ = s.bind_to_any_port(host);
  } else {
    port_ = s.bind_to_port(host, port) ? port : -1;
  }
  if (port_ <= 0) throw std::runtime_error("UM-Bridge: cannot listen on " + host + ":" + std::to_string(port));
  thread_ = std::thread([this] {
    server_->listen_after_bind();
    listen_returned_ = true;
  });
  // httplib's stop() does nothing until the listen loop runs: wait for it, so that a gateway
  // destroyed right after construction cannot leave its thread in accept() forever.
  while (!server_->is_running() && !listen_returned_) std::this_thread::sleep_for(std::chrono::milliseconds(1));
}

UmBridgeGateway::~UmBridgeGateway() {
  stopping_ = true;
  notifier_.notify();  // waiting Evaluates see stopping_ and answer
  server_->stop();
  if (thread_.joinable()) thread_.join();
}

}  // namespace systole::service
