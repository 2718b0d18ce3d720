#pragma once
// A systole-server child process for service_bench: ephemeral ports on 127.0.0.1, its own
// temp dir (db, data, logs), the port file as the "ready" signal. Same idea as
// tests/e2e/harness.h, but without gtest and with a hard stop and a kill-on-parent-death.
#include <signal.h>
#include <stdlib.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <grpcpp/grpcpp.h>
#include <nlohmann/json.hpp>

namespace systole::bench {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

// Thrown by the bench's waiting loops after SIGINT/SIGTERM.
struct Interrupted : std::runtime_error {
  Interrupted() : std::runtime_error("interrupted") {}
};

inline double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

// A fresh directory under the system temp dir; removed by TempDir's destructor.
class TempDir {
 public:
  explicit TempDir(const std::string& tag) {
    std::string pattern = (fs::temp_directory_path() / ("systole-bench-" + tag + "-XXXXXX")).string();
    if (::mkdtemp(pattern.data()) == nullptr) throw std::runtime_error("mkdtemp failed for " + pattern);
    path_ = pattern;
  }
  ~TempDir() {
    if (keep_) return;
    std::error_code ignored;
    fs::remove_all(path_, ignored);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const fs::path& path() const { return path_; }
  void keep() { keep_ = true; }

 private:
  fs::path path_;
  bool keep_ = false;
};

struct ServerOptions {
  fs::path bin_dir;
  int local_workers = 0;
  int ranks = 1;
  int64_t lease_ms = 15000;
};

class BenchServer {
 public:
  BenchServer(fs::path dir, ServerOptions options) : dir_(std::move(dir)), options_(std::move(options)) { start(); }
  ~BenchServer() { stop(); }
  BenchServer(const BenchServer&) = delete;
  BenchServer& operator=(const BenchServer&) = delete;

  // SIGTERM (the server stops its workers), then SIGKILL after 30 s.
  void stop() {
    if (pid_ <= 0) return;
    ::kill(pid_, SIGTERM);
    const auto deadline = Clock::now() + std::chrono::seconds(30);
    while (::waitpid(pid_, nullptr, WNOHANG) == 0) {
      if (Clock::now() > deadline) {
        ::kill(pid_, SIGKILL);
        ::waitpid(pid_, nullptr, 0);
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    remove_worker_scratch(pid_);
    pid_ = -1;
  }

  std::optional<uintmax_t> file_size(const fs::path& path) const {
    std::error_code ec;
    const auto size = fs::file_size(path, ec);
    if (ec) return std::nullopt;
    return size;
  }
  // Bytes of the job database and its WAL (0 when missing).
  std::pair<uintmax_t, uintmax_t> db_bytes() const {
    return {file_size(dir_ / "systole.db").value_or(0), file_size(dir_ / "systole.db-wal").value_or(0)};
  }

  // "running", or how the process ended (it is reaped then).
  std::string health() {
    if (pid_ <= 0) return "stopped";
    int status = 0;
    if (::waitpid(pid_, &status, WNOHANG) != pid_) return "running (pid " + std::to_string(pid_) + ")";
    pid_ = -1;
    if (WIFSIGNALED(status)) return "killed by signal " + std::to_string(WTERMSIG(status));
    return "exited with status " + std::to_string(WEXITSTATUS(status));
  }
  // Runs f; an exception from it gets the server's state and log tail appended.
  template <class F>
  auto diagnosed(F&& f) -> decltype(f()) {
    try {
      return f();
    } catch (const Interrupted&) {
      throw;
    } catch (const std::exception& e) {
      throw std::runtime_error(std::string(e.what()) + "\nsystole-server: " + health() + "; log tail:\n" +
                               log_tail(3000));
    }
  }

  std::string address() const { return "127.0.0.1:" + std::to_string(grpc_port_); }
  const fs::path& dir() const { return dir_; }
  fs::path log_path() const { return dir_ / "server.log"; }
  fs::path worker_log_path(int slot) const {
    return dir_ / "data" / "logs" / ("worker-" + std::to_string(slot) + ".log");
  }
  double startup_ms() const { return startup_ms_; }
  pid_t pid() const { return pid_; }

  // A channel with its own TCP connection (clients in different threads must not share one
  // HTTP/2 connection, or the bench would measure that connection's serialization).
  std::shared_ptr<grpc::Channel> new_channel(int tag) const {
    grpc::ChannelArguments args;
    args.SetInt(GRPC_ARG_USE_LOCAL_SUBCHANNEL_POOL, 1);
    args.SetInt("systole.bench_channel", tag);
    args.SetMaxReceiveMessageSize(64 << 20);
    return grpc::CreateCustomChannel(address(), grpc::InsecureChannelCredentials(), args);
  }

  static std::string read_file(const fs::path& path) {
    std::ifstream in(path);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  }
  std::string log_tail(size_t bytes = 4000) const {
    const std::string log = read_file(log_path());
    return log.size() > bytes ? log.substr(log.size() - bytes) : log;
  }

 private:
  // systole-worker's default scratch dir is <temp>/systole-worker-<worker id>, and a local
  // worker's id ends in "-<server pid>": remove the (empty) dirs our workers left behind.
  static void remove_worker_scratch(pid_t server_pid) {
    const std::string suffix = "-" + std::to_string(server_pid);
    std::error_code ec;
    for (const auto& entry : fs::directory_iterator(fs::temp_directory_path(), ec)) {
      const std::string name = entry.path().filename().string();
      if (name.rfind("systole-worker-local-", 0) == 0 && name.size() > suffix.size() &&
          name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0)
        fs::remove_all(entry.path(), ec);
    }
  }

  void start() {
    const fs::path ports = dir_ / "ports.json";
    const fs::path server = options_.bin_dir / "systole-server";
    if (::access(server.c_str(), X_OK) != 0) throw std::runtime_error(server.string() + " is not executable");
    std::vector<std::string> args{server.string(),
                                  "--listen",
                                  "127.0.0.1:0",
                                  "--http-listen",
                                  "127.0.0.1:0",
                                  "--db",
                                  (dir_ / "systole.db").string(),
                                  "--data-dir",
                                  (dir_ / "data").string(),
                                  "--port-file",
                                  ports.string(),
                                  "--local-workers",
                                  std::to_string(options_.local_workers),
                                  "--ranks",
                                  std::to_string(options_.ranks),
                                  "--lease-ms",
                                  std::to_string(options_.lease_ms),
                                  "--worker-binary",
                                  (options_.bin_dir / "systole-worker").string()};
    const std::string log = log_path().string();
    const pid_t parent = ::getpid();
    const auto t0 = Clock::now();
    pid_ = ::fork();
    if (pid_ < 0) throw std::runtime_error("fork failed");
    if (pid_ == 0) {
      ::prctl(PR_SET_PDEATHSIG, SIGTERM);  // never outlive the bench
      sigset_t none;                       // the bench blocks SIGINT/SIGTERM in its threads
      sigemptyset(&none);
      ::sigprocmask(SIG_SETMASK, &none, nullptr);
      if (::getppid() != parent) ::_exit(1);
      ::setenv("OMPI_ALLOW_RUN_AS_ROOT", "1", 1);
      ::setenv("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1", 1);
      if (std::freopen(log.c_str(), "a", stdout) == nullptr) ::_exit(126);
      ::dup2(1, 2);
      std::vector<char*> argv;
      for (auto& a : args) argv.push_back(a.data());
      argv.push_back(nullptr);
      ::execv(server.c_str(), argv.data());
      ::_exit(127);
    }
    const auto deadline = Clock::now() + std::chrono::seconds(30);
    while (!fs::exists(ports)) {
      int status = 0;
      if (::waitpid(pid_, &status, WNOHANG) == pid_) {
        pid_ = -1;
        throw std::runtime_error("systole-server exited during start-up; log:\n" + log_tail());
      }
      if (Clock::now() > deadline)
        throw std::runtime_error("systole-server did not start in 30 s; log:\n" + log_tail());
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    startup_ms_ = ms_since(t0);
    const auto json = nlohmann::json::parse(read_file(ports));
    grpc_port_ = json.at("grpc").get<int>();
  }

  fs::path dir_;
  ServerOptions options_;
  pid_t pid_ = -1;
  int grpc_port_ = 0;
  double startup_ms_ = 0;
};

}  // namespace systole::bench
