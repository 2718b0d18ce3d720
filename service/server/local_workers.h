#pragma once
// Embedded mode: the server spawns N local workers, each `mpirun -np R systole-worker ...`,
// and restarts any that dies (after a short back-off). Each mpirun gets SIGTERM if the server
// dies (PR_SET_PDEATHSIG), so no orphaned worker outlives its server.
#include <atomic>
#include <condition_variable>
#include <filesystem>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <sys/types.h>

namespace systole::service {

struct LocalWorkerOptions {
  std::string worker_binary;   // path to systole-worker
  std::string server_address;  // host:port the workers connect to
  int count = 0;               // workers
  int ranks = 1;               // MPI ranks per worker
  std::filesystem::path log_dir;
  std::filesystem::path checkpoint_dir;  // the workers' --checkpoint-dir (shared: a requeued job resumes)
};

class LocalWorkers {
 public:
  explicit LocalWorkers(LocalWorkerOptions options);
  ~LocalWorkers();  // SIGTERM to every worker, waits up to 10 s, then SIGKILL
  LocalWorkers(const LocalWorkers&) = delete;
  LocalWorkers& operator=(const LocalWorkers&) = delete;
  int restarts() const { return restarts_.load(); }

 private:
  pid_t spawn(int slot);
  void supervise();
  void drain();

  LocalWorkerOptions options_;
  std::vector<pid_t> pids_;  // touched only by the supervisor thread
  std::vector<int> generation_;
  std::atomic<int> restarts_{0};
  std::atomic<bool> stopping_{false};
  std::mutex mu_;
  std::condition_variable cv_;
  std::thread supervisor_;
};

}  // namespace systole::service
