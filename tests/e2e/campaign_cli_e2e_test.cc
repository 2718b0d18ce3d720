// `systole campaign ...` end to end: a real server with 2 local workers, the CLI binary, the
// files of `campaign results` (CSV, HDF5 read back with the HDF5 C API, statistics.json), the
// exit codes (0 all succeeded, 1 failed samples, 2 bad input, 3 unreachable) and
// systole-plot-campaign when matplotlib is installed.
#include <hdf5.h>

#include <cmath>
#include <set>

#include "tests/e2e/harness.h"

namespace systole::e2e {
namespace {

std::string systole_bin() { return (bin_dir() / "systole").string(); }

std::string trim(std::string s) {
  while (!s.empty() && (s.back() == '\n' || s.back() == '\r' || s.back() == ' ')) s.pop_back();
  return s;
}

bool contains(const std::string& text, const std::string& needle) { return text.find(needle) != std::string::npos; }

// RFC 4180 CSV: quoted cells may hold commas, quotes and newlines.
std::vector<std::vector<std::string>> read_csv(const fs::path& file) {
  std::ifstream in(file);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::vector<std::vector<std::string>> rows;
  std::vector<std::string> row;
  std::string cell;
  bool quoted = false;
  for (size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (quoted) {
      if (c == '"' && i + 1 < text.size() && text[i + 1] == '"') {
        cell += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        cell += c;
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      row.push_back(cell);
      cell.clear();
    } else if (c == '\n') {
      row.push_back(cell);
      cell.clear();
      rows.push_back(row);
      row.clear();
    } else {
      cell += c;
    }
  }
  return rows;
}

// Minimal HDF5 reading (the C API, as a user's tool would).
class H5Reader {
 public:
  explicit H5Reader(const fs::path& file) : id_(H5Fopen(file.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT)) {}
  ~H5Reader() {
    if (id_ >= 0) H5Fclose(id_);
  }
  bool ok() const { return id_ >= 0; }
  bool exists(const std::string& path) const {
    std::string prefix;
    std::istringstream in(path);
    std::string part;
    while (std::getline(in, part, '/')) {
      if (part.empty()) continue;
      prefix += "/" + part;
      if (H5Lexists(id_, prefix.c_str(), H5P_DEFAULT) <= 0) return false;
    }
    return true;
  }
  std::vector<hsize_t> dims(const std::string& path) const {
    const hid_t set = H5Dopen2(id_, path.c_str(), H5P_DEFAULT);
    if (set < 0) return {};
    const hid_t space = H5Dget_space(set);
    std::vector<hsize_t> d(static_cast<size_t>(std::max(0, H5Sget_simple_extent_ndims(space))));
    H5Sget_simple_extent_dims(space, d.data(), nullptr);
    H5Sclose(space);
    H5Dclose(set);
    return d;
  }
  std::vector<double> doubles(const std::string& path) const {
    const hid_t set = H5Dopen2(id_, path.c_str(), H5P_DEFAULT);
    if (set < 0) return {};
    const hid_t space = H5Dget_space(set);
    std::vector<double> v(static_cast<size_t>(H5Sget_simple_extent_npoints(space)));
    if (!v.empty()) H5Dread(set, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data());
    H5Sclose(space);
    H5Dclose(set);
    return v;
  }
  std::vector<int> ints(const std::string& path) const {
    const hid_t set = H5Dopen2(id_, path.c_str(), H5P_DEFAULT);
    if (set < 0) return {};
    const hid_t space = H5Dget_space(set);
    std::vector<int> v(static_cast<size_t>(H5Sget_simple_extent_npoints(space)));
    if (!v.empty()) H5Dread(set, H5T_NATIVE_INT, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data());
    H5Sclose(space);
    H5Dclose(set);
    return v;
  }
  // A variable-length string attribute (scalar or 1-D) of the object at `path`.
  std::vector<std::string> string_attribute(const std::string& path, const std::string& name) const {
    std::vector<std::string> out;
    const hid_t attr = H5Aopen_by_name(id_, path.c_str(), name.c_str(), H5P_DEFAULT, H5P_DEFAULT);
    if (attr < 0) return out;
    const hid_t space = H5Aget_space(attr);
    const hid_t stored = H5Aget_type(attr);
    const hid_t type = H5Tcopy(H5T_C_S1);
    H5Tset_size(type, H5T_VARIABLE);
    H5Tset_cset(type, H5Tget_cset(stored));  // no conversion between ASCII and UTF-8
    H5Tclose(stored);
    std::vector<char*> p(static_cast<size_t>(H5Sget_simple_extent_npoints(space)), nullptr);
    if (!p.empty() && H5Aread(attr, type, p.data()) >= 0) {
      for (char* s : p) out.emplace_back(s ? s : "");
      H5Dvlen_reclaim(type, space, H5P_DEFAULT, p.data());
    }
    H5Tclose(type);
    H5Sclose(space);
    H5Aclose(attr);
    return out;
  }

 private:
  hid_t id_;
};

nlohmann::json zero_d_spec(int n, const std::string& design, int seed) {
  return {{"base_scenario", {{"scene", "lumped"}, {"outputs", {{"time_series", false}}}}},
          {"parameters",
           {{{"path", "lumped.lv.emax_mmhg_per_ml"}, {"uniform", {{"min", 2.0}, {"max", 3.5}}}},
            {{"path", "heart_rate_bpm"}, {"uniform", {{"min", 60}, {"max", 90}}}},
            {{"path", "lumped.systemic_resistance_mmhg_s_per_ml"}, {"uniform", {{"min", 0.8}, {"max", 1.3}}}}}},
          {"design", design}, {"samples", n}, {"seed", seed},
          {"quantities_of_interest", {"ejection_fraction_percent", "cardiac_output_l_min"}}};
}

nlohmann::json ishigami_spec(int n) {
  nlohmann::json params = nlohmann::json::array();
  for (const char* x : {"analytic.x1", "analytic.x2", "analytic.x3"})
    params.push_back({{"path", x}, {"uniform", {{"min", -3.14159}, {"max", 3.14159}}}});
  return {{"base_scenario", {{"scene", "analytic"}}}, {"parameters", params}, {"design", "SALTELLI"},
          {"samples", n}, {"seed", 7}, {"quantities_of_interest", {"f"}}};
}

class CampaignCliE2E : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = make_temp_dir("campaign-cli");
    server_ = new ServerProcess(dir_, /*local_workers=*/2, /*ranks=*/1, /*lease_ms=*/3000);
  }
  static void TearDownTestSuite() {
    delete server_;
    server_ = nullptr;
    fs::remove_all(dir_);
  }

  // `systole --server ADDR campaign ARGS`: {exit code, stdout+stderr}.
  static std::pair<int, std::string> campaign(const std::string& args) {
    return run_command(systole_bin() + " --server " + server_->address() + " campaign " + args);
  }
  static fs::path write_spec(const std::string& name, const nlohmann::json& spec) {
    const fs::path file = dir_ / (name + ".json");
    std::ofstream(file) << spec.dump(2);
    return file;
  }
  // Submits; returns the id (stdout only: the stderr note is dropped).
  static std::string submit(const fs::path& spec, const std::string& extra = "") {
    std::string command = systole_bin() + " --server " + server_->address() + " campaign submit ";
    command += spec.string() + " " + extra;
    const auto [code, out] = run_command("(" + command + " 2>/dev/null)");
    EXPECT_EQ(code, 0) << out;
    return trim(out);
  }
  static nlohmann::json read_json(const fs::path& file) {
    std::ifstream in(file);
    return nlohmann::json::parse(in);
  }

  // The SALTELLI campaign over the analytic scene, watched and written once for the tests that
  // need it: the results directory.
  static const fs::path& saltelli_results() {
    if (!saltelli_dir_.empty()) return saltelli_dir_;
    const std::string id = submit(write_spec("ishigami", ishigami_spec(16)));
    const auto [code, out] = campaign("watch " + id);
    EXPECT_EQ(code, 0) << out;
    saltelli_watch_output_ = out;
    const fs::path results = dir_ / "ishigami-results";
    const auto [rcode, rout] = campaign("results " + id + " --out " + results.string());
    EXPECT_EQ(rcode, 0) << rout;
    saltelli_id_ = id;
    saltelli_dir_ = results;
    return saltelli_dir_;
  }

  static inline fs::path dir_;
  static inline ServerProcess* server_ = nullptr;
  static inline fs::path saltelli_dir_;
  static inline std::string saltelli_id_, saltelli_watch_output_;
};

TEST_F(CampaignCliE2E, ZeroDLatinHypercubeSubmitWatchStatusResults) {
  // The file says 10 samples; --set makes it 20 (and changes a base scenario field).
  const fs::path spec = write_spec("lhs", zero_d_spec(10, "LATIN_HYPERCUBE", 11));
  const std::string id = submit(spec, "--set samples=20 --set base.beats=25 --request-id cli-lhs");
  ASSERT_FALSE(id.empty());
  EXPECT_EQ(submit(spec, "--set samples=20 --set base.beats=25 --request-id cli-lhs"), id);  // idempotent

  const auto [code, out] = campaign("watch " + id);
  ASSERT_EQ(code, 0) << out;
  EXPECT_TRUE(contains(out, "20/20 done")) << out;                 // a line per change, not a bar: no TTY
  EXPECT_TRUE(contains(out, "SUCCEEDED 20")) << out;
  EXPECT_TRUE(contains(out, "ejection_fraction_percent")) << out;  // the summary table
  EXPECT_TRUE(contains(out, "cardiac_output_l_min")) << out;
  EXPECT_TRUE(contains(out, "spearman")) << out;
  EXPECT_FALSE(contains(out, "first order S1")) << out;            // no Sobol' indices without SALTELLI
  EXPECT_FALSE(contains(out, "\r")) << out;

  const auto [scode, status] = campaign("status " + id);
  EXPECT_EQ(scode, 0) << status;
  EXPECT_TRUE(contains(status, "FINISHED")) << status;
  EXPECT_TRUE(contains(status, "LATIN_HYPERCUBE, 20 base samples, 20 jobs")) << status;
  const auto [jcode, json_text] = campaign("status " + id + " --json");
  ASSERT_EQ(jcode, 0) << json_text;
  const auto status_json = nlohmann::json::parse(json_text);
  EXPECT_EQ(status_json["campaign"]["id"], id);
  EXPECT_EQ(status_json["campaign"]["spec"]["base_scenario"]["beats"], 25);

  const fs::path results = dir_ / "lhs-results";
  const auto [rcode, rout] = campaign("results " + id + " --out " + results.string());
  ASSERT_EQ(rcode, 0) << rout;

  // CSV: header + one row per sample, every column.
  const auto csv = read_csv(results / "campaign.csv");
  ASSERT_EQ(csv.size(), 21u);
  const std::vector<std::string> header{"index", "job_id", "state", "lumped.lv.emax_mmhg_per_ml", "heart_rate_bpm",
                                        "lumped.systemic_resistance_mmhg_s_per_ml", "ejection_fraction_percent",
                                        "cardiac_output_l_min", "cached_from", "error"};
  EXPECT_EQ(csv[0], header);
  std::set<std::string> jobs;
  for (size_t r = 1; r < csv.size(); ++r) {
    ASSERT_EQ(csv[r].size(), header.size()) << r;
    EXPECT_EQ(csv[r][0], std::to_string(r - 1));
    EXPECT_EQ(csv[r][2], "SUCCEEDED");
    jobs.insert(csv[r][1]);
    const double emax = std::stod(csv[r][3]), hr = std::stod(csv[r][4]), rs = std::stod(csv[r][5]);
    EXPECT_TRUE(emax >= 2.0 && emax <= 3.5 && hr >= 60 && hr <= 90 && rs >= 0.8 && rs <= 1.3) << r;
    const double ef = std::stod(csv[r][6]), co = std::stod(csv[r][7]);
    EXPECT_TRUE(ef > 20 && ef < 90 && co > 1 && co < 15) << ef << " " << co;
    EXPECT_EQ(csv[r][9], "");
  }
  EXPECT_EQ(jobs.size(), 20u);

  // statistics.json: the GetCampaignResponse.
  const auto stats = read_json(results / "statistics.json");
  EXPECT_EQ(stats["campaign"]["id"], id);
  EXPECT_EQ(stats["statistics"]["samples_succeeded"], 20);
  EXPECT_EQ(stats["statistics"]["samples_failed"], 0);  // zeros are printed too
  ASSERT_EQ(stats["statistics"]["qoi"].size(), 2u);
  const double ef_mean = stats["statistics"]["qoi"][0]["mean"].get<double>();

  // campaign.h5
  H5Reader h5(results / "campaign.h5");
  ASSERT_TRUE(h5.ok());
  EXPECT_EQ(h5.dims("/samples/inputs"), (std::vector<hsize_t>{20, 3}));
  EXPECT_EQ(h5.dims("/samples/outputs"), (std::vector<hsize_t>{20, 2}));
  EXPECT_EQ(h5.string_attribute("/samples/inputs", "paths"),
            (std::vector<std::string>{"lumped.lv.emax_mmhg_per_ml", "heart_rate_bpm",
                                      "lumped.systemic_resistance_mmhg_s_per_ml"}));
  EXPECT_EQ(h5.string_attribute("/samples/outputs", "names"),
            (std::vector<std::string>{"ejection_fraction_percent", "cardiac_output_l_min"}));
  EXPECT_EQ(h5.string_attribute("/samples/outputs", "units"), (std::vector<std::string>{"%", "l/min"}));
  const auto state = h5.ints("/samples/state");
  ASSERT_EQ(state.size(), 20u);
  const auto legend = h5.string_attribute("/samples/state", "legend");
  ASSERT_GT(legend.size(), 3u);
  for (int s : state) EXPECT_EQ(legend.at(static_cast<size_t>(s)), "SUCCEEDED");
  const auto outputs = h5.doubles("/samples/outputs");
  ASSERT_EQ(outputs.size(), 40u);
  EXPECT_DOUBLE_EQ(outputs[0], std::stod(csv[1][6]));
  for (double v : outputs) EXPECT_TRUE(std::isfinite(v));
  for (const char* d : {"mean", "std", "percentiles", "histogram_edges", "histogram_counts", "pearson", "spearman"})
    EXPECT_TRUE(h5.exists(std::string("/statistics/ejection_fraction_percent/") + d)) << d;
  EXPECT_FALSE(h5.exists("/statistics/ejection_fraction_percent/sobol_first"));
  EXPECT_DOUBLE_EQ(h5.doubles("/statistics/ejection_fraction_percent/mean").at(0), ef_mean);
  EXPECT_EQ(h5.doubles("/statistics/ejection_fraction_percent/percentiles").size(), 5u);
  EXPECT_EQ(h5.doubles("/statistics/cardiac_output_l_min/pearson").size(), 3u);
  const auto spec_json = h5.string_attribute("/", "spec_json");
  ASSERT_EQ(spec_json.size(), 1u);
  EXPECT_EQ(nlohmann::json::parse(spec_json[0])["samples"], 20);

  const auto [lcode, list] = campaign("list");
  EXPECT_EQ(lcode, 0) << list;
  EXPECT_TRUE(contains(list, id)) << list;
}

TEST_F(CampaignCliE2E, SaltelliCampaignHasSobolIndicesInTheSummaryAndFiles) {
  const fs::path& results = saltelli_results();
  const std::string& out = saltelli_watch_output_;
  EXPECT_TRUE(contains(out, "80/80 done")) << out;  // N (d + 2) = 16 x 5
  EXPECT_TRUE(contains(out, "first order S1 [low, high]")) << out;
  EXPECT_TRUE(contains(out, "analytic.x3")) << out;

  const auto csv = read_csv(results / "campaign.csv");
  ASSERT_EQ(csv.size(), 81u);
  EXPECT_EQ(csv[0], (std::vector<std::string>{"index", "job_id", "state", "analytic.x1", "analytic.x2", "analytic.x3",
                                              "f", "cached_from", "error"}));
  for (size_t r = 1; r < csv.size(); ++r) EXPECT_EQ(csv[r].size(), 9u);

  H5Reader h5(results / "campaign.h5");
  ASSERT_TRUE(h5.ok());
  EXPECT_EQ(h5.dims("/samples/inputs"), (std::vector<hsize_t>{80, 3}));
  EXPECT_EQ(h5.dims("/samples/outputs"), (std::vector<hsize_t>{80, 1}));
  for (const char* d : {"sobol_first", "sobol_first_low", "sobol_first_high", "sobol_total", "sobol_total_low",
                        "sobol_total_high"}) {
    const auto v = h5.doubles(std::string("/statistics/f/") + d);
    ASSERT_EQ(v.size(), 3u) << d;
    for (double x : v) EXPECT_TRUE(std::isfinite(x)) << d;
  }
  const auto s1 = h5.doubles("/statistics/f/sobol_first");
  const auto lo = h5.doubles("/statistics/f/sobol_first_low");
  const auto hi = h5.doubles("/statistics/f/sobol_first_high");
  for (size_t i = 0; i < 3; ++i) EXPECT_TRUE(lo[i] <= s1[i] && s1[i] <= hi[i]) << i;

  const auto stats = read_json(results / "statistics.json");
  EXPECT_EQ(stats["campaign"]["spec"]["design"], "SALTELLI");
  EXPECT_TRUE(stats["statistics"]["qoi"][0]["sensitivities"][0].contains("sobol_first"));
  EXPECT_EQ(stats["statistics"]["sobol_rows_used"], 16);
}

TEST_F(CampaignCliE2E, PlotScriptWritesThePng) {
  const std::string plot = (bin_dir() / "systole-plot-campaign").string();
  ASSERT_TRUE(fs::exists(plot)) << plot;
  const auto [check, why] = run_command(plot + " --check");
  if (check != 0) GTEST_SKIP() << "matplotlib not installed: " << why;
  const fs::path& results = saltelli_results();
  fs::remove(results / "campaign.png");
  const auto [code, out] = run_command(plot + " " + results.string());
  ASSERT_EQ(code, 0) << out;
  ASSERT_TRUE(fs::exists(results / "campaign.png")) << out;
  EXPECT_GT(fs::file_size(results / "campaign.png"), 10000u);
  std::ifstream png(results / "campaign.png", std::ios::binary);
  char magic[4] = {};
  png.read(magic, 4);
  EXPECT_EQ(std::string(magic + 1, 3), "PNG");
  // A directory without results: a clear message, exit 2.
  const auto [bad, message] = run_command(plot + " " + (dir_ / "nowhere").string());
  EXPECT_EQ(bad, 2) << message;
  EXPECT_TRUE(contains(message, "statistics.json")) << message;
}

TEST_F(CampaignCliE2E, FailedSamplesExitOneAreListedAndCanBeRetried) {
  // Emin above the default Emax 2.7 breaks "emax must exceed emin": those draws fail.
  nlohmann::json spec = {{"base_scenario", {{"scene", "lumped"}, {"outputs", {{"time_series", false}}}}},
                         {"parameters", {{{"path", "lumped.lv.emin_mmhg_per_ml"}, {"uniform", {{"min", 0.05}, {"max", 5}}}}}},
                         {"design", "LATIN_HYPERCUBE"}, {"samples", 8}, {"seed", 5},
                         {"quantities_of_interest", {"edv_ml"}}};
  const std::string id = submit(write_spec("failing", spec));
  const auto [code, out] = campaign("watch " + id);
  EXPECT_EQ(code, 1) << out;
  EXPECT_TRUE(contains(out, "failed or cancelled sample")) << out;
  EXPECT_TRUE(contains(out, "must exceed lumped.lv.emin_mmhg_per_ml")) << out;
  EXPECT_TRUE(contains(out, "systole campaign retry " + id)) << out;

  const fs::path results = dir_ / "failing-results";
  const auto [rcode, rout] = campaign("results " + id + " --out " + results.string());
  ASSERT_EQ(rcode, 0) << rout;
  const auto csv = read_csv(results / "campaign.csv");
  ASSERT_EQ(csv.size(), 9u);
  int failed = 0;
  H5Reader h5(results / "campaign.h5");
  const auto outputs = h5.doubles("/samples/outputs");
  ASSERT_EQ(outputs.size(), 8u);
  for (size_t r = 1; r < csv.size(); ++r) {
    ASSERT_EQ(csv[r].size(), 7u);
    if (csv[r][2] == "FAILED") {
      ++failed;
      EXPECT_EQ(csv[r][4], "");  // no QoI
      EXPECT_TRUE(contains(csv[r][6], "must exceed")) << csv[r][6];
      EXPECT_TRUE(std::isnan(outputs[r - 1]));
    } else {
      EXPECT_EQ(csv[r][2], "SUCCEEDED");
      EXPECT_TRUE(std::isfinite(outputs[r - 1]));
    }
  }
  EXPECT_GT(failed, 0);
  EXPECT_LT(failed, 8);

  const auto [tcode, tout] = campaign("retry " + id);
  EXPECT_EQ(tcode, 0) << tout;
  EXPECT_TRUE(contains(tout, std::to_string(failed) + " failed or cancelled sample")) << tout;
  const auto [again, again_out] = campaign("watch " + id + " --quiet");  // they fail again, deterministically
  EXPECT_EQ(again, 1) << again_out;
}

TEST_F(CampaignCliE2E, CancelStopsTheCampaignAndWatchReportsIt) {
  nlohmann::json spec = zero_d_spec(400, "MONTE_CARLO", 99);
  spec["no_cache"] = true;
  const std::string id = submit(write_spec("cancel", spec));
  const auto [code, out] = campaign("cancel " + id);
  EXPECT_EQ(code, 0) << out;
  EXPECT_TRUE(contains(out, id + " CANCEL")) << out;
  const auto [wcode, wout] = campaign("watch " + id);
  EXPECT_EQ(wcode, 1) << wout;
  EXPECT_TRUE(contains(wout, "CANCELLED")) << wout;
  const auto [scode, sout] = campaign("status " + id + " --json");
  ASSERT_EQ(scode, 0) << sout;
  const auto j = nlohmann::json::parse(sout);
  EXPECT_TRUE(j["campaign"]["cancelled"].get<bool>());
  EXPECT_GT(j["campaign"]["jobs_by_state"]["CANCELLED"].get<int>(), 0);
}

TEST_F(CampaignCliE2E, BadInputExitsTwoNamingTheOffender) {
  auto spec = zero_d_spec(10, "MONTE_CARLO", 1);
  spec["parameters"][0]["path"] = "lumped.lv.emax";
  auto [code, out] = campaign("submit " + write_spec("bad-path", spec).string());
  EXPECT_EQ(code, 2) << out;
  EXPECT_TRUE(contains(out, "'lumped.lv.emax' is not a scenario field")) << out;

  spec = zero_d_spec(10, "MONTE_CARLO", 1);
  spec["quantities_of_interest"] = {"ef"};
  std::tie(code, out) = campaign("submit " + write_spec("bad-qoi", spec).string());
  EXPECT_EQ(code, 2) << out;
  EXPECT_TRUE(contains(out, "'ef' is not a metric of scene 'lumped'")) << out;

  const fs::path good = write_spec("good", zero_d_spec(10, "MONTE_CARLO", 1));
  std::tie(code, out) = campaign("submit " + good.string() + " --set base.lumped.lv.nope=1");
  EXPECT_EQ(code, 2) << out;
  EXPECT_TRUE(contains(out, "lumped.lv.nope")) << out;
  std::tie(code, out) = campaign("submit " + good.string() + " --set bogus=1");
  EXPECT_EQ(code, 2) << out;
  EXPECT_TRUE(contains(out, "unknown key 'bogus'")) << out;
  std::tie(code, out) = campaign("submit " + good.string() + " --set samples=many");
  EXPECT_EQ(code, 2) << out;
  EXPECT_TRUE(contains(out, "'many' is not a number")) << out;

  spec = zero_d_spec(10, "MONTE_CARLO", 1);
  spec["sample_count"] = 10;
  std::tie(code, out) = campaign("submit " + write_spec("bad-field", spec).string());
  EXPECT_EQ(code, 2) << out;
  EXPECT_TRUE(contains(out, "sample_count")) << out;

  std::ofstream(dir_ / "broken.json") << "{\"samples\": ";
  std::tie(code, out) = campaign("submit " + (dir_ / "broken.json").string());
  EXPECT_EQ(code, 2) << out;
  EXPECT_TRUE(contains(out, "is not valid JSON")) << out;
  std::tie(code, out) = campaign("submit " + (dir_ / "missing.json").string());
  EXPECT_EQ(code, 2) << out;
  EXPECT_TRUE(contains(out, "cannot read campaign spec")) << out;

  for (const char* command : {"watch", "status", "retry", "cancel"}) {
    std::tie(code, out) = campaign(std::string(command) + " no-such-campaign");
    EXPECT_EQ(code, 2) << command << ": " << out;
    EXPECT_TRUE(contains(out, "not found")) << command << ": " << out;
  }
  std::tie(code, out) = campaign("results no-such-campaign --out " + (dir_ / "none").string());
  EXPECT_EQ(code, 2) << out;

  // Nothing listens on port 1: unreachable, exit 3.
  std::tie(code, out) = run_command(systole_bin() + " --server 127.0.0.1:1 campaign list");
  EXPECT_EQ(code, 3) << out;
  EXPECT_TRUE(contains(out, "cannot reach systole-server")) << out;
}

}  // namespace
}  // namespace systole::e2e
