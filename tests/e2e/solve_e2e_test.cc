// systole-solve, the service-free runner: serial and under mpirun -np 2 give the same results;
// bad input exits 2 with the field named.
#include "tests/e2e/harness.h"

namespace systole::e2e {
namespace {

nlohmann::json read_metrics(const fs::path& dir) { return nlohmann::json::parse(std::ifstream(dir / "metrics.json")); }

TEST(SolveE2E, SerialAndTwoRanksWriteTheSameResults) {
  const fs::path dir = make_temp_dir("solve");
  const std::string solve = (bin_dir() / "systole-solve").string();
  const std::string scenario = (source_dir() / "examples/healthy-0d.json").string();
  auto [c1, out1] = run_command(solve + " " + scenario + " --quiet --out " + (dir / "serial").string());
  ASSERT_EQ(c1, 0) << out1;
  auto [c2, out2] = run_command("OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 mpirun -np 2 --oversubscribe " +
                                solve + " " + scenario + " --quiet --out " + (dir / "mpi").string());
  ASSERT_EQ(c2, 0) << out2;
  const auto a = read_metrics(dir / "serial");
  const auto b = read_metrics(dir / "mpi");
  for (const char* key : {"ejection_fraction_percent", "cardiac_output_l_min", "edv_ml", "esv_ml", "beats_simulated"})
    EXPECT_EQ(a[key], b[key]) << key;  // the same deterministic computation on every rank
  EXPECT_TRUE(fs::exists(dir / "mpi" / "result.h5"));
  EXPECT_TRUE(fs::exists(dir / "mpi" / "pv_loop.csv"));
  fs::remove_all(dir);
}

TEST(SolveE2E, PlotBeatDrawsTheWiggersDiagramAndThePvLoop) {
  const std::string plot = (bin_dir() / "systole-plot-beat").string();
  ASSERT_TRUE(fs::exists(plot)) << plot;
  const auto [check, why] = run_command(plot + " --check");
  if (check != 0) GTEST_SKIP() << "matplotlib not installed: " << why;
  const fs::path dir = make_temp_dir("plot-beat");
  const auto [c1, out1] = run_command((bin_dir() / "systole-solve").string() + " " +
                                      (source_dir() / "examples/healthy-0d.json").string() + " --quiet --out " +
                                      dir.string());
  ASSERT_EQ(c1, 0) << out1;
  ASSERT_TRUE(fs::exists(dir / "time_series.csv"));
  const auto [code, out] = run_command(plot + " " + dir.string());
  ASSERT_EQ(code, 0) << out;
  for (const char* name : {"wiggers.png", "pv_loop.png"}) {
    ASSERT_TRUE(fs::exists(dir / name)) << out;
    EXPECT_GT(fs::file_size(dir / name), 10000u) << name;
    std::ifstream png(dir / name, std::ios::binary);
    char magic[4] = {};
    png.read(magic, 4);
    EXPECT_EQ(std::string(magic + 1, 3), "PNG") << name;
  }
  // Not a result directory: exit 2, naming the missing file.
  const auto [bad, message] = run_command(plot + " " + (dir / "nowhere").string() + " 2>&1");
  EXPECT_EQ(bad, 2) << message;
  EXPECT_NE(message.find("time_series.csv not found"), std::string::npos) << message;
  fs::remove_all(dir);
}

// Scene mechanics' protocol pv_relations through the CLI (a coarse LV): pv_relations.csv holds
// the points, and systole-plot-pv draws them with the fits.
TEST(SolveE2E, PvRelationsAndTheirPlot) {
  const fs::path dir = make_temp_dir("plot-pv");
  {
    std::ofstream f(dir / "scenario.json");
    f << R"({"scene": "mechanics", "geometry": {"target_edge_mm": 4},
             "structure": {"body": "lv", "walls": "chamber", "protocol": "pv_relations", "pv_points": 2,
                           "edpvr_max_mmhg": 20, "active_tension_kpa": 120, "pressure_ramp_ms": 20,
                           "output_interval_ms": 2, "end_time_ms": 300, "write_positions": false}})";
  }
  const auto [c1, out1] = run_command((bin_dir() / "systole-solve").string() + " " + (dir / "scenario.json").string() +
                                      " --quiet --out " + dir.string());
  ASSERT_EQ(c1, 0) << out1;
  std::ifstream csv(dir / "pv_relations.csv");
  std::string line;
  int rows = 0;
  while (std::getline(csv, line)) ++rows;
  EXPECT_EQ(rows, 1 + 3 + 2);  // header, EDPVR 0/10/20 mmHg, ESPVR 80/120 mmHg
  const std::string plot = (bin_dir() / "systole-plot-pv").string();
  ASSERT_TRUE(fs::exists(plot)) << plot;
  const auto [check, why] = run_command(plot + " --check");
  if (check != 0) GTEST_SKIP() << "matplotlib not installed: " << why;
  const auto [code, out] = run_command(plot + " " + dir.string());
  ASSERT_EQ(code, 0) << out;
  EXPECT_GT(fs::file_size(dir / "pv_relations.png"), 10000u);
  const auto [bad, message] = run_command(plot + " " + (dir / "nowhere").string() + " 2>&1");
  EXPECT_EQ(bad, 2) << message;
  EXPECT_NE(message.find("pv_relations.csv not found"), std::string::npos) << message;
  fs::remove_all(dir);
}

TEST(SolveE2E, ListScenesPrintsTheRegistry) {
  const std::string solve = (bin_dir() / "systole-solve").string();
  // stdout only (the table); stderr (MPI's notes, if any) is not part of it.
  auto [code, output] = run_command("(" + solve + " --list-scenes 2>/dev/null)");
  ASSERT_EQ(code, 0) << output;
  std::istringstream lines(output);
  std::string line;
  std::vector<std::string> names;
  std::getline(lines, line);
  EXPECT_EQ(line.rfind("scene", 0), 0u) << line;  // the header
  while (std::getline(lines, line)) {
    std::istringstream row(line);
    std::string name;
    int metrics = 0;
    row >> name >> metrics;
    EXPECT_GT(metrics, 0) << line;
    std::string description;
    std::getline(row, description);
    EXPECT_GT(description.size(), 10u) << line;
    names.push_back(name);
  }
  // The registry's rows (tests/unit/scene_test.cc checks they are config::implemented_scenes()).
  const std::vector<std::string> expected{"lumped", "analytic", "fluid", "electro", "mechanics",
                                          "ibm", "electromechanics", "fsi", "fsei"};
  EXPECT_EQ(names, expected) << output;
}

TEST(SolveE2E, BadInputExitsTwoNamingTheField) {
  const std::string solve = (bin_dir() / "systole-solve").string();
  const std::string scenario = (source_dir() / "examples/healthy-0d.json").string();
  auto [code, output] = run_command(solve + " " + scenario + " --out /tmp/never --set av_delay_ms=900");
  EXPECT_EQ(code, 2);
  EXPECT_NE(output.find("av_delay_ms = 900 is out of range [0, 400]"), std::string::npos) << output;
  EXPECT_FALSE(fs::exists("/tmp/never/result.h5"));
}

}  // namespace
}  // namespace systole::e2e
