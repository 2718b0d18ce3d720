#pragma once
// Checkpoints of scenes "fsi"/"fsei" (issue #9, docs/fsei.md "Checkpoint and restart"): the
// whole coupled state at a synchronisation point, so a continued run equals a straight run
// bitwise, and a requeued job resumes instead of starting over.
//
// Layout of a checkpoint directory D (RunControl::checkpoint_directory()):
//   D/latest/fluid.h5   the fluid (FluidSolver::write_checkpoint: global arrays, any rank count)
//   D/latest/state.h5   everything else as one StateArchive (shells, contact, EP, scheduler,
//                       the scene's series), plus the scenario's fingerprint; written by rank 0
// A new checkpoint is written into D/next.<pid of rank 0> and published by renames (latest ->
// old, next -> latest, old removed), so a crash at any moment leaves one complete checkpoint:
// latest, or old when the crash fell between the two renames; an abandoned next.* is ignored.
#include <filesystem>
#include <optional>
#include <string>

#include "solver/config/scenario.h"
#include "solver/core/state_archive.h"

namespace systole::scene {

// The scenario's parameters that decide the trajectory, one "path=value" line each (every
// parameter of the table except the outputs, the run's length, the field and checkpoint
// intervals and the strain limit (a guard), which a continued run may change). Reals with 17
// significant digits.
std::string scenario_fingerprint(const config::Scenario& scenario);

class CheckpointDirectory {
 public:
  explicit CheckpointDirectory(std::filesystem::path root) : root_(std::move(root)) {}
  const std::filesystem::path& root() const { return root_; }
  // The complete checkpoint to resume from, if any (latest, else old). Collective-safe: every
  // rank sees the same files.
  std::optional<std::filesystem::path> resumable() const;
  // Rank 0 creates root/next.<pid>; the caller then writes fluid.h5 (collective) and state.h5
  // (rank 0) into it and calls publish(). Collective (barriers on MPI_COMM_WORLD).
  std::filesystem::path begin();
  void publish();

 private:
  std::filesystem::path root_, next_;
};

// state.h5: the archive (one dataset per entry) and the fingerprint. Rank 0 writes; any rank
// reads. Throws std::runtime_error naming the file on an HDF5 failure.
void write_state_file(const std::filesystem::path& file, const StateArchive& archive, const std::string& fingerprint);
StateArchive read_state_file(const std::filesystem::path& file, std::string& fingerprint);

// Compares a checkpoint's fingerprint with this scenario's, parameter by parameter: InputError
// naming the checkpoint and the first parameter that differs (its value there and here) when they
// differ. An older checkpoint's fields that moved since are compared under their new paths; a
// removed field with the one value every run used is skipped (config/removed_fields.h).
void check_fingerprint(const std::filesystem::path& checkpoint, const std::string& stored, const std::string& current);

}  // namespace systole::scene
