#pragma once
// Phase averages over beats (the seed's statistics, MODEL.md §7: "11 beats, the first
// discarded, statistics phase-averaged over the last 10"; rms = the root mean square of the
// deviation of each beat from that average, the seed's Figs. 17 and 19). Physics-free.
//
// Beats are the windows [k T, (k + 1) T), k = 0, 1, ... from t = 0 (scenes start every beat at
// the activation). A beat counts when the samples cover it whole (a sample at or before its start
// and one at or after its end, to 1e-9 s). The phase [0, 1) is cut into `bins` equal bins; a
// beat's value in a bin is the mean of its samples there, so beats with more samples in a bin do
// not weigh more. Every bin of every counted beat must hold a sample (bins <= T / sample interval).
#include <string>
#include <vector>

#include "solver/core/run_result.h"
#include "solver/core/state_archive.h"

namespace systole::diagnostics {

struct PhaseAverage {
  int first_beat = 0;           // 1-based number of the first beat averaged
  int beats = 0;                // beats averaged
  std::vector<double> phase;    // bin centres, t/T
  std::vector<double> mean;     // per bin, over the beats
  std::vector<double> rms;      // per bin: sqrt(mean over beats of (value - mean)^2)
};

// Phase average of one sampled curve (time_s strictly increasing, the same length as values),
// discarding the first `discard` whole beats. Fewer than one beat left: beats = 0 and empty
// vectors. Throws std::invalid_argument for mismatched lengths, period <= 0, bins < 1, or a bin
// of a counted beat without a sample (naming the beat and the bin).
PhaseAverage phase_average(const std::vector<double>& time_s, const std::vector<double>& values, double period_s,
                           int bins, int discard);

// RunResult::phase_averaged of a result's series (series[0] must be "time_s"): "phase", then X
// and X_rms for every other series X. Empty when fewer than one beat is left after `discard`.
std::vector<Series> phase_averaged_series(const std::vector<Series>& series, double period_s, int bins, int discard);

// The same statistics for a field sampled during a run (e.g. the wall shear stress at every shell
// node), accumulated as the samples come so that no beat is kept: per bin, the sums over the
// finished beats of each beat's bin mean and of its square. A beat is finished when a sample of a
// later beat arrives (the scenes sample at every beat's start). A bin averages over the finished
// beats after `discard` that had a sample in it. The accumulators are state: export_state /
// import_state put them in a checkpoint so a resumed run gives the straight run's averages.
class FieldPhaseAverage {
 public:
  // size values per sample; throws std::invalid_argument for period <= 0 or bins < 1.
  FieldPhaseAverage(std::size_t size, double period_s, int bins, int discard);
  // One sample at t_s (>= the previous sample's time); values.size() == size (else
  // std::invalid_argument).
  void add(double t_s, const std::vector<double>& values);
  int bins() const { return bins_; }
  // Beats folded into bin j so far, and that bin's mean and rms (size values each; zeros when
  // no beat was folded).
  int beats(int j) const { return folded_[static_cast<std::size_t>(j)]; }
  std::vector<double> mean(int j) const;
  std::vector<double> rms(int j) const;
  void export_state(StateArchive& archive, const std::string& prefix) const;
  void import_state(const StateArchive& archive, const std::string& prefix);

 private:
  void fold();  // the current beat's bin means into the sums (when it is after `discard`)
  std::size_t size_;
  double period_s_;
  int bins_, discard_;
  long beat_ = -1;                      // the beat the current sums belong to
  std::vector<double> sum_, count_;     // current beat: per bin x value, per bin
  std::vector<double> s1_, s2_;         // finished beats: per bin x value
  std::vector<int> folded_;             // finished beats per bin
};

}  // namespace systole::diagnostics
