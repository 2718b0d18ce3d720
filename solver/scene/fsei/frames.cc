#include "solver/scene/fsei/frames.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "solver/scene/fsei/wall_shear.h"

namespace systole::scene::fsei {

FieldFrames::FieldFrames(CoupledHeart& h, const std::filesystem::path& output_directory, const Resume& resume)
    : h_(h) {
  const config::Fsei& fs = h.s.fsei;
  const std::vector<double>& phases = h.s.outputs.field_phases;
  wanted_ = fs.field_interval_ms > 0 || !phases.empty();
  if (!wanted_ || output_directory.empty()) return;
  std::vector<double> resumed_frames_ms;
  if (resume.directory && resume.state.has("scene/field_times_ms")) resumed_frames_ms = resume.state.get("scene/field_times_ms");
  fluid::FluidSolver::FieldSelection units;
  units.velocity_scale = kUmMmPerMs;                 // U (mm/ms = m/s)
  units.pressure_scale = h.scales.mmhg_per_unit;     // ρU² in mmHg
  units.vorticity_scale = 1e3 * kUmMmPerMs / kDmMm;  // U/d in 1/s
  units.gzip_level = 4;                              // shuffle + gzip (ours: level 4)
  std::vector<std::string> names(deformable_bodies().begin(), deformable_bodies().end());
  std::function<std::vector<double>(std::size_t)> node_vm_mv;  // fsei: the EP's potential at the LV's and LA's nodes
  if (h.tension.with_ep())
    node_vm_mv = [&h](std::size_t b) {
      if (b != kLv && b != kLa) throw std::logic_error("fsei fields: body " + std::to_string(b) + " has no potential");
      return h.tension.node_vm_mv(b == kLv ? 0 : 1);
    };
  writer_ = std::make_unique<FseiFieldWriter>(output_directory, h.grid, kDmMm, h.heart.body(geometry::kValvularPlaneBody),
                                              h.group, names, units, std::move(node_vm_mv),
                                              resume.directory ? &resumed_frames_ms : nullptr);
  const bool phase_zero = std::find(phases.begin(), phases.end(), 0.0) != phases.end();
  if (!resume.directory && (fs.field_interval_ms > 0 || phase_zero))
    writer_->frame(0.0, h.fluid, h.group, node_wss_pa(h, h.fluid_module.wall_shear()));
  // resumed: the next frame after the checkpoint's time, whether the frames continue in the same
  // directory or start anew (a new directory, another interval)
  if (fs.field_interval_ms > 0)
    interval_frames_done_ =
        resume.directory ? static_cast<long>(std::floor(resume.time_ms() / fs.field_interval_ms + 1e-9)) + 1 : 1;
}

double FieldFrames::next_phase_frame(double after_ms) const {
  const double period_ms = h_.s.period_ms();
  double best = 1e300;
  const double k0 = std::floor(after_ms / period_ms);
  for (double k : {k0, k0 + 1})
    for (double phase : h_.s.outputs.field_phases)
      if ((k + phase) * period_ms > after_ms + 1e-9) best = std::min(best, (k + phase) * period_ms);
  return best;
}

double FieldFrames::next_interval_frame() const {
  const double interval_ms = h_.s.fsei.field_interval_ms;
  return writer_ && interval_ms > 0 ? static_cast<double>(interval_frames_done_) * interval_ms : 1e300;
}

double FieldFrames::next_after(double t_ms) const {
  return writer_ ? std::min(next_interval_frame(), next_phase_frame(t_ms)) : 1e300;
}

void FieldFrames::write_if_due(double t_ms, double due_ms) {
  if (!writer_ || std::abs(t_ms - due_ms) >= 1e-9) return;
  const double interval_frame = next_interval_frame();
  writer_->frame(t_ms, h_.fluid, h_.group, node_wss_pa(h_, h_.fluid_module.wall_shear()));
  if (std::abs(t_ms - interval_frame) < 1e-9) ++interval_frames_done_;
}

void FieldFrames::bodies_frame_on_stop(double t_ms) noexcept {
  if (!writer_) return;
  try {
    writer_->bodies_frame(t_ms, h_.group, "unstable");
  } catch (const std::exception&) {
    // the frame is a help; what is reported is the stop itself
  }
}

std::vector<std::string> FieldFrames::notes(bool resumed) const {
  const config::Fsei& fs = h_.s.fsei;
  const std::vector<double>& phases = h_.s.outputs.field_phases;
  if (!writer_) {
    if (!wanted_) return {};
    return {"fields were requested (fsei.field_interval_ms, outputs.field_phases) but the caller gave no output "
            "directory: none written"};
  }
  std::ostringstream m;
  m << writer_->frames() << " field frames";
  if (fs.field_interval_ms > 0) m << " every " << fs.field_interval_ms << " ms";
  if (!phases.empty()) {
    m << (fs.field_interval_ms > 0 ? " and" : "") << " at t/T =";
    for (double phase : phases) m << " " << phase;
    m << " of every beat";
  }
  m << ": fsei_fields.xmf (fluid fsei_fluid_<k>.h5, bodies fsei_bodies.h5)";
  if (!h_.s.outputs.fields.empty()) m << "; outputs.fields does not select among them: every frame has all the fields";
  std::vector<std::string> out{m.str()};
  if (resumed && !writer_->earlier_frames_present())
    out.push_back("the field frames written before the checkpoint are not in this output directory (left out of "
                  "fsei_fields.xmf)");
  return out;
}

}  // namespace systole::scene::fsei
