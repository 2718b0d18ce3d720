// systole-server: the job service. A straight start-up sequence: flags → store → service →
// gRPC + REST front ends → lease reaper → local workers → port file; then wait for SIGINT or
// SIGTERM and tear down in reverse order.
#include <signal.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <thread>

#include <CLI/CLI.hpp>
#include <grpcpp/ext/proto_server_reflection_plugin.h>
#include <grpcpp/grpcpp.h>
#include <grpcpp/health_check_service_interface.h>
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include "service/server/grpc_services.h"
#include "service/server/local_workers.h"
#include "service/server/rest_gateway.h"
#include "service/server/umbridge_gateway.h"
#include "solver/core/version.h"
#include "solver/scene/scene.h"

namespace fs = std::filesystem;
using namespace systole;

namespace {

std::pair<std::string, int> split_host_port(const std::string& address, const char* flag) {
  const auto colon = address.rfind(':');
  if (colon == std::string::npos) throw CLI::ValidationError(flag, "expected host:port, got '" + address + "'");
  try {
    return {address.substr(0, colon), std::stoi(address.substr(colon + 1))};
  } catch (const std::exception&) {
    throw CLI::ValidationError(flag, "bad port in '" + address + "'");
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"systole-server: the systole simulation job service (gRPC + REST, SQLite job store)"};
  std::string grpc_listen = "127.0.0.1:50051";
  std::string http_listen = "127.0.0.1:8080";
  std::string db_path = "var/systole.db";
  std::string data_dir = "var/data";
  std::string port_file;
  std::string worker_binary;
  int local_workers = 0;
  int ranks = 1;
  int64_t lease_ms = 15000;
  int max_request_mb = 4;
  std::string umbridge_listen = "off";
  std::string umbridge_preset;
  double umbridge_timeout_s = 600;
  app.add_option("--listen", grpc_listen, "gRPC listen address (port 0: any free port)")->capture_default_str();
  app.add_option("--http-listen", http_listen, "REST listen address (port 0: any free port; 'off' disables)")
      ->capture_default_str();
  app.add_option("--db", db_path, "SQLite job database file")->capture_default_str();
  app.add_option("--data-dir", data_dir, "directory for job artifacts")->capture_default_str();
  app.add_option("--local-workers", local_workers, "local MPI workers to spawn and keep alive")
      ->check(CLI::Range(0, 64))
      ->capture_default_str();
  app.add_option("--ranks", ranks, "MPI ranks per local worker")->check(CLI::Range(1, 256))->capture_default_str();
  app.add_option("--worker-binary", worker_binary, "systole-worker path (default: next to this binary)");
  app.add_option("--lease-ms", lease_ms, "worker lease; a job whose worker misses heartbeats this long is requeued")
      ->check(CLI::Range(int64_t{1000}, int64_t{3600000}))
      ->capture_default_str();
  app.add_option("--max-request-mb", max_request_mb, "largest accepted request")->check(CLI::Range(1, 1024))
      ->capture_default_str();
  app.add_option("--umbridge-listen", umbridge_listen,
                 "UM-Bridge model server address, e.g. 127.0.0.1:4242 (docs/umbridge.md; port 0: any free port; "
                 "'off' disables)")
      ->capture_default_str();
  app.add_option("--umbridge-preset", umbridge_preset, "JSON file: the UM-Bridge model's default config");
  app.add_option("--umbridge-timeout-s", umbridge_timeout_s, "longest a UM-Bridge Evaluate waits for its job")
      ->check(CLI::Range(1.0, 86400.0))
      ->capture_default_str();
  app.add_option("--port-file", port_file,
                 "write {\"grpc\": port, \"http\": port, \"umbridge\": port} here once listening");
  app.set_version_flag("--version", std::string(kVersion) + " (" + kGitRevision + ")");
  CLI11_PARSE(app, argc, argv);
  spdlog::set_pattern("%Y-%m-%dT%H:%M:%S.%e %^%l%$ server %v");

  // Signals are handled by sigwait() in main; every thread started below inherits the mask.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);
  ::signal(SIGPIPE, SIG_IGN);

  try {
    if (fs::path(db_path).has_parent_path()) fs::create_directories(fs::path(db_path).parent_path());
    store::JobStore store(db_path);
    service::ChangeNotifier notifier;
    service::JobService jobs(store, notifier, {fs::path(data_dir), lease_ms, 3});
    spdlog::info("store {} (schema {}): {} jobs, {} queued, {} running", db_path, store::JobStore::schema_version(),
                 store.count(std::nullopt), store.count(store::JobState::kQueued),
                 store.count(store::JobState::kRunning));

    service::CampaignService campaigns(store, notifier, {fs::path(data_dir), lease_ms, 3});
    service::SimulationService simulation(jobs);
    service::CampaignsGrpcService campaigns_api(campaigns);
    service::WorkerService worker_api(jobs);
    grpc::EnableDefaultHealthCheckService(true);
    grpc::reflection::InitProtoReflectionServerBuilderPlugin();
    grpc::ServerBuilder builder;
    int grpc_port = 0;
    builder.AddListeningPort(grpc_listen, grpc::InsecureServerCredentials(), &grpc_port);
    builder.RegisterService(&simulation);
    builder.RegisterService(&worker_api);
    builder.RegisterService(&campaigns_api);
    builder.SetMaxReceiveMessageSize(max_request_mb << 20);
    builder.SetMaxSendMessageSize(64 << 20);
    std::unique_ptr<grpc::Server> server = builder.BuildAndStart();
    if (!server || grpc_port == 0) {
      spdlog::critical("cannot listen on {} (gRPC)", grpc_listen);
      return 2;
    }
    const std::string grpc_host = grpc_listen.substr(0, grpc_listen.rfind(':'));
    spdlog::info("gRPC listening on {}:{}", grpc_host, grpc_port);

    std::unique_ptr<service::RestGateway> rest;
    if (http_listen != "off") {
      const auto [host, port] = split_host_port(http_listen, "--http-listen");
      rest = std::make_unique<service::RestGateway>(jobs, campaigns, host, port, static_cast<size_t>(max_request_mb) << 20);
      spdlog::info("REST listening on {}:{}", host, rest->port());
    }

    std::unique_ptr<service::UmBridgeGateway> umbridge;
    if (umbridge_listen != "off") {
      const auto [host, port] = split_host_port(umbridge_listen, "--umbridge-listen");
      nlohmann::json preset = nlohmann::json::object();
      if (!umbridge_preset.empty()) {
        std::ifstream in(umbridge_preset);
        if (!in) throw std::runtime_error("--umbridge-preset: cannot read " + umbridge_preset);
        preset = nlohmann::json::parse(in);
      }
      umbridge = std::make_unique<service::UmBridgeGateway>(
          jobs, notifier, host, port, preset,
          std::chrono::milliseconds(static_cast<int64_t>(umbridge_timeout_s * 1000)),
          [](const std::string& name) { return scene::metric_names(name); });
      spdlog::info("UM-Bridge listening on {}:{}", host, umbridge->port());
    }

    std::atomic<bool> stopping{false};
    std::thread reaper([&] {
      while (!stopping) {
        try {
          jobs.reap_expired_leases();
        } catch (const std::exception& e) {
          spdlog::error("lease reaper: {}", e.what());
        }
        for (int i = 0; i < 10 && !stopping; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(100));
      }
    });

    std::unique_ptr<service::LocalWorkers> workers;
    if (local_workers > 0) {
      if (worker_binary.empty()) {
        char self[4096];
        const ssize_t n = ::readlink("/proc/self/exe", self, sizeof self - 1);
        worker_binary = (fs::path(std::string(self, n > 0 ? n : 0)).parent_path() / "systole-worker").string();
      }
      const std::string connect = (grpc_host == "0.0.0.0" || grpc_host == "[::]" ? "127.0.0.1" : grpc_host) + ":" +
                                  std::to_string(grpc_port);
      workers = std::make_unique<service::LocalWorkers>(service::LocalWorkerOptions{
          worker_binary, connect, local_workers, ranks, fs::path(data_dir) / "logs", fs::path(data_dir) / "checkpoints"});
    }

    if (!port_file.empty()) {
      const std::string tmp = port_file + ".tmp";
      std::ofstream(tmp) << nlohmann::json{{"grpc", grpc_port}, {"http", rest ? rest->port() : 0},
                                 {"umbridge", umbridge ? umbridge->port() : 0}, {"pid", ::getpid()}}
                                .dump()
                         << "\n";
      fs::rename(tmp, port_file);
    }
    spdlog::info("systole-server {} ({}) ready", kVersion, kGitRevision);

    int signal_number = 0;
    sigwait(&signals, &signal_number);
    spdlog::info("signal {}: shutting down", signal_number);
    stopping = true;
    umbridge.reset();  // waiting Evaluates answer 503 first
    workers.reset();  // workers release their leases on SIGTERM
    rest.reset();
    server->Shutdown(std::chrono::system_clock::now() + std::chrono::seconds(5));
    reaper.join();
    spdlog::info("stopped");
    return 0;
  } catch (const std::exception& e) {
    spdlog::critical("{}", e.what());
    return 1;
  }
}
