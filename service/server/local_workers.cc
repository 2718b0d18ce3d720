#include "service/server/local_workers.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>

#include <spdlog/spdlog.h>

namespace systole::service {

LocalWorkers::LocalWorkers(LocalWorkerOptions options)
    : options_(std::move(options)), pids_(options_.count, -1), generation_(options_.count, 0) {
  if (options_.count < 0 || options_.ranks < 1)
    throw std::invalid_argument("local workers: count must be >= 0 and ranks >= 1");
  if (::access(options_.worker_binary.c_str(), X_OK) != 0)
    throw std::runtime_error("local workers: worker binary '" + options_.worker_binary + "' is not executable");
  std::filesystem::create_directories(options_.log_dir);
  supervisor_ = std::thread([this] { supervise(); });
}

pid_t LocalWorkers::spawn(int slot) {
  const std::string worker_id = "local-" + std::to_string(slot) + "-" + std::to_string(++generation_[slot]) + "-" +
                                std::to_string(::getpid());
  const std::string log = (options_.log_dir / ("worker-" + std::to_string(slot) + ".log")).string();
  const pid_t parent = ::getpid();
  const pid_t pid = ::fork();
  if (pid < 0) throw std::runtime_error("fork failed");
  if (pid == 0) {
    // The server blocks SIGINT/SIGTERM in all its threads (it sigwait()s for them); a child
    // must not inherit that mask, or mpirun would never see its SIGTERM.
    sigset_t none;
    sigemptyset(&none);
    ::sigprocmask(SIG_SETMASK, &none, nullptr);
    ::setpgid(0, 0);
    ::prctl(PR_SET_PDEATHSIG, SIGTERM);
    if (::getppid() != parent) ::_exit(1);  // the server died before prctl took effect
    const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
    if (fd >= 0) {
      ::dup2(fd, 1);
      ::dup2(fd, 2);
      ::close(fd);
    }
    ::setenv("OMPI_ALLOW_RUN_AS_ROOT", "1", 1);
    ::setenv("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1", 1);
    // If mpirun itself gets SIGTERM (e.g. the server died), it SIGTERMs the ranks and SIGKILLs
    // them after this many seconds: time for a worker to give its job back.
    ::setenv("OMPI_MCA_odls_base_sigkill_timeout", "5", 1);
    // OpenMP threads: the worker's rule (one per rank unless the operator set OMP_NUM_THREADS,
    // which the child inherits; solver/core/threads.h).
    const std::string ranks = std::to_string(options_.ranks);
    std::vector<std::string> args{"mpirun", "-np", ranks, "--oversubscribe", "--bind-to", "none",
                                  options_.worker_binary, "--server", options_.server_address,
                                  "--worker-id", worker_id};
    if (!options_.checkpoint_dir.empty()) {
      args.push_back("--checkpoint-dir");
      args.push_back(options_.checkpoint_dir.string());
    }
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    ::execvp("mpirun", argv.data());
    ::_exit(127);
  }
  spdlog::info("local worker {} started: mpirun -np {} (pid {}, id {}, log {})", slot, options_.ranks, pid, worker_id, log);
  return pid;
}

void LocalWorkers::supervise() {
  std::vector<std::chrono::steady_clock::time_point> not_before(options_.count);
  while (!stopping_) {
    for (int slot = 0; slot < options_.count && !stopping_; ++slot) {
      if (pids_[slot] > 0) {
        int status = 0;
        if (::waitpid(pids_[slot], &status, WNOHANG) == pids_[slot]) {
          spdlog::warn("local worker {} (pid {}) exited ({}); restarting", slot, pids_[slot],
                       WIFSIGNALED(status) ? "signal " + std::to_string(WTERMSIG(status))
                                           : "status " + std::to_string(WEXITSTATUS(status)));
          pids_[slot] = -1;
          ++restarts_;
          not_before[slot] = std::chrono::steady_clock::now() + std::chrono::milliseconds(500);
        }
      }
      if (pids_[slot] <= 0 && std::chrono::steady_clock::now() >= not_before[slot]) {
        try {
          pids_[slot] = spawn(slot);
        } catch (const std::exception& e) {
          spdlog::error("local worker {}: {}", slot, e.what());
          not_before[slot] = std::chrono::steady_clock::now() + std::chrono::seconds(2);
        }
      }
    }
    std::unique_lock lock(mu_);
    cv_.wait_for(lock, std::chrono::milliseconds(200), [&] { return stopping_.load(); });
  }
  drain();
}

LocalWorkers::~LocalWorkers() {
  {
    std::lock_guard lock(mu_);
    stopping_ = true;
  }
  cv_.notify_all();
  supervisor_.join();  // the supervisor drains the workers before it returns
}

// Runs on the supervisor thread: the thread that forked the workers must outlive them, since
// PR_SET_PDEATHSIG fires when the *thread* that forked a child ends.
void LocalWorkers::drain() {
  // SIGUSR1 is forwarded by mpirun to every rank (Open MPI's default signal forwarding): the
  // worker gives its job back (ReleaseJob) and exits, and then mpirun exits. SIGTERM after
  // 8 s, SIGKILL after 10 s.
  for (pid_t pid : pids_)
    if (pid > 0) ::kill(pid, SIGUSR1);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  bool terminated = false;
  for (pid_t pid : pids_) {
    if (pid <= 0) continue;
    while (::waitpid(pid, nullptr, WNOHANG) == 0) {
      if (!terminated && std::chrono::steady_clock::now() > deadline - std::chrono::seconds(2)) {
        for (pid_t p : pids_)
          if (p > 0) ::kill(p, SIGTERM);
        terminated = true;
      }
      if (std::chrono::steady_clock::now() > deadline) {
        ::kill(-pid, SIGKILL);
        ::kill(pid, SIGKILL);
        ::waitpid(pid, nullptr, 0);
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  }
}

}  // namespace systole::service
