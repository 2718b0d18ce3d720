// The OpenMP team size of the command-line programs (solver/core/threads.h); MPI around the
// tests by tests/fluid/mpi_main.cc.
#include "solver/core/threads.h"

#include <gtest/gtest.h>
#include <mpi.h>
#include <omp.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <optional>
#include <string>

namespace {

// Sets or unsets OMP_NUM_THREADS for one test and puts back what was there.
class ScopedOmpEnv {
 public:
  explicit ScopedOmpEnv(const char* value) {
    if (const char* v = std::getenv("OMP_NUM_THREADS")) old_ = v;
    if (value) ::setenv("OMP_NUM_THREADS", value, 1);
    else ::unsetenv("OMP_NUM_THREADS");
    team_before_ = omp_get_max_threads();
  }
  ~ScopedOmpEnv() {
    if (old_) ::setenv("OMP_NUM_THREADS", old_->c_str(), 1);
    else ::unsetenv("OMP_NUM_THREADS");
    omp_set_num_threads(team_before_);
  }

 private:
  std::optional<std::string> old_;
  int team_before_ = 1;
};

TEST(OpenMpThreads, WithoutTheEnvironmentEveryRankRunsOneThread) {
  const ScopedOmpEnv env(nullptr);
  omp_set_num_threads(7);  // a team the call must replace
  const systole::OpenMpThreads t = systole::share_cores_among_ranks(MPI_COMM_WORLD);
  EXPECT_FALSE(t.from_environment);
  EXPECT_EQ(t.ranks_on_node, 1);
  EXPECT_EQ(t.cores_online, static_cast<int>(std::max(1L, ::sysconf(_SC_NPROCESSORS_ONLN))));
  EXPECT_EQ(t.threads, 1);
  EXPECT_EQ(omp_get_max_threads(), 1);
  EXPECT_NE(t.describe().find("1 thread per rank (the default; 1 rank on this node"), std::string::npos)
      << t.describe();
  EXPECT_EQ(t.describe().find("warning"), std::string::npos) << t.describe();
}

TEST(OpenMpThreads, AnOperatorsOmpNumThreadsIsLeftAlone) {
  const ScopedOmpEnv env("3");
  omp_set_num_threads(3);  // what the runtime read from the variable at start in a real run
  const systole::OpenMpThreads t = systole::share_cores_among_ranks(MPI_COMM_WORLD);
  EXPECT_TRUE(t.from_environment);
  EXPECT_EQ(t.threads, 3);
  EXPECT_EQ(omp_get_max_threads(), 3);
  EXPECT_NE(t.describe().find("OMP_NUM_THREADS"), std::string::npos) << t.describe();
  // more threads than this node's cores: the line says so
  systole::OpenMpThreads crowded = t;
  crowded.threads = crowded.cores_online + 1;
  EXPECT_NE(crowded.describe().find("warning: more threads than cores"), std::string::npos) << crowded.describe();
}

}  // namespace
