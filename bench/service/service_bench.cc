// service_bench: throughput and submit latency of a real systole-server with real local MPI
// workers, on 127.0.0.1. A benchmark, not a test: it prints Markdown tables (and writes them
// to --out if given); every server runs in its own temp dir, removed afterwards.
//
//   1. components   in-process probes that explain the end-to-end numbers (components.h)
//   2. idle server  --local-workers 0: SubmitJob latency (1 and --clients threads), GetJob as a
//                   no-commit baseline, and a replay of the worker protocol by this process
//                   (LeaseJob, Heartbeat, 3 x UploadArtifact, ReportProgress, CompleteJob)
//   3. throughput   per --ranks value and scenario variant: a fresh server with --workers
//                   local workers; --jobs submits from --clients threads as fast as possible;
//                   time from the first submit until no job is QUEUED or RUNNING (two
//                   ListJobs(page_size=1) calls per poll), then every job is listed once to
//                   count SUCCEEDED/FAILED and to split the time per job (queue wait, service
//                   time, the gap between a worker's jobs).
//
//   service_bench [--jobs 1000] [--clients 4] [--workers 2] [--ranks 1,2] [--variants full,no_ts]
//                 [--bin-dir DIR] [--quiet-wait-s 60] [--out results.md]        (--help: all flags)
// On a shared machine, --quiet-wait-s waits for other processes to calm down before each phase;
// the report's "other processes" column shows how much CPU they took anyway.
#include <signal.h>
#include <sys/utsname.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <functional>
#include <iostream>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <thread>
#include <tuple>

#include <CLI/CLI.hpp>
#include <google/protobuf/util/json_util.h>
#include <grpcpp/grpcpp.h>

#include "bench/service/bench_server.h"
#include "bench/service/components.h"
#include "bench/service/stats.h"
#include "service/server/sha256.h"
#include "systole/v1/service.grpc.pb.h"
#include "systole/v1/worker.grpc.pb.h"
#include "worker/result_proto.h"

#ifndef SYSTOLE_BENCH_BIN_DIR
#define SYSTOLE_BENCH_BIN_DIR "bin"
#endif
#ifndef SYSTOLE_SOURCE_DIR
#define SYSTOLE_SOURCE_DIR "."
#endif

using namespace systole;
using namespace systole::bench;

namespace {

struct Options {
  int jobs = 1000;
  int clients = 4;
  int workers = 2;
  std::vector<int> ranks{1, 2};
  std::vector<std::string> variants{"full", "no_ts"};
  int idle_submits = 1000;
  int replay_jobs = 200;
  int component_reps = 30;
  fs::path bin_dir = SYSTOLE_BENCH_BIN_DIR;
  int64_t lease_ms = 15000;
  int timeout_s = 240;
  int poll_ms = 10;
  int quiet_wait_s = 0;
  int attempts = 2;
  std::string out;
  bool keep_dirs = false;
  bool skip_components = false;
  bool skip_idle = false;
  bool allow_cache = false;
};

// Set by the signal thread on SIGINT/SIGTERM; the waiting loops below then throw Interrupted,
// and unwinding stops the servers and removes their temp dirs.
std::atomic<bool> g_interrupted{false};
void check_interrupted() {
  if (g_interrupted) throw Interrupted();
}

// ---- small helpers ------------------------------------------------------------------------

std::string scenario_json(const std::string& variant) {
  if (variant == "full") return R"({"scene":"lumped"})";
  if (variant == "no_ts") return R"({"scene":"lumped","outputs":{"time_series":false}})";
  throw std::invalid_argument("unknown variant '" + variant + "' (full, no_ts)");
}

v1::Scenario scenario_proto(const std::string& variant) {
  v1::Scenario scenario;
  const auto status = google::protobuf::util::JsonStringToMessage(scenario_json(variant), &scenario);
  if (!status.ok()) throw std::runtime_error("scenario: " + std::string(status.message()));
  return scenario;
}

int64_t epoch_ms() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

void set_deadline(grpc::ClientContext& context, int seconds = 30) {
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(seconds));
}

std::string shell_output(const std::string& command) {
  std::string out;
  FILE* pipe = ::popen(command.c_str(), "r");
  if (!pipe) return "";
  char buffer[512];
  size_t n;
  while ((n = fread(buffer, 1, sizeof buffer, pipe)) > 0) out.append(buffer, n);
  ::pclose(pipe);
  while (!out.empty() && (out.back() == '\n' || out.back() == ' ')) out.pop_back();
  return out;
}

std::string cpu_model() {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("model name", 0) == 0) return line.substr(line.find(':') + 2);
  return "?";
}

// The mount (device, fs type) that holds `path`: the longest mount point prefix.
std::string filesystem_of(const fs::path& path) {
  std::ifstream in("/proc/mounts");
  std::string device, mount, type, rest, best_mount, best;
  const std::string p = fs::canonical(path).string();
  while (in >> device >> mount >> type && std::getline(in, rest)) {
    if (p.rfind(mount, 0) == 0 && mount.size() >= best_mount.size()) {
      best_mount = mount;
      best = device + " (" + type + ") on " + mount;
    }
  }
  return best;
}

// CPU seconds (user + system) of one process.
double process_cpu_s(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  std::string stat((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto paren = stat.rfind(')');
  if (paren == std::string::npos) return 0;
  std::istringstream fields(stat.substr(paren + 2));
  std::string field;
  double ticks = 0;
  for (int i = 3; fields >> field; ++i) {
    if (i == 14 || i == 15) ticks += std::stod(field);
    if (i == 15) break;
  }
  return ticks / static_cast<double>(::sysconf(_SC_CLK_TCK));
}

// The systole-worker ranks and mpirun processes that serve `address`.
struct WorkerPids {
  std::vector<pid_t> ranks, mpirun;
};
WorkerPids worker_pids(const std::string& address) {
  WorkerPids out;
  for (const auto& entry : fs::directory_iterator("/proc")) {
    const std::string name = entry.path().filename().string();
    if (name.find_first_not_of("0123456789") != std::string::npos) continue;
    std::ifstream in(entry.path() / "cmdline");
    std::string cmdline((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    for (char& c : cmdline)
      if (c == '\0') c = ' ';
    if (cmdline.find("--server " + address + " ") == std::string::npos) continue;
    (cmdline.rfind("mpirun", 0) == 0 ? out.mpirun : out.ranks).push_back(std::stoi(name));
  }
  return out;
}
double cpu_s(const std::vector<pid_t>& pids) {
  double total = 0;
  for (pid_t p : pids) total += process_cpu_s(p);
  return total;
}

// Whole-machine CPU ticks from /proc/stat: busy (user+nice+system+irq+softirq+steal), idle, iowait.
struct MachineTicks {
  double busy = 0, idle = 0, iowait = 0;
};
MachineTicks machine_ticks() {
  std::ifstream in("/proc/stat");
  std::string cpu;
  double user, nice, system, idle, iowait, irq, softirq, steal = 0;
  in >> cpu >> user >> nice >> system >> idle >> iowait >> irq >> softirq >> steal;
  return {user + nice + system + irq + softirq + steal, idle, iowait};
}

// Waits up to max_s seconds until the whole machine was less than 25 % busy during one second,
// so that other processes (builds on a shared machine) stay out of the numbers. Returns the
// busy % of the last second measured.
double wait_for_quiet_machine(int max_s) {
  const auto deadline = Clock::now() + std::chrono::seconds(max_s);
  double busy = 100;
  int waited = 0;
  do {
    check_interrupted();
    const auto a = machine_ticks();
    std::this_thread::sleep_for(std::chrono::seconds(1));
    const auto b = machine_ticks();
    const double total = (b.busy - a.busy) + (b.idle - a.idle) + (b.iowait - a.iowait);
    busy = total > 0 ? 100.0 * (b.busy - a.busy) / total : 0;
    if (busy < 25) break;
    if (++waited % 10 == 1)
      std::cerr << "  machine " << static_cast<int>(busy) << " % busy; waiting up to " << max_s
                << " s for it to calm down ...\n";
  } while (Clock::now() < deadline);
  return busy;
}

// The result cache (SubmitJobRequest.no_cache, Job.cached_from) is not in every version of the
// API: reach those fields by name so that the bench builds either way. The bench sets no_cache
// unless --allow-cache, because 1000 identical scenarios would otherwise be served from the
// cache after the first one ran, and the workers would not be measured.
bool set_bool_field(google::protobuf::Message& message, const char* name, bool value) {
  const auto* field = message.GetDescriptor()->FindFieldByName(name);
  if (field == nullptr || field->cpp_type() != google::protobuf::FieldDescriptor::CPPTYPE_BOOL || field->is_repeated())
    return false;
  message.GetReflection()->SetBool(&message, field, value);
  return true;
}
std::string string_field(const google::protobuf::Message& message, const char* name) {
  const auto* field = message.GetDescriptor()->FindFieldByName(name);
  if (field == nullptr || field->cpp_type() != google::protobuf::FieldDescriptor::CPPTYPE_STRING ||
      field->is_repeated())
    return "";
  return message.GetReflection()->GetString(message, field);
}
bool g_no_cache = true;  // --allow-cache clears it

// ---- client operations --------------------------------------------------------------------

struct SubmitBurst {
  std::vector<double> latency_ms;
  std::vector<std::string> ids;
  int errors = 0;
  std::string first_error;
  double wall_ms = 0;
  int64_t first_submit_epoch_ms = 0;
  Clock::time_point first_submit;  // after the clients connected
};

// `total` SubmitJob calls from `clients` threads (each with its own connection), back to back.
SubmitBurst submit_burst(const BenchServer& server, const v1::Scenario& scenario, int total, int clients) {
  SubmitBurst burst;
  std::vector<std::unique_ptr<v1::Simulation::Stub>> stubs;
  for (int c = 0; c < clients; ++c) {
    stubs.push_back(v1::Simulation::NewStub(server.new_channel(c)));
    // Connect before the clock starts: the first call must not pay for the TCP handshake.
    v1::ListJobsRequest request;
    request.set_page_size(1);
    v1::ListJobsResponse response;
    grpc::ClientContext context;
    set_deadline(context);
    (void)stubs.back()->ListJobs(&context, request, &response);
  }
  std::atomic<int> next{0};
  std::mutex mu;
  v1::SubmitJobRequest request;
  *request.mutable_scenario() = scenario;
  if (g_no_cache) set_bool_field(request, "no_cache", true);
  const auto t0 = Clock::now();
  burst.first_submit = t0;
  burst.first_submit_epoch_ms = epoch_ms();
  std::vector<std::thread> threads;
  for (int c = 0; c < clients; ++c) {
    threads.emplace_back([&, c] {
      std::vector<double> latency;
      std::vector<std::string> ids;
      int errors = 0;
      std::string first_error;
      while (!g_interrupted && next.fetch_add(1) < total) {
        v1::SubmitJobResponse response;
        grpc::ClientContext context;
        set_deadline(context);
        const auto start = Clock::now();
        const auto status = stubs[c]->SubmitJob(&context, request, &response);
        latency.push_back(ms_since(start));
        if (status.ok()) {
          ids.push_back(response.job().id());
        } else if (errors++ == 0) {
          first_error = status.error_message();
        }
      }
      std::lock_guard lock(mu);
      burst.latency_ms.insert(burst.latency_ms.end(), latency.begin(), latency.end());
      burst.ids.insert(burst.ids.end(), ids.begin(), ids.end());
      if (burst.errors == 0 && errors > 0) burst.first_error = first_error;
      burst.errors += errors;
    });
  }
  for (auto& t : threads) t.join();
  burst.wall_ms = ms_since(t0);
  check_interrupted();
  return burst;
}

bool any_in_state(v1::Simulation::Stub& stub, v1::JobState state) {
  v1::ListJobsRequest request;
  request.set_state(state);
  request.set_page_size(1);
  v1::ListJobsResponse response;
  grpc::ClientContext context;
  set_deadline(context);
  const auto status = stub.ListJobs(&context, request, &response);
  if (!status.ok()) throw std::runtime_error("ListJobs: " + status.error_message());
  return response.jobs_size() > 0;
}

std::vector<v1::Job> list_all(v1::Simulation::Stub& stub) {
  std::vector<v1::Job> jobs;
  std::string token;
  do {
    v1::ListJobsRequest request;
    request.set_page_size(1000);
    request.set_page_token(token);
    v1::ListJobsResponse response;
    grpc::ClientContext context;
    set_deadline(context);
    const auto status = stub.ListJobs(&context, request, &response);
    if (!status.ok()) throw std::runtime_error("ListJobs: " + status.error_message());
    for (const auto& j : response.jobs()) jobs.push_back(j);
    token = response.next_page_token();
  } while (!token.empty());
  return jobs;
}

// Polls until no job is QUEUED or RUNNING; false on timeout.
bool wait_all_terminal(v1::Simulation::Stub& stub, std::chrono::milliseconds timeout, std::chrono::milliseconds poll) {
  const auto deadline = Clock::now() + timeout;
  while (Clock::now() < deadline) {
    check_interrupted();
    if (!any_in_state(stub, v1::QUEUED) && !any_in_state(stub, v1::RUNNING)) return true;
    std::this_thread::sleep_for(poll);
  }
  return false;
}

// job id → worker id, from the server's "job J leased by W (attempt N)" log lines.
std::map<std::string, std::string> leases_from_log(const std::string& log) {
  std::map<std::string, std::string> out;
  std::istringstream in(log);
  std::string line;
  while (std::getline(in, line)) {
    const auto job = line.find(" job j-");
    const auto by = line.find(" leased by ");
    const auto attempt = line.find(" (attempt ");
    if (job == std::string::npos || by == std::string::npos || attempt == std::string::npos || by < job) continue;
    out[line.substr(job + 5, by - job - 5)] = line.substr(by + 11, attempt - by - 11);
  }
  return out;
}

// ---- reports --------------------------------------------------------------------------------

struct ComponentReport {
  Summary fdatasync, sqlite_full, sqlite_normal, jobstore_submit;
  std::map<std::string, SceneProbe> scene;  // by variant
  std::map<int, Summary> mpirun;            // by ranks
};

struct IdleReport {
  Summary submit_1, submit_c, get_1;
  double submit_c_per_s = 0;
  int errors = 0;
  std::string first_error;
  double submit_server_cpu_ms = 0, get_server_cpu_ms = 0;  // per call
  std::map<std::string, Summary> replay;                   // by step
  std::map<std::string, double> replay_server_cpu_ms;      // by step, per call
  std::vector<std::string> replay_steps;
  int replay_done = 0;
  double busy_before_pct = -1;
  Summary fsync_before, fsync_after;  // fdatasync probe in the server's dir around the measurements
  double other_busy_pct = 0;          // CPU used by other processes during the submit/GetJob part, % of all CPUs
};

struct RunReport {
  int ranks = 1;
  std::string variant;
  int jobs = 0;
  double workers_ready_ms = 0, warmup_ms = 0;
  SubmitBurst burst;
  Summary submit;
  bool finished = false;
  double drain_ms = 0;              // first submit → no job QUEUED or RUNNING (polled)
  double wall_from_records_ms = 0;  // first submit → max finished_ms
  int succeeded = 0, failed = 0, cancelled = 0, other = 0, retried = 0, cached = 0;
  Summary queue_wait, service, end_to_end, lease_gap;
  std::map<std::string, int> per_worker;
  double server_cpu_s = 0, ranks_cpu_s = 0, mpirun_cpu_s = 0, bench_cpu_s = 0;
  double machine_busy_pct = 0, machine_iowait_pct = 0;
  double other_cpu_s = 0;       // machine busy CPU time not spent by the processes above
  std::string loadavg;          // /proc/loadavg before the run
  double busy_before_pct = -1;  // machine busy % in the second before the run (--quiet-wait-s)
  std::string failure_example;
  uintmax_t db_bytes = 0, wal_bytes = 0;  // after the run
  double jobs_per_s() const { return drain_ms > 0 ? succeeded / (drain_ms / 1000.0) : 0; }
};

// ---- phases ---------------------------------------------------------------------------------

ComponentReport run_components(const Options& o, const fs::path& dir) {
  ComponentReport r;
  std::cerr << "components: fdatasync, SQLite commits, JobStore::submit ...\n";
  r.fdatasync = probe_fdatasync(dir, 200);
  r.sqlite_full = probe_sqlite_commit(dir, "FULL", 300);
  r.sqlite_normal = probe_sqlite_commit(dir, "NORMAL", 300);
  r.jobstore_submit = probe_jobstore_submit(dir, scenario_json("full"), 300);
  for (const auto& v : o.variants) {
    std::cerr << "components: scene + result files, variant " << v << " ...\n";
    r.scene[v] = probe_scene(scenario_json(v), dir / ("scene-" + v), o.component_reps);
  }
  for (int ranks : o.ranks) {
    std::cerr << "components: mpirun -np " << ranks << " start-up ...\n";
    r.mpirun[ranks] = probe_mpirun(ranks, 5);
  }
  return r;
}

grpc::Status upload_file(v1::WorkerApi::Stub& stub, const std::string& worker_id, const std::string& job_id,
                         const fs::path& file) {
  grpc::ClientContext context;
  set_deadline(context, 60);
  v1::UploadArtifactResponse response;
  auto writer = stub.UploadArtifact(&context, &response);
  std::ifstream in(file, std::ios::binary);
  std::string buffer(1 << 20, '\0');
  const std::string sha = service::sha256_of_file(file);
  bool first = true;
  while (true) {
    in.read(buffer.data(), static_cast<std::streamsize>(buffer.size()));
    v1::UploadArtifactRequest chunk;
    if (first) {
      chunk.set_worker_id(worker_id);
      chunk.set_job_id(job_id);
      chunk.set_name(file.filename().string());
      first = false;
    }
    chunk.set_data(buffer.data(), static_cast<size_t>(in.gcount()));
    if (!in) chunk.set_sha256(sha);
    if (!writer->Write(chunk) || !in) break;
  }
  writer->WritesDone();
  return writer->Finish();
}

// This process plays a worker against an idle server: the same RPCs as systole-worker, with
// real result files, but no MPI, no scene and no heartbeat thread. Step by step (lease N jobs,
// then N heartbeats, then N uploads of result.h5, ...), so that the server's CPU time per RPC
// can be read from /proc/<pid>/stat (10 ms ticks) over N calls.
void replay_worker_protocol(const Options& o, BenchServer& server, const SceneProbe& scene, IdleReport& r) {
  auto stub = v1::WorkerApi::NewStub(server.new_channel(1000));
  const std::string worker_id = "bench-replay";
  std::vector<std::string> ids;
  auto step = [&](const std::string& name, const std::function<grpc::Status(const std::string& job_id)>& call,
                  int count) {
    std::vector<double> samples;
    const double cpu0 = process_cpu_s(server.pid());
    for (int k = 0; k < count; ++k) {
      const auto t0 = Clock::now();
      const auto status = call(k < static_cast<int>(ids.size()) ? ids[k] : std::string());
      samples.push_back(ms_since(t0));
      if (!status.ok()) throw std::runtime_error("replay " + name + ": " + status.error_message());
    }
    r.replay_steps.push_back(name);
    r.replay[name] = summarize(samples);
    r.replay_server_cpu_ms[name] = 1000.0 * (process_cpu_s(server.pid()) - cpu0) / std::max(1, count);
  };
  step(
      "LeaseJob",
      [&](const std::string&) {
        v1::LeaseJobRequest lease;
        lease.set_worker_id(worker_id);
        lease.set_wait_ms(0);
        v1::LeaseJobResponse leased;
        grpc::ClientContext context;
        set_deadline(context);
        const auto status = stub->LeaseJob(&context, lease, &leased);
        if (status.ok() && !leased.has_job()) return grpc::Status(grpc::StatusCode::NOT_FOUND, "no job to lease");
        ids.push_back(leased.job_id());
        return status;
      },
      o.replay_jobs);
  const int n = static_cast<int>(ids.size());
  step(
      "Heartbeat",
      [&](const std::string& job_id) {
        v1::HeartbeatRequest beat;
        beat.set_worker_id(worker_id);
        beat.set_job_id(job_id);
        v1::HeartbeatResponse answer;
        grpc::ClientContext context;
        set_deadline(context);
        return stub->Heartbeat(&context, beat, &answer);
      },
      n);
  for (const auto& f : scene.files)
    step(
        "UploadArtifact " + f.filename().string(),
        [&](const std::string& job_id) { return upload_file(*stub, worker_id, job_id, f); }, n);
  v1::ReportProgressRequest progress;
  progress.set_worker_id(worker_id);
  progress.mutable_progress()->set_beat(5);
  progress.mutable_progress()->set_beats_total(30);
  progress.mutable_progress()->set_fraction(1.0);
  progress.mutable_progress()->set_message("beat 5 done");
  (*progress.mutable_progress()->mutable_latest_beat_metrics())["ejection_fraction_percent"] = 60.0;
  step(
      "ReportProgress",
      [&](const std::string& job_id) {
        progress.set_job_id(job_id);
        v1::HeartbeatResponse answer;
        grpc::ClientContext context;
        set_deadline(context);
        return stub->ReportProgress(&context, progress, &answer);
      },
      n);
  v1::CompleteJobRequest complete;
  complete.set_worker_id(worker_id);
  *complete.mutable_result() = worker::to_proto(scene.result);
  step(
      "CompleteJob",
      [&](const std::string& job_id) {
        complete.set_job_id(job_id);
        v1::WorkerAck ack;
        grpc::ClientContext context;
        set_deadline(context);
        auto status = stub->CompleteJob(&context, complete, &ack);
        if (status.ok() && ack.job().state() != v1::SUCCEEDED)
          return grpc::Status(grpc::StatusCode::INTERNAL, "job not SUCCEEDED after CompleteJob");
        return status;
      },
      n);
  r.replay_done = n;
}

IdleReport run_idle(const Options& o, const ComponentReport* components) {
  IdleReport r;
  if (o.quiet_wait_s > 0) r.busy_before_pct = wait_for_quiet_machine(o.quiet_wait_s);
  TempDir dir("idle");
  if (o.keep_dirs) dir.keep();
  BenchServer server(dir.path(), {o.bin_dir, 0, 1, o.lease_ms});
  server.diagnosed([&] {
    const auto scenario = scenario_proto("full");
    std::cerr << "idle server: warm-up ...\n";
    (void)submit_burst(server, scenario, 20, 1);
    r.fsync_before = probe_fdatasync(dir.path(), 50);
    const auto ticks0 = machine_ticks();
    const double ours0 = process_cpu_s(server.pid()) + process_cpu_s(::getpid());
    const auto wall0 = Clock::now();
    std::cerr << "idle server: " << o.idle_submits << " submits from 1 client ...\n";
    double cpu0 = process_cpu_s(server.pid());
    auto one = submit_burst(server, scenario, o.idle_submits, 1);
    r.submit_server_cpu_ms = 1000.0 * (process_cpu_s(server.pid()) - cpu0) / std::max<size_t>(1, one.latency_ms.size());
    r.submit_1 = summarize(one.latency_ms);
    std::cerr << "idle server: " << o.idle_submits << " submits from " << o.clients << " clients ...\n";
    auto many = submit_burst(server, scenario, o.idle_submits, o.clients);
    r.submit_c = summarize(many.latency_ms);
    r.submit_c_per_s = many.latency_ms.size() / (many.wall_ms / 1000.0);
    r.errors = one.errors + many.errors;
    r.first_error = !one.first_error.empty() ? one.first_error : many.first_error;
    std::cerr << "idle server: GetJob baseline ...\n";
    {
      auto stub = v1::Simulation::NewStub(server.new_channel(0));
      std::vector<double> samples;
      cpu0 = process_cpu_s(server.pid());
      for (size_t i = 0; i < one.ids.size(); ++i) {
        v1::GetJobRequest request;
        request.set_id(one.ids[i]);
        v1::Job job;
        grpc::ClientContext context;
        set_deadline(context);
        const auto t0 = Clock::now();
        (void)stub->GetJob(&context, request, &job);
        samples.push_back(ms_since(t0));
      }
      r.get_1 = summarize(samples);
      r.get_server_cpu_ms = 1000.0 * (process_cpu_s(server.pid()) - cpu0) / std::max<size_t>(1, samples.size());
    }
    const double busy_s = (machine_ticks().busy - ticks0.busy) / static_cast<double>(::sysconf(_SC_CLK_TCK));
    const double ours_s = process_cpu_s(server.pid()) + process_cpu_s(::getpid()) - ours0;
    r.other_busy_pct = 100.0 * std::max(0.0, busy_s - ours_s) /
                       (ms_since(wall0) / 1000.0 * std::max(1u, std::thread::hardware_concurrency()));
    r.fsync_after = probe_fdatasync(dir.path(), 50);
    if (components != nullptr && components->scene.count("full") && o.replay_jobs > 0) {
      std::cerr << "idle server: worker protocol replay, " << o.replay_jobs << " jobs ...\n";
      replay_worker_protocol(o, server, components->scene.at("full"), r);
    }
  });
  server.stop();
  return r;
}

RunReport run_throughput(const Options& o, int ranks, const std::string& variant) {
  RunReport r;
  r.ranks = ranks;
  r.variant = variant;
  r.jobs = o.jobs;
  TempDir dir("w" + std::to_string(o.workers) + "r" + std::to_string(ranks) + "-" + variant);
  if (o.keep_dirs) dir.keep();
  const auto spawn = Clock::now();
  BenchServer server(dir.path(), {o.bin_dir, o.workers, ranks, o.lease_ms});
  server.diagnosed([&] {
    auto stub = v1::Simulation::NewStub(server.new_channel(999));

    // Ready: every worker's rank 0 has logged its start line (it long-polls LeaseJob next).
    const auto ready_deadline = Clock::now() + std::chrono::seconds(60);
    for (int slot = 0; slot < o.workers; ++slot) {
      while (BenchServer::read_file(server.worker_log_path(slot)).find("systole-worker ") == std::string::npos) {
        if (Clock::now() > ready_deadline)
          throw std::runtime_error("worker " + std::to_string(slot) + " not ready in 60 s");
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
      }
    }
    r.workers_ready_ms = ms_since(spawn);
    const auto scenario = scenario_proto(variant);
    if (o.quiet_wait_s > 0) r.busy_before_pct = wait_for_quiet_machine(o.quiet_wait_s);
    const auto warm = Clock::now();
    const auto warmup = submit_burst(server, scenario, 2 * o.workers, 1);
    if (!wait_all_terminal(*stub, std::chrono::seconds(60), std::chrono::milliseconds(o.poll_ms)))
      throw std::runtime_error("warm-up jobs did not finish in 60 s; log:\n" + server.log_tail());
    r.warmup_ms = ms_since(warm);

    const auto pids = worker_pids(server.address());
    const double server_cpu0 = process_cpu_s(server.pid());
    const double ranks_cpu0 = cpu_s(pids.ranks), mpirun_cpu0 = cpu_s(pids.mpirun),
                 bench_cpu0 = process_cpu_s(::getpid());
    const auto ticks0 = machine_ticks();
    r.loadavg = BenchServer::read_file("/proc/loadavg");
    if (!r.loadavg.empty() && r.loadavg.back() == '\n') r.loadavg.pop_back();

    std::cerr << "throughput: workers " << o.workers << " x ranks " << ranks << ", variant " << variant << ": "
              << o.jobs << " submits from " << o.clients << " clients ...\n";
    r.burst = submit_burst(server, scenario, o.jobs, o.clients);
    r.submit = summarize(r.burst.latency_ms);
    r.finished = wait_all_terminal(*stub, std::chrono::seconds(o.timeout_s), std::chrono::milliseconds(o.poll_ms));
    r.drain_ms = ms_since(r.burst.first_submit);

    const auto ticks1 = machine_ticks();
    r.server_cpu_s = process_cpu_s(server.pid()) - server_cpu0;
    r.ranks_cpu_s = cpu_s(pids.ranks) - ranks_cpu0;
    r.mpirun_cpu_s = cpu_s(pids.mpirun) - mpirun_cpu0;
    r.bench_cpu_s = process_cpu_s(::getpid()) - bench_cpu0;
    const double total = (ticks1.busy - ticks0.busy) + (ticks1.idle - ticks0.idle) + (ticks1.iowait - ticks0.iowait);
    r.other_cpu_s = (ticks1.busy - ticks0.busy) / static_cast<double>(::sysconf(_SC_CLK_TCK)) - r.server_cpu_s -
                    r.ranks_cpu_s - r.mpirun_cpu_s - r.bench_cpu_s;
    if (total > 0) {
      r.machine_busy_pct = 100.0 * (ticks1.busy - ticks0.busy) / total;
      r.machine_iowait_pct = 100.0 * (ticks1.iowait - ticks0.iowait) / total;
    }
    std::cerr << "  " << (r.finished ? "all terminal" : "TIMED OUT") << " after " << r.drain_ms / 1000 << " s\n";

    // Every job once: states and the per-job split of the time.
    const std::set<std::string> mine(r.burst.ids.begin(), r.burst.ids.end());
    const auto jobs = list_all(*stub);
    const auto leases = leases_from_log(BenchServer::read_file(server.log_path()));
    std::vector<double> queue_wait, service, end_to_end;
    std::map<std::string, std::vector<const v1::Job*>> by_worker;
    int64_t last_finish = 0;
    for (const auto& j : jobs) {
      if (!mine.count(j.id())) continue;
      switch (j.state()) {
        case v1::SUCCEEDED:
          ++r.succeeded;
          break;
        case v1::FAILED:
          ++r.failed;
          if (r.failure_example.empty()) r.failure_example = j.error();
          break;
        case v1::CANCELLED:
          ++r.cancelled;
          break;
        default:
          ++r.other;
      }
      if (j.attempts() > 1) ++r.retried;
      if (!string_field(j, "cached_from").empty()) ++r.cached;
      if (j.finished_ms() > 0) {
        last_finish = std::max(last_finish, j.finished_ms());
        queue_wait.push_back(static_cast<double>(j.started_ms() - j.created_ms()));
        service.push_back(static_cast<double>(j.finished_ms() - j.started_ms()));
        end_to_end.push_back(static_cast<double>(j.finished_ms() - j.created_ms()));
      }
      if (auto it = leases.find(j.id()); it != leases.end()) by_worker[it->second].push_back(&j);
    }
    r.failed += static_cast<int>(r.burst.ids.size()) < o.jobs ? o.jobs - static_cast<int>(r.burst.ids.size()) : 0;
    r.wall_from_records_ms = last_finish > 0 ? static_cast<double>(last_finish - r.burst.first_submit_epoch_ms) : 0;
    // Gap between a worker's consecutive jobs: previous finished_ms → next started_ms, counted
    // only when the next job was already queued (created) when the previous one finished.
    std::vector<double> gaps;
    for (auto& [worker, list] : by_worker) {
      r.per_worker[worker] = static_cast<int>(list.size());
      std::sort(list.begin(), list.end(),
                [](const v1::Job* a, const v1::Job* b) { return a->started_ms() < b->started_ms(); });
      for (size_t i = 1; i < list.size(); ++i)
        if (list[i]->created_ms() <= list[i - 1]->finished_ms())
          gaps.push_back(static_cast<double>(list[i]->started_ms() - list[i - 1]->finished_ms()));
    }
    r.queue_wait = summarize(queue_wait);
    r.service = summarize(service);
    r.end_to_end = summarize(end_to_end);
    r.lease_gap = summarize(gaps);
    std::tie(r.db_bytes, r.wal_bytes) = server.db_bytes();
  });
  server.stop();
  return r;
}

// ---- Markdown ------------------------------------------------------------------------------

std::string markdown(const Options& o, const ComponentReport* c, const IdleReport* idle,
                     const std::vector<RunReport>& runs) {
  std::ostringstream md;
  utsname un{};
  ::uname(&un);
  const std::string commit = shell_output("git -C " SYSTOLE_SOURCE_DIR " rev-parse --short HEAD 2>/dev/null");
  md << "## service_bench results\n\n";
  md << "- date: " << shell_output("date -u +%Y-%m-%dT%H:%M:%SZ") << "\n";
  md << "- commit: " << (commit.empty() ? "?" : commit) << " (working tree may contain uncommitted changes)\n";
  md << "- machine: nproc " << std::thread::hardware_concurrency() << ", CPU " << cpu_model() << ", kernel "
     << un.sysname << " " << un.release << " " << un.machine << "\n";
  md << "- temp dir: " << fs::temp_directory_path().string() << " on " << filesystem_of(fs::temp_directory_path())
     << "\n";
  md << "- server: `systole-server --local-workers " << o.workers << " --ranks R --lease-ms " << o.lease_ms
     << "` on 127.0.0.1 (bin dir " << o.bin_dir.string() << ")\n";
  md << "- load: " << o.jobs << " SubmitJob calls from " << o.clients
     << " client threads (one connection each); done = no job QUEUED or RUNNING (ListJobs page_size 1, every "
     << o.poll_ms << " ms)\n";
  {
    v1::SubmitJobRequest probe;
    const bool has_cache = probe.GetDescriptor()->FindFieldByName("no_cache") != nullptr;
    md << "- result cache: "
       << (!has_cache   ? "not in this API version"
           : g_no_cache ? "bypassed (SubmitJobRequest.no_cache = true)"
                        : "allowed (--allow-cache)")
       << "\n";
  }
  md << "- variants: full = `" << scenario_json("full") << "`, no_ts = `" << scenario_json("no_ts") << "`\n\n";

  if (!runs.empty()) {
    md << "### 1. Throughput (goal >= 50 jobs/s, 0 failed)\n\n";
    md << "| workers x ranks | variant | jobs | SUCCEEDED | of which cached | failed/other | first submit -> all done "
          "(s) | "
          "jobs/s | goal | submit wall (s) |\n";
    md << "|---|---|---:|---:|---:|---:|---:|---:|---|---:|\n";
    for (const auto& r : runs) {
      md << "| " << o.workers << " x " << r.ranks << " | " << r.variant << " | " << r.jobs << " | " << r.succeeded
         << " | " << r.cached << " | " << r.failed + r.cancelled + r.other << " ("
         << f1(100.0 * (r.jobs - r.succeeded) / r.jobs) << " %) | " << f2(r.drain_ms / 1000)
         << (r.finished ? "" : " (timeout)") << " | " << f1(r.jobs_per_s()) << " | "
         << (r.jobs_per_s() >= 50 && r.succeeded == r.jobs ? "met" : "**missed**") << " | "
         << f2(r.burst.wall_ms / 1000) << " |\n";
    }
    md << "\n";
  }

  md << "### 2. SubmitJob round-trip latency, ms (goal p99 <= 20 ms)\n\n";
  md << "| server | clients | n | p50 | p90 | p99 | max | submits/s | goal "
        "|\n|---|---:|---:|---:|---:|---:|---:|---:|---|\n";
  auto goal = [](const Summary& s) { return s.p99 <= 20 ? std::string("met") : std::string("**missed**"); };
  if (idle) {
    md << "| idle (0 workers) | 1 | " << idle->submit_1.n << " | " << latency_cells(idle->submit_1) << " | "
       << f1(1000.0 / idle->submit_1.mean) << " | " << goal(idle->submit_1) << " |\n";
    md << "| idle (0 workers) | " << o.clients << " | " << idle->submit_c.n << " | " << latency_cells(idle->submit_c)
       << " | " << f1(idle->submit_c_per_s) << " | " << goal(idle->submit_c) << " |\n";
  }
  for (const auto& r : runs)
    md << "| under load: " << o.workers << " x " << r.ranks << ", " << r.variant << " | " << o.clients << " | "
       << r.submit.n << " | " << latency_cells(r.submit) << " | " << f1(r.submit.n / (r.burst.wall_ms / 1000.0))
       << " | " << goal(r.submit) << " |\n";
  if (idle)
    md << "| idle, GetJob (read only, no commit) | 1 | " << idle->get_1.n << " | " << latency_cells(idle->get_1)
       << " | " << f1(1000.0 / idle->get_1.mean) << " | |\n";
  if (idle && idle->busy_before_pct >= 0)
    md << "\nmachine busy just before the idle-server phase: " << f1(idle->busy_before_pct) << " %\n";
  if (idle)
    md << "\nCPU used by other processes during the idle-server submits and GetJobs: " << f1(idle->other_busy_pct)
       << " % of the machine; write 4 KiB + fdatasync in the server's dir just before / after: p50 "
       << f2(idle->fsync_before.p50) << " / " << f2(idle->fsync_after.p50) << " ms, p99 " << f2(idle->fsync_before.p99)
       << " / " << f2(idle->fsync_after.p99) << " ms\n";
  if (idle && idle->errors > 0) md << "\nidle submit errors: " << idle->errors << " (" << idle->first_error << ")\n";
  md << "\n";

  if (!runs.empty()) {
    md << "### 3. Where a job's time goes (from the job records and the server log; ms)\n\n";
    md << "| workers x ranks | variant | service time started->finished p50 / p90 / min | queue wait p50 / max | "
          "gap between a worker's jobs p50 / p90 | jobs per worker | retried | wall by finished_ms (s) | db + wal "
          "after (MB) |\n";
    md << "|---|---|---|---|---|---|---:|---:|---:|\n";
    for (const auto& r : runs) {
      std::string per_worker;
      for (const auto& [w, n] : r.per_worker) per_worker += (per_worker.empty() ? "" : ", ") + std::to_string(n);
      md << "| " << o.workers << " x " << r.ranks << " | " << r.variant << " | " << f1(r.service.p50) << " / "
         << f1(r.service.p90) << " / " << f1(r.service.min) << " | " << f1(r.queue_wait.p50) << " / "
         << f1(r.queue_wait.max) << " | " << f1(r.lease_gap.p50) << " / " << f1(r.lease_gap.p90) << " | " << per_worker
         << " | " << r.retried << " | " << f2(r.wall_from_records_ms / 1000) << " | " << f1(r.db_bytes / 1e6) << " + "
         << f1(r.wal_bytes / 1e6) << " |\n";
    }
    md << "\n| workers x ranks | variant | CPU s: server | worker ranks | mpirun | bench (clients) | other processes "
          "| machine busy % | iowait % | server CPU ms/job | ranks CPU ms/job | workers ready after spawn (ms) | "
          "machine busy % just before | loadavg before |\n";
    md << "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|\n";
    for (const auto& r : runs) {
      md << "| " << o.workers << " x " << r.ranks << " | " << r.variant << " | " << f2(r.server_cpu_s) << " | "
         << f2(r.ranks_cpu_s) << " | " << f2(r.mpirun_cpu_s) << " | " << f2(r.bench_cpu_s) << " | " << f2(r.other_cpu_s)
         << " | " << f1(r.machine_busy_pct) << " | " << f1(r.machine_iowait_pct) << " | "
         << f2(1000 * r.server_cpu_s / std::max(1, r.jobs)) << " | " << f2(1000 * r.ranks_cpu_s / std::max(1, r.jobs))
         << " | " << f1(r.workers_ready_ms) << " | "
         << (r.busy_before_pct < 0 ? std::string("-") : f1(r.busy_before_pct)) << " | " << r.loadavg << " |\n";
    }
    for (const auto& r : runs)
      if (!r.failure_example.empty())
        md << "\nfailure example (" << r.ranks << " ranks, " << r.variant << "): " << r.failure_example << "\n";
    md << "\n";
  }

  if (idle && !idle->replay.empty()) {
    md << "### 4. Worker protocol replayed by the bench against the idle server (" << idle->replay_done
       << " jobs; no MPI, no scene, no heartbeat thread; ms)\n\n";
    md << "| RPC | p50 | p90 | p99 | max | mean | server CPU per call |\n|---|---:|---:|---:|---:|---:|---:|\n";
    double mean_sum = 0, cpu_sum = 0;
    for (const auto& step : idle->replay_steps) {
      const auto& s = idle->replay.at(step);
      const double cpu = idle->replay_server_cpu_ms.at(step);
      mean_sum += s.mean;
      cpu_sum += cpu;
      md << "| " << step << " | " << latency_cells(s) << " | " << f2(s.mean) << " | " << f2(cpu) << " |\n";
    }
    md << "| **sum per job** | | | | | " << f2(mean_sum) << " | " << f2(cpu_sum) << " |\n";
    md << "| (SubmitJob, idle, 1 client) | " << latency_cells(idle->submit_1) << " | " << f2(idle->submit_1.mean)
       << " | " << f2(idle->submit_server_cpu_ms) << " |\n";
    md << "| (GetJob, idle, 1 client) | " << latency_cells(idle->get_1) << " | " << f2(idle->get_1.mean) << " | "
       << f2(idle->get_server_cpu_ms) << " |\n\n";
  }

  if (c) {
    md << "### 5. Components, in process (ms)\n\n";
    md << "| component | p50 | p90 | p99 | max |\n|---|---:|---:|---:|---:|\n";
    md << "| write 4 KiB + fdatasync (temp dir's disk) | " << latency_cells(c->fdatasync) << " |\n";
    md << "| SQLite WAL commit of one row, synchronous=FULL | " << latency_cells(c->sqlite_full) << " |\n";
    md << "| SQLite WAL commit of one row, synchronous=NORMAL | " << latency_cells(c->sqlite_normal) << " |\n";
    md << "| JobStore::submit (as shipped) | " << latency_cells(c->jobstore_submit) << " |\n";
    for (const auto& [v, s] : c->scene) {
      md << "| " << v << ": validate scenario | " << latency_cells(s.validate_ms) << " |\n";
      md << "| " << v << ": scene::run (0-D) | " << latency_cells(s.run_ms) << " |\n";
      md << "| " << v << ": write result.h5 | " << latency_cells(s.write_h5_ms) << " |\n";
      md << "| " << v << ": write metrics.json | " << latency_cells(s.write_json_ms) << " |\n";
      md << "| " << v << ": write pv_loop.csv | " << latency_cells(s.write_csv_ms) << " |\n";
      md << "| " << v << ": io::write_results (all three) | " << latency_cells(s.write_all_ms) << " |\n";
    }
    for (const auto& [ranks, s] : c->mpirun)
      md << "| mpirun -np " << ranks << " /bin/true (launcher only) | " << latency_cells(s) << " |\n";
    md << "\n| variant | result.h5 bytes | metrics.json bytes | pv_loop.csv bytes | CompleteJob result bytes |\n";
    md << "|---|---:|---:|---:|---:|\n";
    for (const auto& [v, s] : c->scene) {
      auto bytes = [&](const char* name) {
        auto it = s.file_bytes.find(name);
        return it == s.file_bytes.end() ? std::string("-") : std::to_string(it->second);
      };
      md << "| " << v << " | " << bytes("result.h5") << " | " << bytes("metrics.json") << " | " << bytes("pv_loop.csv")
         << " | " << s.complete_request_bytes << " |\n";
    }
    md << "\n";
  }
  return md.str();
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  CLI::App app{"service_bench: job throughput and SubmitJob latency of systole-server with local MPI workers"};
  app.add_option("--jobs", o.jobs, "jobs per throughput run (0: no throughput runs)")
      ->check(CLI::Range(0, 100000))
      ->capture_default_str();
  app.add_option("--clients", o.clients, "submitting client threads")->check(CLI::Range(1, 64))->capture_default_str();
  app.add_option("--workers", o.workers, "--local-workers of the server in throughput runs")
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
  app.add_option("--ranks", o.ranks, "--ranks values to run (one throughput run per value and variant)")
      ->delimiter(',')
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
  app.add_option("--variants", o.variants, "scenario variants: full ({\"scene\":\"lumped\"}), no_ts (time_series off)")
      ->delimiter(',')
      ->check(CLI::IsMember({"full", "no_ts"}))
      ->capture_default_str();
  app.add_option("--idle-submits", o.idle_submits, "submits per idle-server latency measurement (0: skip)")
      ->check(CLI::Range(0, 100000))
      ->capture_default_str();
  app.add_option("--replay-jobs", o.replay_jobs, "jobs for the worker protocol replay (0: skip)")
      ->check(CLI::Range(0, 100000))
      ->capture_default_str();
  app.add_option("--component-reps", o.component_reps, "repetitions of the in-process scene/result-file probe")
      ->check(CLI::Range(1, 10000))
      ->capture_default_str();
  app.add_option("--bin-dir", o.bin_dir, "directory with systole-server and systole-worker")->capture_default_str();
  app.add_option("--lease-ms", o.lease_ms, "server --lease-ms")->capture_default_str();
  app.add_option("--timeout-s", o.timeout_s, "give up on a throughput run after this long")->capture_default_str();
  app.add_option("--poll-ms", o.poll_ms, "interval of the all-done poll")
      ->check(CLI::Range(1, 10000))
      ->capture_default_str();
  app.add_option("--quiet-wait-s", o.quiet_wait_s,
                 "before each phase, wait up to this long for the machine to be < 25 % busy (0: do not wait)")
      ->capture_default_str();
  app.add_option("--attempts", o.attempts, "tries per phase (a phase fails e.g. when its server is killed)")
      ->check(CLI::Range(1, 10))
      ->capture_default_str();
  app.add_option("--out", o.out, "also write the Markdown report to this file");
  app.add_flag("--keep-dirs", o.keep_dirs, "keep the servers' temp dirs (db, data, logs) for inspection");
  app.add_flag("--skip-components", o.skip_components, "skip the in-process component probes (and the replay)");
  app.add_flag("--allow-cache", o.allow_cache,
               "do not set SubmitJobRequest.no_cache (identical jobs may then be served from the result cache)");
  app.add_flag("--skip-idle", o.skip_idle, "skip the idle-server measurements");
  CLI11_PARSE(app, argc, argv);

  ::signal(SIGPIPE, SIG_IGN);
  // SIGINT/SIGTERM: blocked in every thread (set before any is started) and taken by one
  // thread, which asks the phases to stop; unwinding then cleans up.
  sigset_t stop_signals;
  sigemptyset(&stop_signals);
  sigaddset(&stop_signals, SIGINT);
  sigaddset(&stop_signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &stop_signals, nullptr);
  std::thread([stop_signals] {
    int signal_number = 0;
    sigwait(&stop_signals, &signal_number);
    g_interrupted = true;
  }).detach();
  g_no_cache = !o.allow_cache;
  ::setenv("OMPI_ALLOW_RUN_AS_ROOT", "1", 1);
  ::setenv("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1", 1);
  try {
    TempDir scratch("components");
    if (o.keep_dirs) scratch.keep();
    std::unique_ptr<ComponentReport> components;
    if (!o.skip_components) components = std::make_unique<ComponentReport>(run_components(o, scratch.path()));
    // A phase that throws (e.g. its server was killed from outside) is tried again, up to
    // --attempts times; what went wrong goes into the report.
    std::vector<std::string> incidents;
    auto attempt = [&](const std::string& what, const auto& f) -> bool {
      for (int i = 1; i <= o.attempts; ++i) {
        try {
          f();
          return true;
        } catch (const Interrupted&) {
          throw;
        } catch (const std::exception& e) {
          const std::string message = e.what();
          std::cerr << "service_bench: " << what << ", attempt " << i << ": " << message << "\n";
          incidents.push_back(what + ", attempt " + std::to_string(i) + ": " + message.substr(0, message.find('\n')));
        }
      }
      return false;
    };
    std::unique_ptr<IdleReport> idle;
    if (!o.skip_idle && o.idle_submits > 0)
      attempt("idle server", [&] { idle = std::make_unique<IdleReport>(run_idle(o, components.get())); });
    std::vector<RunReport> runs;
    bool all_ran = true;
    if (o.jobs > 0)
      for (int ranks : o.ranks)
        for (const auto& v : o.variants)
          all_ran = attempt("throughput " + std::to_string(o.workers) + " x " + std::to_string(ranks) + " " + v,
                            [&] { runs.push_back(run_throughput(o, ranks, v)); }) &&
                    all_ran;
    std::string md = markdown(o, components.get(), idle.get(), runs);
    if (!incidents.empty()) {
      md += "### Incidents (phases that failed and were retried)\n\n";
      for (const auto& i : incidents) md += "- " + i + "\n";
      md += "\n";
    }
    std::cout << md << std::flush;
    if (!o.out.empty()) std::ofstream(o.out) << md;
    bool ok = all_ran;
    for (const auto& r : runs) ok = ok && r.finished && r.succeeded == r.jobs;
    return ok ? 0 : 1;
  } catch (const Interrupted&) {
    std::cerr << "service_bench: interrupted; servers stopped, temp dirs removed\n";
    return 130;
  } catch (const std::exception& e) {
    std::cerr << "service_bench: " << e.what() << "\n";
    return 2;
  }
}
