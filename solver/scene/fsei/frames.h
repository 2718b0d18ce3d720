#pragma once
// Field frames of the coupled scene into the caller's output directory (fields.h writes them):
// every fsei.field_interval_ms from t = 0 and/or at the phases outputs.field_phases (t/T) of
// every beat. A frame is not a sample: the scene clips its intervals at the frames' times.
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "solver/scene/fsei/coupled_heart.h"
#include "solver/scene/fsei/fields.h"

namespace systole::scene::fsei {

class FieldFrames {
 public:
  // Writes the frame at t = 0 of a fresh run when one is due then; a resumed run continues with
  // the next frame after the checkpoint's time.
  FieldFrames(CoupledHeart& h, const std::filesystem::path& output_directory, const Resume& resume);
  bool writing() const { return writer_ != nullptr; }
  // The next frame's time after t_ms (1e300: none).
  double next_after(double t_ms) const;
  // Writes a frame when t_ms is due_ms (next_after's answer before the interval that reached t_ms).
  void write_if_due(double t_ms, double due_ms);
  // The bodies as they were when the run stopped (rank 0, no communication; never throws).
  void bodies_frame_on_stop(double t_ms) noexcept;
  int frames() const { return writer_ ? writer_->frames() : 0; }
  std::vector<double> frame_times_ms() const { return writer_ ? writer_->frame_times_ms() : std::vector<double>{}; }
  // The result's notes about the frames (none when none were asked for).
  std::vector<std::string> notes(bool resumed) const;

 private:
  double next_phase_frame(double after_ms) const;  // the first (k + phase) T later than after_ms
  double next_interval_frame() const;

  CoupledHeart& h_;
  bool wanted_;
  std::unique_ptr<FseiFieldWriter> writer_;
  long interval_frames_done_ = 0;  // the next interval frame is at this × fsei.field_interval_ms
};

}  // namespace systole::scene::fsei
