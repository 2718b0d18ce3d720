#include "solver/core/threads.h"

#include <omp.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>

namespace systole {

std::string OpenMpThreads::describe() const {
  std::string s = "OpenMP: " + std::to_string(threads) + (threads == 1 ? " thread" : " threads") + " per rank (" +
                  (from_environment ? "OMP_NUM_THREADS" : "the default") + "; " + std::to_string(ranks_on_node) +
                  (ranks_on_node == 1 ? " rank" : " ranks") + " on this node's " + std::to_string(cores_online) +
                  (cores_online == 1 ? " core)" : " cores)");
  if (static_cast<long>(threads) * ranks_on_node > cores_online)
    s += "; warning: more threads than cores, they will wait on each other";
  return s;
}

OpenMpThreads share_cores_among_ranks(MPI_Comm comm) {
  OpenMpThreads t;
  MPI_Comm node = MPI_COMM_NULL;
  MPI_Comm_split_type(comm, MPI_COMM_TYPE_SHARED, 0, MPI_INFO_NULL, &node);
  MPI_Comm_size(node, &t.ranks_on_node);
  MPI_Comm_free(&node);
  t.cores_online = static_cast<int>(std::max(1L, ::sysconf(_SC_NPROCESSORS_ONLN)));
  const char* env = std::getenv("OMP_NUM_THREADS");
  if (env != nullptr && *env != '\0') {
    t.from_environment = true;
    t.threads = omp_get_max_threads();
    return t;
  }
  t.threads = 1;
  omp_set_num_threads(t.threads);
  return t;
}

}  // namespace systole
