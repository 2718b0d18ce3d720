#pragma once
// End-to-end harness: a real systole-server process (ephemeral ports, its own temp dir and
// SQLite file), real local workers under mpirun, real gRPC/HTTP clients, and the CLI.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <google/protobuf/util/json_util.h>
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "systole/v1/service.grpc.pb.h"

namespace systole::e2e {

namespace fs = std::filesystem;

inline fs::path bin_dir() { return SYSTOLE_BIN_DIR; }
inline fs::path source_dir() { return SYSTOLE_SOURCE_DIR; }

inline fs::path make_temp_dir(const std::string& tag) {
  std::random_device rd;
  const fs::path dir = fs::temp_directory_path() / ("systole-e2e-" + tag + "-" + std::to_string(rd()));
  fs::create_directories(dir);
  return dir;
}

// Runs a command through the shell; returns {exit code, stdout+stderr}.
inline std::pair<int, std::string> run_command(const std::string& command) {
  std::string output;
  FILE* pipe = ::popen((command + " 2>&1").c_str(), "r");
  if (!pipe) return {-1, "popen failed"};
  char buffer[4096];
  size_t n;
  while ((n = fread(buffer, 1, sizeof buffer, pipe)) > 0) output.append(buffer, n);
  const int status = ::pclose(pipe);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, output};
}

template <class Pred>
bool wait_until(Pred pred, std::chrono::milliseconds timeout, std::chrono::milliseconds poll = std::chrono::milliseconds(50)) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < deadline) {
    if (pred()) return true;
    std::this_thread::sleep_for(poll);
  }
  return pred();
}

class ServerProcess {
 public:
  // Starts systole-server in `dir` (db and data inside). Blocks until it listens.
  ServerProcess(fs::path dir, int local_workers, int ranks, int lease_ms = 4000) : dir_(std::move(dir)) {
    start(local_workers, ranks, lease_ms);
  }
  ~ServerProcess() { stop(SIGTERM); }

  void start(int local_workers, int ranks, int lease_ms) {
    const fs::path ports = dir_ / "ports.json";
    fs::remove(ports);
    std::cout.flush();  // the child must not inherit (and later flush) unwritten output
    std::fflush(nullptr);
    pid_ = ::fork();
    if (pid_ == 0) {
      ::setenv("OMPI_ALLOW_RUN_AS_ROOT", "1", 1);
      ::setenv("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1", 1);
      const std::string log = (dir_ / "server.log").string();
      FILE* f = std::freopen(log.c_str(), "a", stdout);
      (void)f;
      ::dup2(1, 2);
      const std::string server = (bin_dir() / "systole-server").string();
      std::vector<std::string> args{server, "--listen", "127.0.0.1:0", "--http-listen", "127.0.0.1:0",
                                    "--db", (dir_ / "systole.db").string(), "--data-dir", (dir_ / "data").string(),
                                    "--port-file", ports.string(), "--local-workers", std::to_string(local_workers),
                                    "--ranks", std::to_string(ranks), "--lease-ms", std::to_string(lease_ms)};
      std::vector<char*> argv;
      for (auto& a : args) argv.push_back(a.data());
      argv.push_back(nullptr);
      ::execv(server.c_str(), argv.data());
      ::_exit(127);
    }
    const bool up = wait_until([&] { return fs::exists(ports); }, std::chrono::seconds(30));
    if (!up) throw std::runtime_error("server did not start; log: " + log());
    std::ifstream in(ports);
    const auto json = nlohmann::json::parse(in);
    grpc_port_ = json["grpc"].get<int>();
    http_port_ = json["http"].get<int>();
    channel_ = grpc::CreateChannel(address(), grpc::InsecureChannelCredentials());
    stub_ = v1::Simulation::NewStub(channel_);
  }

  // SIGTERM: graceful; SIGKILL: a crash. Waits for the process.
  void stop(int signal) {
    if (pid_ <= 0) return;
    ::kill(pid_, signal);
    int status = 0;
    ::waitpid(pid_, &status, 0);
    pid_ = -1;
  }

  std::string address() const { return "127.0.0.1:" + std::to_string(grpc_port_); }
  int http_port() const { return http_port_; }
  v1::Simulation::Stub& stub() { return *stub_; }
  std::shared_ptr<grpc::Channel> channel() { return channel_; }
  std::string log() const {
    std::ifstream in(dir_ / "server.log");
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  }
  const fs::path& dir() const { return dir_; }
  pid_t pid() const { return pid_; }

  // The pids of this server's systole-worker processes (children of its mpirun).
  std::vector<pid_t> worker_pids() const {
    std::vector<pid_t> pids;
    for (const auto& entry : fs::directory_iterator("/proc")) {
      const std::string name = entry.path().filename().string();
      if (name.find_first_not_of("0123456789") != std::string::npos) continue;
      std::ifstream in(entry.path() / "cmdline");
      std::string cmdline((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
      for (char& c : cmdline)
        if (c == '\0') c = ' ';
      if (cmdline.find("systole-worker --server " + address()) != std::string::npos &&
          cmdline.find("mpirun") == std::string::npos)
        pids.push_back(std::stoi(name));
    }
    return pids;
  }

 private:
  fs::path dir_;
  pid_t pid_ = -1;
  int grpc_port_ = 0;
  int http_port_ = 0;
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v1::Simulation::Stub> stub_;
};

inline std::unique_ptr<grpc::ClientContext> deadline_context(int seconds = 20) {
  auto c = std::make_unique<grpc::ClientContext>();
  c->set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(seconds));
  return c;
}

inline v1::Job get_job(ServerProcess& server, const std::string& id) {
  v1::GetJobRequest request;
  request.set_id(id);
  v1::Job job;
  auto context = deadline_context();
  const auto status = server.stub().GetJob(context.get(), request, &job);
  if (!status.ok()) throw std::runtime_error("GetJob: " + status.error_message());
  return job;
}

// A job's result; throws (failing the calling test) when the server does not give it.
inline v1::Result get_result(ServerProcess& server, const std::string& id) {
  v1::GetResultRequest request;
  request.set_id(id);
  v1::Result result;
  auto context = deadline_context();
  const auto status = server.stub().GetResult(context.get(), request, &result);
  if (!status.ok()) throw std::runtime_error("GetResult: " + status.error_message());
  return result;
}

inline bool wait_for_state(ServerProcess& server, const std::string& id, v1::JobState state,
                           std::chrono::milliseconds timeout) {
  return wait_until([&] { return get_job(server, id).state() == state; }, timeout, std::chrono::milliseconds(100));
}

// The healthy 0-D example, optionally changed by a JSON merge patch.
inline v1::Scenario scenario_from_json(const nlohmann::json& json) {
  v1::Scenario scenario;
  const auto status = google::protobuf::util::JsonStringToMessage(json.dump(), &scenario);
  if (!status.ok()) throw std::runtime_error("bad test scenario: " + std::string(status.message()));
  return scenario;
}

// A long 0-D job: fixed beat count, a fine time step (a real, documented parameter), reporting
// progress every beat. A beat takes ≈ 60 ms on an idle core of the CI machine (measured
// 2026-12-02: 15 beats finished in 0.9 s, before a test polling every 100 ms saw beat 2), so a
// job that must still be running when the test looks needs ≳ 100 beats.
inline nlohmann::json slow_scenario(int beats) {
  return {{"scene", "lumped"},
          {"beats", beats},
          {"periodicity_tolerance", 0},
          {"lumped", {{"time_step_ms", 0.002}}}};
}

inline std::string submit(ServerProcess& server, const nlohmann::json& scenario, const std::string& request_id = "") {
  v1::SubmitJobRequest request;
  *request.mutable_scenario() = scenario_from_json(scenario);
  request.set_request_id(request_id);
  v1::SubmitJobResponse response;
  auto context = deadline_context();
  const auto status = server.stub().SubmitJob(context.get(), request, &response);
  if (!status.ok()) throw std::runtime_error("SubmitJob: " + status.error_message());
  return response.job().id();
}

}  // namespace systole::e2e
