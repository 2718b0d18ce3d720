#include "service/server/job_service.h"

#include <fstream>
#include <random>
#include <regex>

#include <google/protobuf/util/json_util.h>
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include "proto/bridge/scenario_bridge.h"
#include "service/server/sha256.h"
#include "solver/core/errors.h"
#include "solver/core/version.h"

namespace systole::service {
namespace fs = std::filesystem;
using grpc::StatusCode;

namespace {

std::string message_to_json(const google::protobuf::Message& message) {
  google::protobuf::util::JsonPrintOptions options;
  options.preserve_proto_field_names = true;
  std::string text;
  const auto status = google::protobuf::util::MessageToJsonString(message, &text, options);
  if (!status.ok()) throw ServiceError(StatusCode::INTERNAL, "cannot encode JSON: " + std::string(status.message()));
  return text;
}

template <class Message>
Message json_to_message(const std::string& text) {
  Message message;
  if (text.empty()) return message;
  google::protobuf::util::JsonParseOptions options;
  options.ignore_unknown_fields = true;  // stored by an older/newer server: tolerate
  const auto status = google::protobuf::util::JsonStringToMessage(text, &message, options);
  if (!status.ok()) throw ServiceError(StatusCode::INTERNAL, "stored JSON is corrupt: " + std::string(status.message()));
  return message;
}

v1::JobState state_to_proto(store::JobState state) {
  switch (state) {
    case store::JobState::kQueued: return v1::QUEUED;
    case store::JobState::kRunning: return v1::RUNNING;
    case store::JobState::kSucceeded: return v1::SUCCEEDED;
    case store::JobState::kFailed: return v1::FAILED;
    case store::JobState::kCancelled: return v1::CANCELLED;
  }
  return v1::JOB_STATE_UNSPECIFIED;
}

void require_id(const std::string& id, const char* field = "id") {
  if (id.empty()) throw ServiceError(StatusCode::INVALID_ARGUMENT, std::string(field) + " is required");
  if (id.size() > 128)
    throw ServiceError(StatusCode::INVALID_ARGUMENT,
                       std::string(field) + " is " + std::to_string(id.size()) + " characters long; at most 128 allowed");
}

// Artifact names are plain file names: letters, digits, '.', '_', '-', not starting with '.'.
void require_artifact_name(const std::string& name) {
  static const std::regex allowed("[A-Za-z0-9_-][A-Za-z0-9._-]{0,63}");
  if (!std::regex_match(name, allowed))
    throw ServiceError(StatusCode::INVALID_ARGUMENT,
                       "artifact name '" + name.substr(0, 80) +
                           "' is not allowed; use 1-64 of [A-Za-z0-9._-], not starting with '.'");
}

v1::JobEvent to_event(const store::Event& e) {
  v1::JobEvent out;
  out.set_sequence(e.seq);
  out.set_time_ms(e.time_ms);
  out.set_kind(e.kind);
  if (e.kind == "progress") {
    *out.mutable_progress() = json_to_message<v1::Progress>(e.payload_json);
    out.set_state(v1::RUNNING);
    return out;
  }
  const auto payload = nlohmann::json::parse(e.payload_json, nullptr, false);
  if (payload.is_object()) {
    if (payload.contains("state") && payload["state"].is_string()) {
      if (auto s = store::from_string(payload["state"].get<std::string>())) out.set_state(state_to_proto(*s));
    }
    for (const char* key : {"reason", "error", "message"})
      if (payload.contains(key) && payload[key].is_string()) out.set_message(payload[key].get<std::string>());
    if (out.message().empty() && e.kind == "cancel_requested") out.set_message("cancel requested");
  }
  return out;
}

}  // namespace

std::string cache_key(const config::Scenario& scenario) {
  Sha256 hash;
  hash.update(config::to_json(scenario).dump());  // every default expanded, keys sorted
  hash.update("|systole ");
  hash.update(kVersion);
  hash.update(" ");
  hash.update(kGitRevision);
  return hash.hex_digest();
}

int64_t now_ms() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

uint64_t ChangeNotifier::version() const {
  std::lock_guard lock(mu_);
  return version_;
}
void ChangeNotifier::notify() {
  {
    std::lock_guard lock(mu_);
    ++version_;
  }
  cv_.notify_all();
}
uint64_t ChangeNotifier::wait_for_change(uint64_t seen, std::chrono::milliseconds timeout) const {
  std::unique_lock lock(mu_);
  cv_.wait_for(lock, timeout, [&] { return version_ != seen; });
  return version_;
}

JobService::JobService(store::JobStore& store, ChangeNotifier& notifier, ServiceOptions options)
    : store_(store), notifier_(notifier), options_(std::move(options)) {
  if (options_.lease_ms < 1000)
    throw std::invalid_argument("lease_ms = " + std::to_string(options_.lease_ms) + " must be >= 1000");
  fs::create_directories(options_.data_dir / "jobs");
}

fs::path JobService::job_dir(const std::string& id) const { return options_.data_dir / "jobs" / id; }

v1::Job JobService::to_proto(const store::JobRecord& r, bool with_scenario) const {
  v1::Job job;
  job.set_id(r.id);
  job.set_request_id(r.request_id);
  job.set_state(state_to_proto(r.state));
  job.set_priority(r.priority);
  job.set_scene(r.scene);
  job.set_attempts(r.attempts);
  job.set_max_attempts(r.max_attempts);
  job.set_cancel_requested(r.cancel_requested);
  job.set_error(r.error);
  job.set_created_ms(r.created_ms);
  job.set_updated_ms(r.updated_ms);
  job.set_started_ms(r.started_ms);
  job.set_finished_ms(r.finished_ms);
  if (!r.progress_json.empty()) *job.mutable_progress() = json_to_message<v1::Progress>(r.progress_json);
  if (with_scenario) *job.mutable_scenario() = json_to_message<v1::Scenario>(r.scenario_json);
  job.set_cached_from(r.cached_from);
  job.set_campaign_id(r.campaign_id);
  return job;
}

// ---------------------------------------------------------------------------------------------
// Public API

v1::SubmitJobResponse JobService::submit(const v1::SubmitJobRequest& request) {
  if (!request.has_scenario())
    throw ServiceError(StatusCode::INVALID_ARGUMENT, "scenario is required");
  if (request.request_id().size() > 128)
    throw ServiceError(StatusCode::INVALID_ARGUMENT, "request_id is " + std::to_string(request.request_id().size()) +
                                                         " characters long; at most 128 allowed");
  const config::Scenario scenario = bridge::validate(request.scenario());  // InputError → 400
  store::NewJob job;
  job.request_id = request.request_id();
  job.scene = scenario.scene;
  job.scenario_json = bridge::to_json_text(request.scenario());
  job.priority = request.priority();
  job.max_attempts = request.max_attempts() == 0 ? options_.default_max_attempts : request.max_attempts();
  if (!request.no_cache()) job.cache_key = cache_key(scenario);
  const auto outcome = store_.submit_job(job, now_ms());
  if (outcome.created) notifier_.notify();
  v1::SubmitJobResponse response;
  *response.mutable_job() = to_proto(outcome.job, true);
  response.set_created(outcome.created);
  return response;
}

v1::Job JobService::get(const std::string& id) {
  require_id(id);
  const auto record = store_.get(id);
  if (!record) throw ServiceError(StatusCode::NOT_FOUND, "job '" + id + "' not found");
  return to_proto(*record, true);
}

v1::ListJobsResponse JobService::list(const v1::ListJobsRequest& request) {
  std::optional<store::JobState> state;
  switch (request.state()) {
    case v1::JOB_STATE_UNSPECIFIED: break;
    case v1::QUEUED: state = store::JobState::kQueued; break;
    case v1::RUNNING: state = store::JobState::kRunning; break;
    case v1::SUCCEEDED: state = store::JobState::kSucceeded; break;
    case v1::FAILED: state = store::JobState::kFailed; break;
    case v1::CANCELLED: state = store::JobState::kCancelled; break;
    default:
      throw ServiceError(StatusCode::INVALID_ARGUMENT, "state = " + std::to_string(request.state()) + " is not a job state");
  }
  const auto page = store_.list(state, request.page_size(), request.page_token());
  v1::ListJobsResponse response;
  for (const auto& r : page.jobs) *response.add_jobs() = to_proto(r, false);
  response.set_next_page_token(page.next_page_token);
  return response;
}

v1::Job JobService::cancel(const std::string& id) {
  require_id(id);
  const auto record = store_.cancel(id, now_ms());
  notifier_.notify();
  return to_proto(record, true);
}

void JobService::watch(const v1::WatchJobRequest& request, const std::function<bool(const v1::JobEvent&)>& send,
                       const std::function<bool()>& keep_going) {
  if (request.after_sequence() < 0)
    throw ServiceError(StatusCode::INVALID_ARGUMENT,
                       "after_sequence = " + std::to_string(request.after_sequence()) + " must be >= 0");
  v1::JobEvent snapshot;
  snapshot.set_kind("snapshot");
  snapshot.set_sequence(request.after_sequence());
  snapshot.set_time_ms(now_ms());
  *snapshot.mutable_job() = get(request.id());
  snapshot.set_state(snapshot.job().state());
  *snapshot.mutable_progress() = snapshot.job().progress();
  if (!send(snapshot)) return;
  int64_t cursor = request.after_sequence();
  while (keep_going()) {
    const uint64_t seen = notifier_.version();
    const auto events = store_.events(request.id(), cursor, 100);
    for (const auto& e : events) {
      if (!send(to_event(e))) return;
      cursor = e.seq;
    }
    if (!events.empty()) continue;
    const auto record = store_.get(request.id());
    if (!record || store::is_terminal(record->state)) {
      // Drain once more: the terminal event may have landed after the events() call above.
      if (store_.events(request.id(), cursor, 1).empty()) return;
      continue;
    }
    notifier_.wait_for_change(seen, std::chrono::milliseconds(500));
  }
}

v1::Result JobService::result(const std::string& id) {
  const v1::Job job = get(id);
  if (job.state() != v1::SUCCEEDED)
    throw ServiceError(StatusCode::FAILED_PRECONDITION,
                       "job '" + id + "' is " + v1::JobState_Name(job.state()) +
                           "; results exist only for SUCCEEDED jobs");
  const auto record = store_.result(id);
  if (!record) throw ServiceError(StatusCode::INTERNAL, "job '" + id + "' SUCCEEDED but has no result row");
  v1::Result out = json_to_message<v1::Result>(record->metrics_json);
  const v1::Result series = json_to_message<v1::Result>(record->timeseries_json);
  *out.mutable_time_series() = series.time_series();
  out.set_job_id(id);
  for (const auto& a : record->artifacts) {
    auto* artifact = out.add_artifacts();
    artifact->set_name(a.name);
    artifact->set_size_bytes(a.size_bytes);
    artifact->set_sha256(a.sha256);
  }
  return out;
}

store::Artifact JobService::artifact(const std::string& id, const std::string& name) {
  require_artifact_name(name);
  const v1::Result r = result(id);
  const auto record = store_.result(id);
  std::string known;
  for (const auto& a : record->artifacts) {
    if (a.name == name) {
      if (!fs::exists(a.path))
        throw ServiceError(StatusCode::DATA_LOSS, "artifact '" + name + "' of job '" + id + "' is missing on disk");
      return a;
    }
    known += (known.empty() ? "" : ", ") + a.name;
  }
  throw ServiceError(StatusCode::NOT_FOUND, "job '" + id + "' has no artifact '" + name + "'; it has: " + known);
}

// ---------------------------------------------------------------------------------------------
// Worker API

v1::LeaseJobResponse JobService::lease(const v1::LeaseJobRequest& request, std::chrono::milliseconds wait) {
  require_id(request.worker_id(), "worker_id");
  const auto deadline = std::chrono::steady_clock::now() + wait;
  v1::LeaseJobResponse response;
  while (true) {
    const uint64_t seen = notifier_.version();
    if (auto lease = store_.lease(request.worker_id(), options_.lease_ms, now_ms())) {
      notifier_.notify();
      response.set_has_job(true);
      response.set_job_id(lease->job.id);
      *response.mutable_scenario() = json_to_message<v1::Scenario>(lease->job.scenario_json);
      response.set_attempt(lease->job.attempts);
      response.set_lease_ms(options_.lease_ms);
      spdlog::info("job {} leased by {} (attempt {})", lease->job.id, request.worker_id(), lease->job.attempts);
      return response;
    }
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) return response;
    notifier_.wait_for_change(seen, std::min(left, std::chrono::milliseconds(1000)));
  }
}

v1::HeartbeatResponse JobService::heartbeat(const v1::HeartbeatRequest& request) {
  require_id(request.job_id(), "job_id");
  require_id(request.worker_id(), "worker_id");
  const auto answer = store_.heartbeat(request.job_id(), request.worker_id(), options_.lease_ms, now_ms());
  v1::HeartbeatResponse response;
  response.set_lease_valid(answer.lease_valid);
  response.set_cancel_requested(answer.cancel_requested);
  return response;
}

v1::HeartbeatResponse JobService::report_progress(const v1::ReportProgressRequest& request) {
  require_id(request.job_id(), "job_id");
  require_id(request.worker_id(), "worker_id");
  v1::HeartbeatRequest beat;
  beat.set_job_id(request.job_id());
  beat.set_worker_id(request.worker_id());
  const auto answer = heartbeat(beat);
  if (!answer.lease_valid()) return answer;
  store_.progress(request.job_id(), request.worker_id(), message_to_json(request.progress()), now_ms());
  notifier_.notify();
  return answer;
}

v1::WorkerAck JobService::complete(const v1::CompleteJobRequest& request) {
  require_id(request.job_id(), "job_id");
  v1::Result metrics;
  *metrics.mutable_metrics() = request.result().metrics();
  *metrics.mutable_beats() = request.result().beats();
  v1::Result series;
  *series.mutable_time_series() = request.result().time_series();
  const auto record = store_.complete(request.job_id(), request.worker_id(), message_to_json(metrics),
                                      message_to_json(series), now_ms());
  notifier_.notify();
  spdlog::info("job {} SUCCEEDED", request.job_id());
  v1::WorkerAck ack;
  *ack.mutable_job() = to_proto(record, false);
  return ack;
}

v1::WorkerAck JobService::fail(const v1::FailJobRequest& request) {
  require_id(request.job_id(), "job_id");
  const auto record = store_.fail(request.job_id(), request.worker_id(), request.error(), request.retryable(), now_ms());
  notifier_.notify();
  spdlog::warn("job {} attempt failed ({}): {} → {}", request.job_id(), request.retryable() ? "retryable" : "final",
               request.error(), store::to_string(record.state));
  v1::WorkerAck ack;
  *ack.mutable_job() = to_proto(record, false);
  return ack;
}

v1::WorkerAck JobService::release(const v1::ReleaseJobRequest& request) {
  require_id(request.job_id(), "job_id");
  const auto record = request.cancelled()
                          ? store_.acknowledge_cancel(request.job_id(), request.worker_id(), now_ms())
                          : store_.release(request.job_id(), request.worker_id(), now_ms());
  notifier_.notify();
  spdlog::info("job {} released by {} → {}", request.job_id(), request.worker_id(), store::to_string(record.state));
  v1::WorkerAck ack;
  *ack.mutable_job() = to_proto(record, false);
  return ack;
}

v1::UploadArtifactResponse JobService::upload(const v1::UploadArtifactRequest& first,
                                              const std::function<bool(v1::UploadArtifactRequest&)>& next) {
  require_id(first.job_id(), "job_id");
  require_id(first.worker_id(), "worker_id");
  require_artifact_name(first.name());
  const auto record = store_.get(first.job_id());
  if (!record) throw ServiceError(StatusCode::NOT_FOUND, "job '" + first.job_id() + "' not found");
  if (record->state != store::JobState::kRunning || record->worker_id != first.worker_id())
    throw ServiceError(StatusCode::FAILED_PRECONDITION,
                       "job '" + first.job_id() + "' is not RUNNING under worker '" + first.worker_id() + "'");
  const fs::path dir = job_dir(first.job_id());
  fs::create_directories(dir);
  const fs::path final_path = dir / first.name();
  const fs::path tmp = dir / (".upload-" + first.name() + "-" + std::to_string(std::random_device{}()));
  constexpr int64_t kMaxBytes = int64_t{4} << 30;
  Sha256 hash;
  int64_t size = 0;
  std::string expected_sha;
  try {
    std::ofstream out(tmp, std::ios::binary);
    v1::UploadArtifactRequest message = first;
    do {
      size += static_cast<int64_t>(message.data().size());
      if (size > kMaxBytes) throw ServiceError(StatusCode::RESOURCE_EXHAUSTED, "artifact larger than 4 GiB");
      out.write(message.data().data(), static_cast<std::streamsize>(message.data().size()));
      hash.update(message.data());
      if (!message.sha256().empty()) expected_sha = message.sha256();
    } while (next(message));
    out.flush();
    if (!out) throw ServiceError(StatusCode::INTERNAL, "cannot write " + tmp.string());
    out.close();
    const std::string actual = hash.hex_digest();
    if (expected_sha.empty())
      throw ServiceError(StatusCode::INVALID_ARGUMENT, "upload of '" + first.name() + "' carries no sha256");
    if (actual != expected_sha)
      throw ServiceError(StatusCode::DATA_LOSS, "upload of '" + first.name() + "' is corrupt: sha256 " + actual +
                                                    " != declared " + expected_sha);
    fs::rename(tmp, final_path);
    store::Artifact artifact{first.name(), final_path.string(), actual, size};
    store_.add_artifact(first.job_id(), first.worker_id(), artifact);
    v1::UploadArtifactResponse response;
    response.mutable_artifact()->set_name(artifact.name);
    response.mutable_artifact()->set_size_bytes(size);
    response.mutable_artifact()->set_sha256(actual);
    return response;
  } catch (...) {
    std::error_code ignored;
    fs::remove(tmp, ignored);
    throw;
  }
}

std::vector<std::string> JobService::reap_expired_leases() {
  auto ids = store_.requeue_expired(now_ms());
  if (!ids.empty()) {
    notifier_.notify();
    for (const auto& id : ids) spdlog::warn("job {}: lease expired, requeued or failed", id);
  }
  return ids;
}

grpc::Status to_status(const std::exception_ptr& error) {
  try {
    std::rethrow_exception(error);
  } catch (const ServiceError& e) {
    return {e.code(), e.what()};
  } catch (const store::StoreError& e) {
    switch (e.code()) {
      case store::StoreError::Code::kNotFound: return {StatusCode::NOT_FOUND, e.what()};
      case store::StoreError::Code::kFailedPrecondition: return {StatusCode::FAILED_PRECONDITION, e.what()};
      case store::StoreError::Code::kAlreadyExists: return {StatusCode::ALREADY_EXISTS, e.what()};
      case store::StoreError::Code::kInvalidArgument: return {StatusCode::INVALID_ARGUMENT, e.what()};
      case store::StoreError::Code::kInternal: return {StatusCode::INTERNAL, e.what()};
    }
    return {StatusCode::INTERNAL, e.what()};
  } catch (const InputError& e) {
    return {StatusCode::INVALID_ARGUMENT, e.what()};
  } catch (const std::exception& e) {
    spdlog::error("internal error: {}", e.what());
    return {StatusCode::INTERNAL, e.what()};
  } catch (...) {
    return {StatusCode::INTERNAL, "unknown error"};
  }
}

}  // namespace systole::service
