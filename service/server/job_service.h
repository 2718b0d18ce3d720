#pragma once
// The service's logic, independent of the transport: the gRPC services and the REST gateway
// both call this class with protobuf messages and turn a ServiceError into their own status.
// It owns nothing but references: the JobStore (durable state), the artifact directory and
// the change notifier that wakes watchers and long-polling workers.
#include <condition_variable>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <mutex>
#include <string>

#include <grpcpp/support/status.h>

#include "service/store/job_store.h"
#include "solver/config/scenario.h"
#include "systole/v1/service.pb.h"
#include "systole/v1/worker.pb.h"

namespace systole::service {

// An error for the client: a gRPC status code and a message that names what is wrong.
class ServiceError : public std::runtime_error {
 public:
  ServiceError(grpc::StatusCode code, const std::string& message)
      : std::runtime_error(message), code_(code) {}
  grpc::StatusCode code() const { return code_; }

 private:
  grpc::StatusCode code_;
};

// Wakes everyone waiting for "something changed in the store" (a counter + condvar).
class ChangeNotifier {
 public:
  uint64_t version() const;
  void notify();
  // Waits until version() != seen or the timeout passes; returns the current version.
  uint64_t wait_for_change(uint64_t seen, std::chrono::milliseconds timeout) const;

 private:
  mutable std::mutex mu_;
  mutable std::condition_variable cv_;
  uint64_t version_ = 0;  // guarded by mu_
};

struct ServiceOptions {
  std::filesystem::path data_dir;  // artifacts under data_dir/jobs/<id>/
  int64_t lease_ms = 15000;        // a worker must heartbeat within this
  int default_max_attempts = 3;
};

int64_t now_ms();

// The result-cache key of a validated scenario: sha256 of its canonical JSON (every default
// expanded, keys sorted) and the solver version and git revision. Jobs with equal keys compute
// the same result, so a finished one can be reused.
std::string cache_key(const config::Scenario& scenario);

class JobService {
 public:
  JobService(store::JobStore& store, ChangeNotifier& notifier, ServiceOptions options);

  // --- public API (systole.v1.Simulation) -------------------------------------------------
  v1::SubmitJobResponse submit(const v1::SubmitJobRequest& request);
  v1::Job get(const std::string& id);
  v1::ListJobsResponse list(const v1::ListJobsRequest& request);
  v1::Job cancel(const std::string& id);
  // Streams the snapshot, then every event, until the job is terminal and drained, or
  // `keep_going()` returns false (client gone), or `send` returns false.
  void watch(const v1::WatchJobRequest& request, const std::function<bool(const v1::JobEvent&)>& send,
             const std::function<bool()>& keep_going);
  v1::Result result(const std::string& id);
  // The artifact's path, size and sha256 after checking the job and the name.
  store::Artifact artifact(const std::string& id, const std::string& name);

  // --- worker API (systole.v1.WorkerApi) --------------------------------------------------
  // Waits up to `wait` for a queued job.
  v1::LeaseJobResponse lease(const v1::LeaseJobRequest& request, std::chrono::milliseconds wait);
  v1::HeartbeatResponse heartbeat(const v1::HeartbeatRequest& request);
  v1::HeartbeatResponse report_progress(const v1::ReportProgressRequest& request);
  v1::WorkerAck complete(const v1::CompleteJobRequest& request);
  v1::WorkerAck fail(const v1::FailJobRequest& request);
  v1::WorkerAck release(const v1::ReleaseJobRequest& request);
  // Called with the first message; `next` yields the following ones (false at the end).
  v1::UploadArtifactResponse upload(const v1::UploadArtifactRequest& first,
                                    const std::function<bool(v1::UploadArtifactRequest&)>& next);

  // Requeues jobs whose lease expired; the server calls it periodically.
  std::vector<std::string> reap_expired_leases();

  v1::Job to_proto(const store::JobRecord& record, bool with_scenario) const;

 private:
  std::filesystem::path job_dir(const std::string& id) const;

  store::JobStore& store_;
  ChangeNotifier& notifier_;
  ServiceOptions options_;
};

// Maps every exception a JobService call can throw onto a gRPC status.
grpc::Status to_status(const std::exception_ptr& error);

// Runs `body` and returns OK or the mapped status.
template <class Body>
grpc::Status guarded(Body&& body) {
  try {
    body();
    return grpc::Status::OK;
  } catch (...) {
    return to_status(std::current_exception());
  }
}

}  // namespace systole::service
