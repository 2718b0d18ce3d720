#pragma once
// Field frames of scenes "fsei"/"fsi" (every fsei.field_interval_ms and/or at the phases
// outputs.field_phases of every beat, docs/fsei.md): what ParaView needs
// to show the blood and the tissue together, in millimetres.
//   fsei_fluid_<k>.h5   the fluid at frame k, cell-centred: velocity_x/y/z (m/s), pressure
//                       (mmHg, relative to the box's arbitrary level), vorticity_x/y/z (1/s);
//                       written collectively by every rank (FluidSolver::write_fields).
//   fsei_bodies.h5      /mesh/<body>_triangles (stress-free connectivity), the rigid plane's
//                       /mesh/valvular_plane_positions_mm, and per frame /frames/<k>/:
//                       time_ms, <body>_positions_mm, <body>_velocity_m_s, <body>_edge_strain
//                       (per node, the signed strain (l - l0)/l of its most strained edge) and,
//                       for the LV and LA, <body>_active_tension_kpa and (scene fsei, with EP)
//                       the transmembrane potential <body>_vm_mv (NaN at a node without an EP
//                       node); with the fluid, the wall shear stress <body>_wss_pa (per node,
//                       the larger of the two sides' for leaflets; ibm::wall_shear_stress).
//                       The per-node arrays are stored with shuffle + gzip level 4. Rank 0 writes.
//   fsei_fields.xmf     a temporal collection: per frame the fluid grid (when it has one), the
//                       plane and every body. Rewritten after every frame, so a run that stops
//                       leaves a readable file with the frames so far.
//   fsei_wss_phase.h5   (write_wss_phase_average, at the end of a run of two or more beats) the
//   + .xmf              wall shear stress phase-averaged over the beats after the first, per body
//                       and phase bin j: /<body>/positions_mm and /<body>/triangles (the
//                       stress-free mesh: the mitral leaflets open by geometry.mitral_rest_opening_mm
//                       when it is > 0), /<body>/bin_<j>/wss_mean_pa and wss_rms_pa (per node,
//                       Pa), /phase (bin centres, t/T) and /beats (beats averaged per bin).
// Contract: construct on every rank with the same arguments; frame() is collective when it
// writes the fluid; bodies_frame() is rank 0's alone (no communication: usable after a
// rank-local failure). Throws std::runtime_error naming the file on I/O failure.
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "solver/fluid/fluid.h"
#include "solver/geometry/tri_mesh.h"
#include "solver/structure/contact.h"

namespace systole::diagnostics {
class FieldPhaseAverage;
}

namespace systole::scene {

// Writes fsei_wss_phase.h5 and fsei_wss_phase.xmf into dir (rank 0's job): wss holds the
// group's nodes body after body (names[b] for body b). Throws std::runtime_error on I/O failure.
void write_wss_phase_average(const std::filesystem::path& dir, const structure::BodyGroup& group,
                             const std::vector<std::string>& names, const diagnostics::FieldPhaseAverage& wss);

class FseiFieldWriter {
 public:
  // names[b]: the name of group body b; mm_per_unit: the fluid grid's length unit in mm;
  // velocity/pressure/vorticity scales: nondimensional → m/s, mmHg, 1/s.
  // resumed_times_ms (a run resumed from a checkpoint, fsei/checkpoint.h): the times of the
  // frames the checkpointed run had written. When fsei_bodies.h5 in `dir` holds all of them,
  // its frames from k = resumed_times_ms->size() on (left by the interrupted attempt after the
  // checkpoint) are removed and the numbering continues; otherwise (another output directory)
  // a new file is started and the earlier frames are left out of the xmf
  // (earlier_frames_present() is then false). Collective (rank 0 looks, every rank learns).
  // node_vm_mv (scene fsei; empty: no potential written): the transmembrane potential in mV at
  // every node of group body b, for the bodies named as the LV and LA, called when a frame is
  // written (on rank 0). The plane and the group must outlive the writer.
  FseiFieldWriter(std::filesystem::path dir, const grid::Grid& grid, double mm_per_unit,
                  const geometry::TriMesh& plane, const structure::BodyGroup& group,
                  std::vector<std::string> names, fluid::FluidSolver::FieldSelection fluid_units,
                  std::function<std::vector<double>(std::size_t body)> node_vm_mv,
                  const std::vector<double>* resumed_times_ms = nullptr);
  bool earlier_frames_present() const { return earlier_present_; }

  // A frame of the fluid and the bodies at time_ms (collective); wss_pa[b]: body b's wall shear
  // stress per node (Pa), the same on every rank.
  void frame(double time_ms, const fluid::FluidSolver& fluid, const structure::BodyGroup& group,
             const std::vector<std::vector<double>>& wss_pa);
  // A frame of the bodies only (rank 0; e.g. when a run stopped unstable), labelled in the xmf.
  void bodies_frame(double time_ms, const structure::BodyGroup& group, const std::string& label);

  int frames() const { return static_cast<int>(frames_.size()); }
  // The times of the frames so far (checkpoints).
  std::vector<double> frame_times_ms() const;
  const std::filesystem::path& directory() const { return dir_; }

 private:
  struct Frame {
    double time_ms;
    bool fluid;
    std::string label;
    bool present = true;  // false: written by an earlier attempt into another directory
  };
  void write_bodies(int k, double time_ms, const structure::BodyGroup& group,
                    const std::vector<std::vector<double>>* wss_pa) const;
  void write_xmf() const;
  void create_bodies_file() const;

  std::filesystem::path dir_;
  int nx_, ny_, nz_;
  double dx_mm_, dy_mm_, dz_mm_;
  std::vector<std::string> names_;
  std::vector<std::size_t> triangles_, nodes_;
  std::size_t plane_nodes_, plane_triangles_;
  const geometry::TriMesh& plane_;
  const structure::BodyGroup& group_;
  fluid::FluidSolver::FieldSelection units_;
  std::function<std::vector<double>(std::size_t)> node_vm_mv_;
  bool rank0_;
  std::vector<Frame> frames_;
  bool earlier_present_ = true;
};

}  // namespace systole::scene
