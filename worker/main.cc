// systole-worker: an MPI program. Rank 0 leases a job from the server, broadcasts the
// validated scenario, every rank runs the scene, rank 0 writes and uploads the results and
// completes the job; then it leases the next one. Heartbeats (with progress) go out every
// second from a helper thread on rank 0; a cancel request stops the run within ~1 s plus one
// scene check; SIGTERM, SIGINT or SIGUSR1 (forwarded by mpirun) gives the current job back
// (ReleaseJob) and exits.
#include <mpi.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <thread>

#include <CLI/CLI.hpp>
#include <grpcpp/grpcpp.h>
#include <spdlog/spdlog.h>

#include "proto/bridge/scenario_bridge.h"
#include "service/server/sha256.h"
#include "solver/core/allocator.h"
#include "solver/core/errors.h"
#include "solver/core/threads.h"
#include "solver/core/version.h"
#include "solver/io/result_writer.h"
#include "solver/scene/scene.h"
#include "systole/v1/worker.grpc.pb.h"
#include "worker/result_proto.h"

namespace fs = std::filesystem;
using namespace systole;

namespace {

std::atomic<bool> g_terminate{false};  // set by the SIGTERM/SIGINT handler only (async-signal-safe)
void on_signal(int) { g_terminate = true; }

// What rank 0 tells the other ranks before each job.
enum Command : int { kRunJob = 1, kShutdown = 2 };

// MPI_Bcast that sleeps while it waits: idle ranks > 0 wait here between jobs and must not
// spin a core (Open MPI busy-polls inside a blocking MPI_Bcast).
void broadcast_int_idle(int* value, MPI_Comm comm) {
  MPI_Request request;
  MPI_Ibcast(value, 1, MPI_INT, 0, comm, &request);
  int done = 0;
  while (true) {
    MPI_Test(&request, &done, MPI_STATUS_IGNORE);
    if (done) return;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
}

void broadcast_string(std::string& text, MPI_Comm comm) {
  long long size = static_cast<long long>(text.size());
  MPI_Bcast(&size, 1, MPI_LONG_LONG, 0, comm);
  text.resize(static_cast<size_t>(size));
  MPI_Bcast(text.data(), static_cast<int>(size), MPI_CHAR, 0, comm);
}

// Rank 0's view of the server for one job, plus the heartbeat thread.
class JobSession {
 public:
  JobSession(v1::WorkerApi::Stub& stub, std::string worker_id, std::string job_id)
      : stub_(stub), worker_id_(std::move(worker_id)), job_id_(std::move(job_id)) {
    thread_ = std::thread([this] { beat(); });
  }
  ~JobSession() {
    {
      std::lock_guard lock(mu_);
      done_ = true;
    }
    wake_.notify_all();  // the beat thread must not hold up the next job
    thread_.join();
  }
  void set_progress(const ProgressReport& report) {
    std::lock_guard lock(mu_);
    progress_.set_simulated_time_s(report.simulated_time_s);
    progress_.set_beat(report.beat);
    progress_.set_beats_total(report.beats_total);
    progress_.set_fraction(report.fraction);
    progress_.set_message(report.message);
    progress_.mutable_latest_beat_metrics()->clear();
    for (const auto& [k, v] : report.latest_beat_metrics) (*progress_.mutable_latest_beat_metrics())[k] = v;
    fresh_progress_ = true;
  }
  // Sends the latest progress now if the heartbeat thread has not yet (short jobs).
  void flush() {
    bool fresh;
    {
      std::lock_guard lock(mu_);
      fresh = fresh_progress_;
    }
    if (fresh) send_heartbeat();
  }
  bool cancel_requested() const { return cancel_.load(); }
  bool lease_lost() const { return lease_lost_.load(); }

 private:
  // One heartbeat (with progress when there is new progress) per second until done.
  void beat() {
    std::unique_lock lock(mu_);
    while (!done_) {
      if (wake_.wait_for(lock, std::chrono::milliseconds(1000), [&] { return done_.load(); })) break;
      lock.unlock();
      send_heartbeat();
      lock.lock();
    }
  }
  void send_heartbeat() {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(5));
    v1::HeartbeatResponse answer;
    grpc::Status status;
    v1::ReportProgressRequest progress;
    {
      std::lock_guard lock(mu_);
      if (fresh_progress_) {
        progress.set_worker_id(worker_id_);
        progress.set_job_id(job_id_);
        *progress.mutable_progress() = progress_;
        fresh_progress_ = false;
      }
    }
    if (!progress.job_id().empty()) {
      status = stub_.ReportProgress(&context, progress, &answer);
    } else {
      v1::HeartbeatRequest request;
      request.set_worker_id(worker_id_);
      request.set_job_id(job_id_);
      status = stub_.Heartbeat(&context, request, &answer);
    }
    if (!status.ok()) {
      spdlog::warn("heartbeat for {} failed: {}", job_id_, status.error_message());
      return;  // keep trying; the lease may still be valid when the server is back
    }
    if (!answer.lease_valid()) lease_lost_ = true;
    if (answer.cancel_requested()) cancel_ = true;
  }

  v1::WorkerApi::Stub& stub_;
  const std::string worker_id_;
  const std::string job_id_;
  std::mutex mu_;
  v1::Progress progress_;        // guarded by mu_
  bool fresh_progress_ = false;  // guarded by mu_
  std::atomic<bool> cancel_{false};
  std::atomic<bool> lease_lost_{false};
  std::atomic<bool> done_{false};  // written under mu_
  std::condition_variable wake_;
  std::thread thread_;
};

// RunControl for every rank: rank 0 decides, the decision is broadcast (collective).
class WorkerControl final : public scene::RunControl {
 public:
  WorkerControl(MPI_Comm comm, JobSession* session, fs::path output, fs::path checkpoints)
      : comm_(comm), session_(session), output_(std::move(output)), checkpoints_(std::move(checkpoints)) {}
  // Where a scene writes extra files (3-D fields); rank 0 uploads every file found there.
  fs::path output_directory() override { return output_; }
  // Per job, kept across attempts (--checkpoint-dir/<job>): a requeued job resumes there.
  fs::path checkpoint_directory() override { return checkpoints_; }
  void on_progress(const ProgressReport& report) override {
    if (session_) session_->set_progress(report);
  }
  bool cancel_requested() override {
    int stop = 0;
    if (session_) stop = (session_->cancel_requested() || session_->lease_lost() || g_terminate) ? 1 : 0;
    MPI_Bcast(&stop, 1, MPI_INT, 0, comm_);
    return stop != 0;
  }

 private:
  MPI_Comm comm_;
  JobSession* session_;  // rank 0 only
  fs::path output_, checkpoints_;
};

grpc::Status upload(v1::WorkerApi::Stub& stub, const std::string& worker_id, const std::string& job_id,
                    const fs::path& file) {
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::minutes(10));
  v1::UploadArtifactResponse response;
  auto writer = stub.UploadArtifact(&context, &response);
  std::ifstream in(file, std::ios::binary);
  std::string buffer(1 << 20, '\0');
  const std::string sha = service::sha256_of_file(file);
  bool first = true;
  while (true) {
    in.read(buffer.data(), static_cast<std::streamsize>(buffer.size()));
    const auto n = static_cast<size_t>(in.gcount());
    v1::UploadArtifactRequest chunk;
    if (first) {
      chunk.set_worker_id(worker_id);
      chunk.set_job_id(job_id);
      chunk.set_name(file.filename().string());
      first = false;
    }
    chunk.set_data(buffer.data(), n);
    if (!in) chunk.set_sha256(sha);
    if (!writer->Write(chunk)) break;
    if (!in) break;
  }
  writer->WritesDone();
  return writer->Finish();
}

template <class Request, class Response>
grpc::Status call(v1::WorkerApi::Stub& stub,
                  grpc::Status (v1::WorkerApi::Stub::*method)(grpc::ClientContext*, const Request&, Response*),
                  const Request& request, Response* response, int timeout_s = 10) {
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(timeout_s));
  return (stub.*method)(&context, request, response);
}

// Rank 0: reports the outcome of one job. Retries while the server is unreachable.
template <class Request>
void report(v1::WorkerApi::Stub& stub,
            grpc::Status (v1::WorkerApi::Stub::*method)(grpc::ClientContext*, const Request&, v1::WorkerAck*),
            const Request& request, const char* what) {
  // Stopping (SIGTERM): a few tries only; an unreported job's lease expires on the server.
  const int attempts = g_terminate ? 3 : 30;
  for (int attempt = 0; attempt < attempts; ++attempt) {
    v1::WorkerAck ack;
    const auto status = call(stub, method, request, &ack);
    if (status.ok()) return;
    if (status.error_code() != grpc::StatusCode::UNAVAILABLE) {
      spdlog::error("{} for {} rejected: {}", what, request.job_id(), status.error_message());
      return;
    }
    std::this_thread::sleep_for(std::chrono::seconds(1));
  }
  spdlog::error("{} for {}: server unreachable, giving up (the lease will expire)", what, request.job_id());
}

// Runs one job on every rank. Rank 0 talks to the server.
void run_job(MPI_Comm comm, int rank, v1::WorkerApi::Stub* stub, const std::string& worker_id,
             const std::string& job_id, const std::string& scenario_text, const fs::path& scratch,
             const fs::path& checkpoint_root) {
  std::unique_ptr<JobSession> session;
  if (rank == 0) session = std::make_unique<JobSession>(*stub, worker_id, job_id);
  const fs::path dir = scratch / job_id;
  if (rank == 0) fs::create_directories(dir);
  // Rank 0 removes the job's scratch files whatever the outcome (after the uploads).
  struct RemoveOnExit {
    fs::path path;
    ~RemoveOnExit() {
      std::error_code ignored;
      if (!path.empty()) fs::remove_all(path, ignored);
    }
  } cleanup{rank == 0 ? dir : fs::path()};
  // The job's checkpoints (scenes fsi, fsei) outlive this attempt: a job released by a stopping
  // worker, failed retryably or requeued after a crash resumes from them on its next lease.
  // They go once the job is finished for good (done, failed for good, cancelled by its client).
  const fs::path checkpoints = checkpoint_root / job_id;
  auto drop_checkpoints = [&] {
    std::error_code ignored;
    fs::remove_all(checkpoints, ignored);
  };
  MPI_Barrier(comm);
  WorkerControl control(comm, session.get(), dir, checkpoints);
  enum class Outcome { kDone, kCancelled, kFailed, kFatal } outcome = Outcome::kDone;
  std::string error;
  RunResult result;
  config::Scenario scenario;
  try {
    scenario = bridge::validate(bridge::scenario_proto_from_json_text(scenario_text));
    result = scene::run(scenario, control);
  } catch (const scene::Cancelled&) {
    outcome = Outcome::kCancelled;
  } catch (const InputError& e) {
    outcome = Outcome::kFatal;
    error = std::string("invalid scenario: ") + e.what();
  } catch (const InstabilityError& e) {
    outcome = Outcome::kFatal;
    error = e.what();
  } catch (const std::exception& e) {
    outcome = Outcome::kFailed;
    error = e.what();
  }
  if (rank != 0) return;

  v1::ReleaseJobRequest release;
  release.set_worker_id(worker_id);
  release.set_job_id(job_id);
  if (session->lease_lost()) {
    spdlog::warn("job {}: lease lost, dropping the run", job_id);
    return;
  }
  if (outcome == Outcome::kCancelled) {
    const bool by_client = session->cancel_requested();
    if (by_client) drop_checkpoints();
    release.set_cancelled(by_client);
    session.reset();
    report(*stub, &v1::WorkerApi::Stub::ReleaseJob, release, by_client ? "cancel" : "release");
    spdlog::info("job {} {}", job_id, by_client ? "cancelled" : "released (worker stopping)");
    return;
  }
  if (outcome == Outcome::kDone) {
    try {
      (void)io::write_results(dir, result, {config::to_json(scenario).dump(), job_id});
      std::vector<fs::path> files;  // the three result files and whatever the scene wrote (fields)
      for (const auto& entry : fs::directory_iterator(dir))
        if (entry.is_regular_file() && entry.path().extension() != ".tmp") files.push_back(entry.path());
      std::sort(files.begin(), files.end());
      for (const auto& file : files) {
        const auto status = upload(*stub, worker_id, job_id, file);
        if (!status.ok()) throw std::runtime_error("upload of " + file.filename().string() + ": " + status.error_message());
      }
      v1::CompleteJobRequest complete;
      complete.set_worker_id(worker_id);
      complete.set_job_id(job_id);
      *complete.mutable_result() = worker::to_proto(result);
      session->flush();
      session.reset();
      report(*stub, &v1::WorkerApi::Stub::CompleteJob, complete, "complete");
      drop_checkpoints();
      spdlog::info("job {} done: EF {:.1f} %, CO {:.2f} l/min", job_id, result.metrics["ejection_fraction_percent"],
                   result.metrics["cardiac_output_l_min"]);
      return;
    } catch (const std::exception& e) {
      outcome = Outcome::kFailed;
      error = std::string("writing results: ") + e.what();
    }
  }
  v1::FailJobRequest fail;
  fail.set_worker_id(worker_id);
  fail.set_job_id(job_id);
  fail.set_error(error);
  fail.set_retryable(outcome == Outcome::kFailed);
  if (outcome != Outcome::kFailed) drop_checkpoints();
  session.reset();
  report(*stub, &v1::WorkerApi::Stub::FailJob, fail, "fail");
  spdlog::error("job {} failed ({}): {}", job_id, outcome == Outcome::kFailed ? "retryable" : "final", error);
}

}  // namespace

int main(int argc, char** argv) {
  const bool heap_policy = systole::keep_freed_memory_in_heap();  // before any large array
  int provided = 0;
  MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);
  int rank = 0;
  int size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  if (!heap_policy && rank == 0)
    spdlog::warn("glibc refused the heap policy (solver/core/allocator.h): large jobs will be slower, values unchanged");
  // The server's local workers get OMP_NUM_THREADS (service/server/local_workers.cc); a worker
  // started by hand under mpirun shares the node's cores among its ranks (solver/core/threads.h).
  const systole::OpenMpThreads omp = systole::share_cores_among_ranks(MPI_COMM_WORLD);
  if (rank == 0) spdlog::info("{}", omp.describe());

  CLI::App app{"systole-worker: runs systole jobs leased from a systole-server (start it under mpirun)"};
  std::string server = "127.0.0.1:50051";
  std::string worker_id;
  std::string scratch_dir, checkpoint_dir;
  int max_jobs = 0;
  app.add_option("--server", server, "server gRPC address")->capture_default_str();
  app.add_option("--worker-id", worker_id, "name in leases and logs (default: host-pid)");
  app.add_option("--scratch", scratch_dir, "where results are written before upload (default: a temp dir)");
  app.add_option("--checkpoint-dir", checkpoint_dir,
                 "where jobs keep checkpoints across attempts (scenes fsi, fsei), one subdirectory per job; shared by "
                 "the workers that may take over a job (default: <temp dir>/systole-checkpoints)");
  app.add_option("--max-jobs", max_jobs, "exit after this many jobs (0: never)")->capture_default_str();
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = rank == 0 ? app.exit(e) : 1;
    MPI_Finalize();
    return code;
  }
  spdlog::set_pattern("%Y-%m-%dT%H:%M:%S.%e %^%l%$ worker " + std::to_string(rank) + " %v");
  struct sigaction action {};
  action.sa_handler = on_signal;
  sigaction(SIGTERM, &action, nullptr);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGUSR1, &action, nullptr);  // what systole-server sends its local workers to drain

  if (worker_id.empty()) {
    char host[256] = "host";
    gethostname(host, sizeof host - 1);
    worker_id = std::string(host) + "-" + std::to_string(getpid());
  }
  const fs::path scratch = scratch_dir.empty() ? fs::temp_directory_path() / ("systole-worker-" + worker_id) : fs::path(scratch_dir);
  const fs::path checkpoint_root =
      checkpoint_dir.empty() ? fs::temp_directory_path() / "systole-checkpoints" : fs::path(checkpoint_dir);

  std::unique_ptr<v1::WorkerApi::Stub> stub;
  if (rank == 0) {
    grpc::ChannelArguments args;
    args.SetMaxReceiveMessageSize(64 << 20);
    stub = v1::WorkerApi::NewStub(grpc::CreateCustomChannel(server, grpc::InsecureChannelCredentials(), args));
    spdlog::info("systole-worker {} ({}) id {} with {} ranks, server {}", kVersion, kGitRevision, worker_id, size, server);
  }

  int jobs_done = 0;
  int backoff_ms = 200;
  while (true) {
    int command = kShutdown;
    std::string job_id;
    std::string scenario_text;
    if (rank == 0) {
      while (!g_terminate) {
        v1::LeaseJobRequest request;
        request.set_worker_id(worker_id);
        request.set_wait_ms(2000);
        v1::LeaseJobResponse response;
        const auto status = call(*stub, &v1::WorkerApi::Stub::LeaseJob, request, &response, 10);
        if (!status.ok()) {
          spdlog::warn("lease: {} (retrying in {} ms)", status.error_message(), backoff_ms);
          std::this_thread::sleep_for(std::chrono::milliseconds(backoff_ms));
          backoff_ms = std::min(backoff_ms * 2, 5000);
          continue;
        }
        backoff_ms = 200;
        if (!response.has_job()) continue;
        job_id = response.job_id();
        scenario_text = bridge::to_json_text(response.scenario());
        if (g_terminate) {  // leased while stopping: give it straight back
          v1::ReleaseJobRequest release;
          release.set_worker_id(worker_id);
          release.set_job_id(job_id);
          report(*stub, &v1::WorkerApi::Stub::ReleaseJob, release, "release");
          break;
        }
        command = kRunJob;
        spdlog::info("job {} leased (attempt {})", job_id, response.attempt());
        break;
      }
    }
    broadcast_int_idle(&command, MPI_COMM_WORLD);
    if (command == kShutdown) break;
    broadcast_string(job_id, MPI_COMM_WORLD);
    broadcast_string(scenario_text, MPI_COMM_WORLD);
    run_job(MPI_COMM_WORLD, rank, stub.get(), worker_id, job_id, scenario_text, scratch, checkpoint_root);
    ++jobs_done;
    if (max_jobs > 0 && jobs_done >= max_jobs) break;
    int stop = g_terminate ? 1 : 0;
    broadcast_int_idle(&stop, MPI_COMM_WORLD);  // ranks > 0 wait here while rank 0 uploads
    if (stop) break;
  }
  if (rank == 0) spdlog::info("worker {} stopping after {} jobs", worker_id, jobs_done);
  MPI_Finalize();
  return 0;
}
