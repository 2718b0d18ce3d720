#pragma once
// OpenMP threads per MPI rank (ours, for speed).
//
// The immersed boundary's loops (solver/ibm/transfer.cc, mls.h) run on OpenMP's team, which is
// one thread per core unless OMP_NUM_THREADS says otherwise. Measured at `basic` (2 ms of the
// ejection from a checkpoint, this 2-core machine otherwise idle; docs/benchmarks.md, "One
// OpenMP thread per rank"): one rank with two threads took the wall time of one thread (71.5
// against 70.7 s) for 45 % more CPU; two ranks with two threads each (four threads on two
// cores, OpenMP's default under `mpirun -np 2`) 93.2 s against 63–65 s with one; and one rank's
// two threads beside another run spent 29 % of its samples spinning in libgomp's barriers. So
// the ranks are the parallelism and every rank runs one OpenMP thread unless the operator sets
// OMP_NUM_THREADS. The programs (systole-solve, systole-worker, fsei_case) call
// share_cores_among_ranks() right after MPI_Init; the server's local workers inherit the
// operator's OMP_NUM_THREADS, if any.
#include <mpi.h>

#include <string>

namespace systole {

struct OpenMpThreads {
  int threads = 1;                // the OpenMP team size every rank now uses
  int ranks_on_node = 1;          // the ranks of the communicator sharing this rank's node
  int cores_online = 1;           // this node's cores online
  bool from_environment = false;  // OMP_NUM_THREADS was set: left as the environment says

  // One line for the run's log, e.g. "OpenMP: 1 thread per rank (the default; 2 ranks on this
  // node's 2 cores)"; it warns when the ranks' threads outnumber the cores.
  std::string describe() const;
};

// Contract: collective over `comm` (every rank calls it). If OMP_NUM_THREADS is set and not
// empty, OpenMP is left alone and its team size reported; otherwise every rank's team becomes
// one thread (omp_set_num_threads(1)). A run's values do not depend on the team size (the
// threaded loops have no reductions: each marker, probe point or velocity component is one
// thread's, transfer.h); only its speed does.
OpenMpThreads share_cores_among_ranks(MPI_Comm comm);

}  // namespace systole
