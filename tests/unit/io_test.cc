// Unit tests of solver/io: result.h5 round trip (values, units, provenance), gzip+shuffle
// chunked datasets, metrics.json and pv_loop.csv.
#include <gtest/gtest.h>
#include <hdf5.h>

#include <fstream>
#include <random>

#include <nlohmann/json.hpp>

#include "solver/core/version.h"
#include "solver/io/result_writer.h"

namespace systole::io {
namespace {

RunResult sample_result() {
  RunResult r;
  Series t{"time_s", "s", {}}, p{"lv_pressure_mmhg", "mmHg", {}}, v{"lv_volume_ml", "ml", {}};
  for (int i = 0; i < 5000; ++i) {
    t.values.push_back(i * 1e-3);
    p.values.push_back(10 + 100 * std::sin(i * 1e-3));
    v.values.push_back(120 - 50 * std::sin(i * 1e-3));
  }
  r.series = {t, p, v};
  r.beats = {{{"ejection_fraction_percent", 57.0}, {"edv_ml", 125.0}}, {{"ejection_fraction_percent", 58.0}, {"edv_ml", 124.0}}};
  r.metrics = {{"ejection_fraction_percent", 58.0}, {"cardiac_output_l_min", 5.1}, {"beats_simulated", 2}};
  return r;
}

TEST(ResultWriter, H5RoundTripWithUnitsAndProvenance) {
  const auto dir = std::filesystem::temp_directory_path() / ("systole-io-" + std::to_string(std::random_device{}()));
  const RunResult r = sample_result();
  const auto files = write_results(dir, r, {R"({"heart_rate_bpm":70})", "j-test"});
  ASSERT_EQ(files.size(), 4u);  // result.h5, metrics.json, time_series.csv, pv_loop.csv
  for (const auto& f : files) EXPECT_TRUE(std::filesystem::exists(f)) << f;
  EXPECT_FALSE(std::filesystem::exists(dir / "result.h5.tmp"));
  const H5Contents c = read_result_h5(dir / "result.h5");
  ASSERT_EQ(c.series.size(), 3u);
  EXPECT_EQ(c.series[0].name, "time_s");
  EXPECT_EQ(c.series[1].name, "lv_pressure_mmhg");
  EXPECT_EQ(c.series[1].unit, "mmHg");
  EXPECT_EQ(c.series[1].values, r.series[1].values);
  EXPECT_EQ(c.beats.at("edv_ml"), (std::vector<double>{125.0, 124.0}));
  EXPECT_EQ(c.beats.at("beat"), (std::vector<double>{1, 2}));
  EXPECT_DOUBLE_EQ(c.metrics.at("cardiac_output_l_min"), 5.1);
  EXPECT_EQ(c.scenario_json, R"({"heart_rate_bpm":70})");
  EXPECT_EQ(c.version, kVersion);
  EXPECT_EQ(c.git_revision, kGitRevision);

  // The datasets are chunked with shuffle + deflate.
  hid_t file = H5Fopen((dir / "result.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  hid_t set = H5Dopen2(file, "/time_series/lv_pressure_mmhg", H5P_DEFAULT);
  hid_t plist = H5Dget_create_plist(set);
  EXPECT_EQ(H5Pget_layout(plist), H5D_CHUNKED);
  std::set<H5Z_filter_t> filters;
  for (int i = 0; i < H5Pget_nfilters(plist); ++i) {
    unsigned flags = 0;
    size_t n = 0;
    filters.insert(H5Pget_filter2(plist, static_cast<unsigned>(i), &flags, &n, nullptr, 0, nullptr, nullptr));
  }
  EXPECT_TRUE(filters.count(H5Z_FILTER_SHUFFLE));
  EXPECT_TRUE(filters.count(H5Z_FILTER_DEFLATE));
  H5Pclose(plist);
  H5Dclose(set);
  H5Fclose(file);

  const auto metrics = nlohmann::json::parse(std::ifstream(dir / "metrics.json"));
  EXPECT_DOUBLE_EQ(metrics["ejection_fraction_percent"].get<double>(), 58.0);
  std::ifstream csv(dir / "pv_loop.csv");
  std::string header, first;
  std::getline(csv, header);
  std::getline(csv, first);
  EXPECT_EQ(header, "time_s,lv_volume_ml,lv_pressure_mmhg");
  EXPECT_EQ(first, "0,120,10");
  std::ifstream series_csv(dir / "time_series.csv");
  std::getline(series_csv, header);
  std::getline(series_csv, first);
  EXPECT_EQ(header, "time_s,lv_pressure_mmhg,lv_volume_ml");
  EXPECT_EQ(first, "0,10,120");
  std::filesystem::remove_all(dir);
}

// Phase averages (scenes fsi/fsei with two or more beats) go to /phase_averaged and
// phase_averaged.csv; a result without them has neither (the group is optional on reading).
TEST(ResultWriter, PhaseAveragesRoundTripAndAreOptional) {
  const auto dir = std::filesystem::temp_directory_path() / ("systole-io-" + std::to_string(std::random_device{}()));
  RunResult r = sample_result();
  r.phase_averaged = {{"phase", "", {0.25, 0.75}},
                      {"lv_pressure_mmhg", "mmHg", {80, 5}},
                      {"lv_pressure_mmhg_rms", "mmHg", {2, 0.5}}};
  const auto files = write_results(dir, r, {"{}", ""});
  EXPECT_EQ(files.size(), 5u);
  const H5Contents c = read_result_h5(dir / "result.h5");
  ASSERT_EQ(c.phase_averaged.size(), 3u);
  EXPECT_EQ(c.phase_averaged[1].name, "lv_pressure_mmhg");
  EXPECT_EQ(c.phase_averaged[1].unit, "mmHg");
  EXPECT_EQ(c.phase_averaged[2].values, (std::vector<double>{2, 0.5}));
  std::ifstream csv(dir / "phase_averaged.csv");
  std::string header, first;
  std::getline(csv, header);
  std::getline(csv, first);
  EXPECT_EQ(header, "phase,lv_pressure_mmhg,lv_pressure_mmhg_rms");
  EXPECT_EQ(first, "0.25,80,2");
  r.phase_averaged.clear();
  std::filesystem::remove_all(dir);
  EXPECT_EQ(write_results(dir, r, {"{}", ""}).size(), 4u);
  EXPECT_TRUE(read_result_h5(dir / "result.h5").phase_averaged.empty());
  EXPECT_FALSE(std::filesystem::exists(dir / "phase_averaged.csv"));
  std::filesystem::remove_all(dir);
}

TEST(ResultWriter, NoPvLoopFileWithoutLvSeriesAndNoSeriesFileWithoutSeries) {
  const auto dir = std::filesystem::temp_directory_path() / ("systole-io-" + std::to_string(std::random_device{}()));
  RunResult r;
  r.metrics["f"] = 1.5;
  auto files = write_results(dir, r, {"{}", ""});
  EXPECT_EQ(files.size(), 2u);
  EXPECT_FALSE(std::filesystem::exists(dir / "pv_loop.csv"));
  EXPECT_FALSE(std::filesystem::exists(dir / "time_series.csv"));
  r.series.push_back({"time_s", "s", {0, 1}});
  r.series.push_back({"kinetic_energy", "", {2, 3}});
  files = write_results(dir, r, {"{}", ""});
  EXPECT_EQ(files.size(), 3u);
  EXPECT_FALSE(std::filesystem::exists(dir / "pv_loop.csv"));
  EXPECT_TRUE(std::filesystem::exists(dir / "time_series.csv"));
  EXPECT_THROW(write_pv_loop_csv(dir / "x.csv", r), std::logic_error);
  std::filesystem::remove_all(dir);
}

TEST(ResultWriter, UnitsFromNames) {
  EXPECT_EQ(unit_from_name("ejection_fraction_percent"), "%");
  EXPECT_EQ(unit_from_name("cardiac_output_l_min"), "l/min");
  EXPECT_EQ(unit_from_name("mitral_flow_ml_s"), "ml/s");
  EXPECT_EQ(unit_from_name("edv_ml"), "ml");
  EXPECT_EQ(unit_from_name("aortic_valve_close_phase"), "t/T");
  EXPECT_EQ(unit_from_name("periodic"), "");
}

TEST(ResultWriter, UnwritableDirectoryThrows) {
  EXPECT_THROW(write_results("/proc/systole-cannot-write", sample_result(), {"{}", ""}), std::exception);
}

}  // namespace
}  // namespace systole::io
