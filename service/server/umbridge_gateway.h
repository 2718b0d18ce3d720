#pragma once
// UM-Bridge gateway: the systole forward model for UQ tools, served over UM-Bridge protocol 1.0
// (HTTP + JSON; docs/umbridge.md). One model, "forward": the input vector maps onto real-valued
// scenario fields, the output vector is a list of result metrics. Routes:
//   GET  /Info          {"protocolVersion": 1.0, "models": ["forward"]}
//   POST /ModelInfo     {"support": {"Evaluate": true, "Gradient": false, ...}}
//   POST /InputSizes    {"inputSizes": [d]}     d = number of config "inputs"
//   POST /OutputSizes   {"outputSizes": [q]}    q = number of config "outputs"
//   POST /Evaluate      {"output": [[y0, ..., y(q-1)]]}
//   POST /Gradient, /ApplyJacobian, /ApplyHessian   UnsupportedFeature
// Each Evaluate builds a scenario (base scenario + the input values, through
// config::apply_override), submits it through JobService::submit -- so it is queued, leased
// and run by the workers like any job, and hits the result cache -- then waits (ChangeNotifier)
// for the job to end, up to a timeout. Identical Evaluates (same scenario text and priority)
// share one job through a derived request_id, so concurrent or retried clients never run the
// same point twice. Errors: {"error": {"type": ..., "message": ...}} with HTTP 400 for the
// caller's mistakes (InvalidInput, ModelNotFound, UnsupportedFeature) and 5xx for the model's
// side (InvalidOutput, ModelError 500; Timeout 504; ModelError 503 while shutting down).
#include <atomic>
#include <chrono>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "service/server/job_service.h"

namespace httplib {
class Server;
}

namespace systole::service {

// The metric names a scene always reports (for example scene::metric_names). Empty: unknown,
// so outputs are checked against the finished job's metrics instead of before submitting.
using MetricCatalog = std::function<std::vector<std::string>(const std::string& scene)>;

class UmBridgeGateway {
 public:
  static constexpr const char* kModelName = "forward";

  // Binds host:port (port 0 picks a free one) and serves on a background thread. `preset` is
  // a server-side default config (keys as in a request's "config"; null or {} for none); a
  // request's config overrides it key by key. `timeout` bounds each Evaluate unless the
  // config's "timeout_s" says otherwise. Throws std::invalid_argument for a bad preset and
  // std::runtime_error if it cannot listen.
  UmBridgeGateway(JobService& jobs, ChangeNotifier& notifier, const std::string& host, int port,
                  const nlohmann::json& preset, std::chrono::milliseconds timeout, MetricCatalog known_metrics = {});
  ~UmBridgeGateway();  // wakes waiting Evaluates (they answer 503), stops and joins
  UmBridgeGateway(const UmBridgeGateway&) = delete;
  UmBridgeGateway& operator=(const UmBridgeGateway&) = delete;
  int port() const { return port_; }

  // The config used when neither the request nor the preset says otherwise.
  static nlohmann::json default_config();

 private:
  struct Model;  // a resolved config: input fields, output metrics, base scenario, ...
  Model resolve(const nlohmann::json& request_config) const;
  nlohmann::json evaluate(const nlohmann::json& body, std::vector<std::pair<std::string, std::string>>& headers);

  JobService& jobs_;
  ChangeNotifier& notifier_;
  nlohmann::json preset_;
  std::chrono::milliseconds timeout_;
  MetricCatalog known_metrics_;
  std::atomic<bool> stopping_{false};
  std::atomic<bool> listen_returned_{false};
  std::unique_ptr<httplib::Server> server_;
  int port_ = 0;
  std::thread thread_;
};

}  // namespace systole::service
