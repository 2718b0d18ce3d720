#include "service/server/rest_gateway.h"

#include <httplib.h>

#include <fstream>
#include <functional>
#include <vector>

#include <google/protobuf/util/json_util.h>
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include "proto/bridge/json_fields.h"
#include "proto/bridge/scenario_bridge.h"

namespace systole::service {
namespace {

std::string to_json(const google::protobuf::Message& message) {
  google::protobuf::util::JsonPrintOptions options;
  options.preserve_proto_field_names = true;
  std::string text;
  (void)google::protobuf::util::MessageToJsonString(message, &text, options);
  return text;
}

// The body (proto3 JSON) → `message`. Every unknown key, at any depth, is named with its path
// and the nearest allowed names (bridge/json_fields.h); when the rest parsed, `more` adds the
// request's own problems (a scenario's rules...), so one INVALID_ARGUMENT lists them all.
void parse_body(const std::string& body, google::protobuf::Message* message,
                const std::function<std::vector<std::string>()>& more = {}) {
  bridge::JsonParse parse = bridge::parse_json_message(body, *message);
  if (parse.problems.empty()) return;
  if (parse.parsed && more)
    for (const auto& p : more()) parse.problems.push_back(p);
  const auto& all = parse.problems;
  std::string text = all.size() == 1 ? "invalid JSON body: " : "invalid JSON body (" + std::to_string(all.size()) + " problems):\n  ";
  for (std::size_t i = 0; i < all.size(); ++i) text += (i ? "\n  " : "") + all[i];
  throw ServiceError(grpc::StatusCode::INVALID_ARGUMENT, text);
}

// A job request's problems beyond its JSON: the scenario's, each with its path.
std::vector<std::string> job_problems(const v1::SubmitJobRequest& request) {
  std::vector<std::string> out;
  if (!request.has_scenario()) return {"scenario is required"};
  for (const auto& p : bridge::scenario_problems(request.scenario())) out.push_back("scenario: " + p);
  return out;
}

void send_error(httplib::Response& res, grpc::StatusCode code, const std::string& message) {
  nlohmann::json body{{"code", static_cast<int>(code)}, {"message", message}, {"details", nlohmann::json::array()}};
  res.status = http_status_for(code);
  res.set_content(body.dump(), "application/json");
}

// Runs a handler; any error becomes a gRPC-style JSON error body with the mapped HTTP status.
template <class Body>
void handle(httplib::Response& res, Body&& body) {
  const grpc::Status status = guarded([&] { body(); });
  if (!status.ok()) send_error(res, status.error_code(), status.error_message());
}

int query_int(const httplib::Request& req, const char* name, int fallback) {
  if (!req.has_param(name)) return fallback;
  const std::string text = req.get_param_value(name);
  try {
    size_t used = 0;
    const long long value = std::stoll(text, &used);
    if (used == text.size() && value >= INT32_MIN && value <= INT32_MAX) return static_cast<int>(value);
  } catch (const std::exception&) {
  }
  throw ServiceError(grpc::StatusCode::INVALID_ARGUMENT,
                     std::string("query parameter ") + name + " = '" + text + "' is not an integer");
}

}  // namespace

int http_status_for(grpc::StatusCode code) {
  switch (code) {
    case grpc::StatusCode::OK: return 200;
    case grpc::StatusCode::CANCELLED: return 499;
    case grpc::StatusCode::INVALID_ARGUMENT:
    case grpc::StatusCode::FAILED_PRECONDITION:
    case grpc::StatusCode::OUT_OF_RANGE: return 400;
    case grpc::StatusCode::DEADLINE_EXCEEDED: return 504;
    case grpc::StatusCode::NOT_FOUND: return 404;
    case grpc::StatusCode::ALREADY_EXISTS:
    case grpc::StatusCode::ABORTED: return 409;
    case grpc::StatusCode::PERMISSION_DENIED: return 403;
    case grpc::StatusCode::UNAUTHENTICATED: return 401;
    case grpc::StatusCode::RESOURCE_EXHAUSTED: return 429;
    case grpc::StatusCode::UNIMPLEMENTED: return 501;
    case grpc::StatusCode::UNAVAILABLE: return 503;
    default: return 500;
  }
}

RestGateway::RestGateway(JobService& jobs, CampaignService& campaigns, const std::string& host, int port,
                         size_t max_body_bytes)
    : jobs_(jobs), campaigns_(campaigns), server_(std::make_unique<httplib::Server>()) {
  auto& s = *server_;
  s.new_task_queue = [] { return new httplib::ThreadPool(32); };
  s.set_payload_max_length(max_body_bytes);
  s.set_error_handler([max_body_bytes](const httplib::Request& req, httplib::Response& res) {
    if (!res.body.empty()) return;
    if (res.status == 413)
      send_error(res, grpc::StatusCode::RESOURCE_EXHAUSTED,
                 "request body larger than " + std::to_string(max_body_bytes) + " bytes");
    else if (res.status == 404)
      send_error(res, grpc::StatusCode::NOT_FOUND, "no route " + req.method + " " + req.path);
    else
      send_error(res, grpc::StatusCode::UNKNOWN, "HTTP " + std::to_string(res.status));
    if (res.status == 429) res.status = 413;  // keep the HTTP meaning of "payload too large"
  });
  s.set_exception_handler([](const httplib::Request&, httplib::Response& res, std::exception_ptr error) {
    const grpc::Status status = to_status(error);
    send_error(res, status.error_code(), status.error_message());
  });

  s.Get("/healthz", [](const httplib::Request&, httplib::Response& res) { res.set_content("SERVING\n", "text/plain"); });

  s.Post("/v1/jobs", [this](const httplib::Request& req, httplib::Response& res) {
    handle(res, [&] {
      v1::SubmitJobRequest request;
      parse_body(req.body, &request, [&] { return job_problems(request); });
      const auto response = jobs_.submit(request);
      res.status = response.created() ? 201 : 200;
      res.set_content(to_json(response), "application/json");
    });
  });
  s.Get("/v1/jobs", [this](const httplib::Request& req, httplib::Response& res) {
    handle(res, [&] {
      v1::ListJobsRequest request;
      if (req.has_param("state")) {
        v1::JobState state;
        if (!v1::JobState_Parse(req.get_param_value("state"), &state))
          throw ServiceError(grpc::StatusCode::INVALID_ARGUMENT,
                             "state = '" + req.get_param_value("state") +
                                 "' is not a job state; one of QUEUED, RUNNING, SUCCEEDED, FAILED, CANCELLED");
        request.set_state(state);
      }
      request.set_page_size(query_int(req, "page_size", 0));
      if (req.has_param("page_token")) request.set_page_token(req.get_param_value("page_token"));
      res.set_content(to_json(jobs_.list(request)), "application/json");
    });
  });
  s.Get(R"(/v1/jobs/([^/:]+))", [this](const httplib::Request& req, httplib::Response& res) {
    handle(res, [&] { res.set_content(to_json(jobs_.get(req.matches[1])), "application/json"); });
  });
  s.Post(R"(/v1/jobs/([^/:]+):cancel)", [this](const httplib::Request& req, httplib::Response& res) {
    handle(res, [&] { res.set_content(to_json(jobs_.cancel(req.matches[1])), "application/json"); });
  });
  s.Get(R"(/v1/jobs/([^/:]+)/result)", [this](const httplib::Request& req, httplib::Response& res) {
    handle(res, [&] { res.set_content(to_json(jobs_.result(req.matches[1])), "application/json"); });
  });
  s.Get(R"(/v1/jobs/([^/:]+):watch)", [this](const httplib::Request& req, httplib::Response& res) {
    handle(res, [&] {
      v1::WatchJobRequest request;
      request.set_id(req.matches[1]);
      request.set_after_sequence(query_int(req, "after_sequence", 0));
      (void)jobs_.get(request.id());  // a clean 404 before the stream starts
      const bool sse = req.get_header_value("Accept").find("text/event-stream") != std::string::npos;
      res.set_chunked_content_provider(
          sse ? "text/event-stream" : "application/x-ndjson",
          [this, request, sse](size_t, httplib::DataSink& sink) {
            try {
              jobs_.watch(
                  request,
                  [&](const v1::JobEvent& event) {
                    const std::string line =
                        sse ? "id: " + std::to_string(event.sequence()) + "\ndata: " + to_json(event) + "\n\n"
                            : to_json(event) + "\n";
                    return sink.is_writable() && sink.write(line.data(), line.size());
                  },
                  [&] { return sink.is_writable(); });
            } catch (const std::exception& e) {
              spdlog::warn("REST watch of {} ended: {}", request.id(), e.what());
            }
            sink.done();
            return true;
          });
    });
  });
  s.Get(R"(/v1/jobs/([^/:]+)/artifacts/([^/]+))", [this](const httplib::Request& req, httplib::Response& res) {
    handle(res, [&] {
      const store::Artifact artifact = jobs_.artifact(req.matches[1], req.matches[2]);
      auto in = std::make_shared<std::ifstream>(artifact.path, std::ios::binary);
      if (!*in) throw ServiceError(grpc::StatusCode::DATA_LOSS, "cannot open artifact '" + artifact.name + "'");
      res.set_header("X-Sha256", artifact.sha256);
      res.set_header("Content-Disposition", "attachment; filename=\"" + artifact.name + "\"");
      res.set_content_provider(static_cast<size_t>(artifact.size_bytes), "application/octet-stream",
                               [in](size_t offset, size_t length, httplib::DataSink& sink) {
                                 std::string buffer(std::min<size_t>(length, 1 << 20), '\0');
                                 in->seekg(static_cast<std::streamoff>(offset));
                                 in->read(buffer.data(), static_cast<std::streamsize>(buffer.size()));
                                 return sink.write(buffer.data(), static_cast<size_t>(in->gcount()));
                               });
    });
  });

  // Campaigns.
  s.Post("/v1/campaigns", [this](const httplib::Request& req, httplib::Response& res) {
    handle(res, [&] {
      v1::SubmitCampaignRequest request;
      parse_body(req.body, &request, [&] {
        std::vector<std::string> out;
        for (const auto& p : campaigns_.problems(request)) out.push_back(p.rfind("spec", 0) == 0 ? p : "spec: " + p);
        return out;
      });
      const auto response = campaigns_.submit(request);
      res.status = response.created() ? 201 : 200;
      res.set_content(to_json(response), "application/json");
    });
  });
  s.Get("/v1/campaigns", [this](const httplib::Request& req, httplib::Response& res) {
    handle(res, [&] {
      v1::ListCampaignsRequest request;
      request.set_page_size(query_int(req, "page_size", 0));
      if (req.has_param("page_token")) request.set_page_token(req.get_param_value("page_token"));
      res.set_content(to_json(campaigns_.list(request)), "application/json");
    });
  });
  s.Get(R"(/v1/campaigns/([^/:]+))", [this](const httplib::Request& req, httplib::Response& res) {
    handle(res, [&] { res.set_content(to_json(campaigns_.get(req.matches[1])), "application/json"); });
  });
  s.Get(R"(/v1/campaigns/([^/:]+)/samples)", [this](const httplib::Request& req, httplib::Response& res) {
    handle(res, [&] { res.set_content(to_json(campaigns_.samples(req.matches[1])), "application/json"); });
  });
  s.Post(R"(/v1/campaigns/([^/:]+):cancel)", [this](const httplib::Request& req, httplib::Response& res) {
    handle(res, [&] { res.set_content(to_json(campaigns_.cancel(req.matches[1])), "application/json"); });
  });
  s.Post(R"(/v1/campaigns/([^/:]+):retry)", [this](const httplib::Request& req, httplib::Response& res) {
    handle(res, [&] { res.set_content(to_json(campaigns_.retry_failed(req.matches[1])), "application/json"); });
  });
  s.Get(R"(/v1/campaigns/([^/:]+):watch)", [this](const httplib::Request& req, httplib::Response& res) {
    handle(res, [&] {
      const std::string id = req.matches[1];
      (void)campaigns_.get(id);  // a clean 404 before the stream starts
      const bool sse = req.get_header_value("Accept").find("text/event-stream") != std::string::npos;
      res.set_chunked_content_provider(sse ? "text/event-stream" : "application/x-ndjson",
                                       [this, id, sse](size_t, httplib::DataSink& sink) {
                                         try {
                                           campaigns_.watch(
                                               id,
                                               [&](const v1::GetCampaignResponse& r) {
                                                 const std::string line = sse ? "data: " + to_json(r) + "\n\n"
                                                                              : to_json(r) + "\n";
                                                 return sink.is_writable() && sink.write(line.data(), line.size());
                                               },
                                               [&] { return sink.is_writable(); });
                                         } catch (const std::exception& e) {
                                           spdlog::warn("REST campaign watch of {} ended: {}", id, e.what());
                                         }
                                         sink.done();
                                         return true;
                                       });
    });
  });

  if (port == 0) {
    port_ = s.bind_to_any_port(host);
  } else {
    port_ = s.bind_to_port(host, port) ? port : -1;
  }
  if (port_ <= 0) throw std::runtime_error("REST: cannot listen on " + host + ":" + std::to_string(port));
  thread_ = std::thread([this] {
    server_->listen_after_bind();
    listen_returned_ = true;
  });
  // httplib's stop() does nothing until the listen loop runs: wait for it, so that a gateway
  // destroyed right after construction cannot hang in its destructor.
  while (!server_->is_running() && !listen_returned_) std::this_thread::sleep_for(std::chrono::milliseconds(1));
}

RestGateway::~RestGateway() {
  server_->stop();
  if (thread_.joinable()) thread_.join();
}

}  // namespace systole::service
