#pragma once
// The coupled scene's time series, each declared once (series.cc's table): its name and unit in
// the result, its key in a checkpoint, its key in the progress line, the group that decides
// whether the run has it, and its sampler. Sampling, the finiteness guard, checkpoints,
// resuming, the result's names and the progress line are all driven from that table: adding a
// series is one entry there.
#include <array>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "solver/core/run_result.h"
#include "solver/core/state_archive.h"
#include "solver/diagnostics/kinematics.h"
#include "solver/diagnostics/phase_average.h"
#include "solver/ibm/loads.h"
#include "solver/scene/fsei/coupled_heart.h"
#include "solver/scene/fsei/probes.h"

namespace systole::scene::fsei {

// Where the samplers read the heart (fixed at the start).
struct SamplingSites {
  SamplingSites(const config::Scenario& s, const CoupledHeart& h);
  std::vector<Probe> probes;  // probes.h's order
  // Doppler-like sample volumes (ours): disks of half the orifice radius (at most 5 mm) on the
  // valves' axes, at the closed mitral leaflets' tips (their coaptation depth below the plane) and
  // at the closed aortic cusps' tips (their height above it).
  geometry::Vec3 mitral_tips_mm, aortic_tips_mm;
  double mitral_disk_mm, aortic_disk_mm;
  double aortic_orifice_mm2, mitral_orifice_mm2;
  int lv_markers, aorta_markers, plane_markers;  // marker bodies
  std::vector<int> link_of_marker_body;          // -1: a body no shell drives (the plane)
  int lv_side;                                   // the LV's side of the plane along z
  geometry::Vec3 outflow_axis;                   // the descending aorta's, towards the outlet
};

// One sample's shared readings, each computed once on first use (collective: every rank asks for
// them in the same order, the table's).
class SampleContext {
 public:
  SampleContext(CoupledHeart& h, const SamplingSites& sites, double t_ms) : h(h), sites(sites), t_ms(t_ms) {}
  double pressure_mmhg(ProbeIndex probe);  // relative to the outer probe
  // the blood's flux through the body's markers relative to them, ml/s, out of the cavity
  // positive (the tiles' normals point into the cavity); for the plane along the LV's axis
  enum SlipBody { kSlipLv, kSlipAorta, kSlipPlane };
  double slip_flux_ml_s(SlipBody body);
  const ibm::WallShear& wall_shear();
  // the LV wall's twist and global strains from the built (end-diastolic, stress-free) shape
  const diagnostics::WallKinematics& lv_kinematics();

  CoupledHeart& h;
  const SamplingSites& sites;
  const double t_ms;

 private:
  std::optional<std::vector<double>> pressures_;
  std::optional<std::array<double, 3>> slip_;
  std::optional<ibm::WallShear> wall_shear_;
  std::optional<diagnostics::WallKinematics> kinematics_;
};

// Groups of series a run may lack: a geometry they do not apply to, or a checkpoint written
// before they existed (they are then left out of the result and of later checkpoints with a
// note, never filled in).
enum class SeriesGroup { kCore, kWallSlip, kOutlet, kDescendingAorta, kHeartKineticEnergy };

struct SeriesSpec {
  std::string name;          // in the result (time_series.csv)
  std::string unit;
  std::string state_key;     // series/<state_key> in a checkpoint
  std::string progress_key;  // empty: not in the progress line
  SeriesGroup group;
  double result_scale;       // stored value → the result's unit (the time is kept in ms)
  std::function<double(SampleContext&)> sample;
};
const std::vector<SeriesSpec>& series_table();

class SeriesRecorder {
 public:
  SeriesRecorder(const config::Scenario& s, CoupledHeart& h);
  // Loads the series of a checkpoint; the groups it lacks are dropped.
  void resume(const StateArchive& state);
  // A sample at the fluid's time: every series the run has, the finiteness guard (InstabilityError), the
  // slow-runaway guard and the wall shear's phase average.
  void sample();

  bool has(SeriesGroup g) const { return present_[static_cast<std::size_t>(g)]; }
  // a series' stored values by its result name (the time: times_ms()); std::logic_error if absent
  const std::vector<double>& values(const std::string& name) const;
  double latest(const std::string& name) const { return values(name).back(); }
  std::size_t samples() const { return values_[0].size(); }
  const std::vector<double>& times_ms() const { return values_[0]; }
  // The box's kinetic energy (latest sample) as a mean speed of the LV's and LA's blood, m/s.
  double mean_speed_m_s() const;
  // "key value" pairs of the latest sample for the progress line, in the table's order.
  std::string progress_fields() const;
  std::vector<Series> named() const;  // the result's series, in the table's order
  std::vector<std::string> absent_notes() const;

  void export_state(StateArchive& a) const;  // the series and the wall shear's accumulators
  diagnostics::FieldPhaseAverage& wss_phase() { return wss_phase_; }
  double wss_phase_from_ms() const { return wss_phase_from_ms_; }
  static constexpr int kWssPhaseBins = 20;

 private:
  bool wanted(const SeriesSpec& spec) const { return has(spec.group); }
  void check_slow_runaway() const;

  const config::Scenario& s_;
  CoupledHeart& h_;
  SamplingSites sites_;
  std::array<bool, 5> present_{};
  std::vector<std::vector<double>> values_;  // per table entry; empty when absent
  // The wall shear stress per shell node phase-averaged over the beats after the first (the
  // seed's Figs. 16-17), in bins of 0.05 T (ours), written to fsei_wss_phase.h5 at the end.
  diagnostics::FieldPhaseAverage wss_phase_;
  double wss_phase_from_ms_ = 0;  // > 0: resumed from a checkpoint without the accumulators
};

}  // namespace systole::scene::fsei
