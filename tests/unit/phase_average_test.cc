// Phase averages over beats (solver/diagnostics/phase_average.h) on curves whose average and
// beat-to-beat rms are known exactly.
#include "solver/diagnostics/phase_average.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

namespace systole::diagnostics {
namespace {

// v(t) = (bin index of the phase) + c_k in beat k (a step in phase, a constant per beat): the
// average in bin j is j + mean(c) over the averaged beats, the rms the population deviation of c.
// 3.5 beats sampled 200 times per beat, 50 bins, the first beat discarded: beats 2 and 3
// averaged, the half beat at the end left out.
TEST(PhaseAverage, StepCurveWithBeatOffsetsGivesExactMeanAndRms) {
  const double period = 0.8;
  const int bins = 50, per_beat = 200;
  const double c[4] = {100.0, 1.0, 3.0, -50.0};  // beat 1 (discarded), 2, 3, 4 (half: ignored)
  std::vector<double> t, v;
  for (int i = 0; i <= 3 * per_beat + per_beat / 2; ++i) {
    const double time = i * period / per_beat;
    const int k = i / per_beat;
    const int j = (i % per_beat) * bins / per_beat;
    t.push_back(time);
    v.push_back(j + c[k]);
  }
  const PhaseAverage a = phase_average(t, v, period, bins, 1);
  EXPECT_EQ(a.first_beat, 2);
  EXPECT_EQ(a.beats, 2);
  ASSERT_EQ(a.mean.size(), static_cast<std::size_t>(bins));
  for (int j = 0; j < bins; ++j) {
    EXPECT_NEAR(a.phase[j], (j + 0.5) / bins, 1e-15);
    EXPECT_NEAR(a.mean[j], j + 2.0, 1e-12) << j;
    EXPECT_NEAR(a.rms[j], 1.0, 1e-12) << j;
  }
}

// A smooth curve sampled finely: the phase average at a bin centre is the curve there to the
// bin's second-order midpoint error, and identical beats have zero rms.
TEST(PhaseAverage, SmoothPeriodicCurveIsRecoveredAtBinCentres) {
  const double period = 0.75;
  std::vector<double> t, v;
  for (int i = 0; i <= 3 * 1000; ++i) {
    t.push_back(i * period / 1000);
    v.push_back(std::sin(2 * M_PI * t.back() / period));
  }
  for (int bins : {20, 40}) {
    const PhaseAverage a = phase_average(t, v, period, bins, 1);
    double err = 0, rms = 0;
    for (int j = 0; j < bins; ++j) {
      err = std::max(err, std::abs(a.mean[j] - std::sin(2 * M_PI * a.phase[j])));
      rms = std::max(rms, a.rms[j]);
    }
    // the mean of sin over a bin of width w about its centre is sin(centre) sinc: error <= (pi w)^2 / 6;
    // the bin's samples start on its lower edge, so their mean sits half a sample (1/2000 of the
    // phase) before the centre: + 2 pi / 2000
    EXPECT_LT(err, std::pow(M_PI / bins, 2) / 6 + 2 * M_PI / 2000) << bins;
    EXPECT_LT(rms, 1e-9) << bins;
  }
}

// The field accumulator gives the series function's mean and rms for every value (the step
// curve with beat offsets and a sine, 3.5 beats, the first discarded, the half beat not folded),
// and one stopped halfway through beat 3, exported and imported into a new accumulator, ends with
// the same numbers bitwise.
TEST(PhaseAverage, FieldAccumulatorMatchesTheSeriesAndSurvivesACheckpoint) {
  const double period = 0.8;
  const int bins = 20, per_beat = 200;
  const double c[4] = {100.0, 1.0, 3.0, -50.0};
  std::vector<double> t, step, wave;
  for (int i = 0; i <= 3 * per_beat + per_beat / 2; ++i) {
    t.push_back(i * period / per_beat);
    step.push_back((i % per_beat) * bins / per_beat + c[i / per_beat]);
    wave.push_back(std::sin(2 * M_PI * t.back() / period) * (1 + 0.1 * (i / per_beat)));
  }
  FieldPhaseAverage straight(2, period, bins, 1), first(2, period, bins, 1);
  for (std::size_t i = 0; i < t.size(); ++i) straight.add(t[i], {step[i], wave[i]});
  const std::size_t stop = 2 * per_beat + per_beat / 2;
  for (std::size_t i = 0; i < stop; ++i) first.add(t[i], {step[i], wave[i]});
  StateArchive archive;
  first.export_state(archive, "wss/");
  FieldPhaseAverage resumed(2, period, bins, 1);
  resumed.import_state(archive, "wss/");
  for (std::size_t i = stop; i < t.size(); ++i) resumed.add(t[i], {step[i], wave[i]});
  const PhaseAverage a = phase_average(t, step, period, bins, 1), b = phase_average(t, wave, period, bins, 1);
  for (int j = 0; j < bins; ++j) {
    EXPECT_EQ(straight.beats(j), 2);
    EXPECT_NEAR(straight.mean(j)[0], a.mean[j], 1e-12);
    EXPECT_NEAR(straight.rms(j)[0], a.rms[j], 1e-9);
    EXPECT_NEAR(straight.mean(j)[1], b.mean[j], 1e-12);
    EXPECT_NEAR(straight.rms(j)[1], b.rms[j], 1e-9);
    EXPECT_EQ(resumed.mean(j), straight.mean(j));
    EXPECT_EQ(resumed.rms(j), straight.rms(j));
  }
  EXPECT_THROW(straight.add(3.0, {1.0}), std::invalid_argument);
  EXPECT_THROW(resumed.import_state(StateArchive{}, "wss/"), std::exception);
}

TEST(PhaseAverage, TooFewBeatsGiveNothingAndBadInputIsRefused) {
  std::vector<double> t{0, 0.25, 0.5, 0.75, 1.0}, v{1, 2, 3, 4, 5};
  EXPECT_EQ(phase_average(t, v, 1.0, 2, 1).beats, 0);  // one whole beat, discarded
  EXPECT_EQ(phase_average(t, v, 1.0, 2, 0).beats, 1);
  EXPECT_THROW(phase_average(t, {1, 2}, 1.0, 2, 0), std::invalid_argument);
  EXPECT_THROW(phase_average(t, v, 0.0, 2, 0), std::invalid_argument);
  EXPECT_THROW(phase_average(t, v, 1.0, 0, 0), std::invalid_argument);
  try {
    phase_average(t, v, 1.0, 8, 0);  // 4 samples per beat cannot fill 8 bins
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("beat 1 has no sample in bin 1 of 8"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace systole::diagnostics
