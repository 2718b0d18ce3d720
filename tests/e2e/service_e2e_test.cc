// End-to-end: a real server on 127.0.0.1 (ephemeral ports), real workers under mpirun -np 2,
// gRPC, REST and the CLI. Physiology of the 0-D scene itself is tested in tests/lumped.
#include <httplib.h>

#include <cmath>

#include "service/server/sha256.h"
#include "tests/e2e/harness.h"

namespace systole::e2e {
namespace {

class ServiceE2E : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = make_temp_dir("service");
    server_ = new ServerProcess(dir_, /*local_workers=*/1, /*ranks=*/2);
  }
  static void TearDownTestSuite() {
    delete server_;
    server_ = nullptr;
    fs::remove_all(dir_);
  }
  static inline fs::path dir_;
  static inline ServerProcess* server_ = nullptr;
};

int64_t job_count(ServerProcess& server) {
  int64_t n = 0;
  std::string token;
  do {
    v1::ListJobsRequest request;
    request.set_page_size(1000);
    request.set_page_token(token);
    v1::ListJobsResponse response;
    auto context = deadline_context();
    EXPECT_TRUE(server.stub().ListJobs(context.get(), request, &response).ok());
    n += response.jobs_size();
    token = response.next_page_token();
  } while (!token.empty());
  return n;
}

TEST_F(ServiceE2E, HealthyJobSucceedsWithResultsAndVerifiedArtifacts) {
  const std::string id = submit(*server_, {{"scene", "lumped"}});
  ASSERT_TRUE(wait_for_state(*server_, id, v1::SUCCEEDED, std::chrono::seconds(60))) << server_->log();
  const v1::Result result = get_result(*server_, id);
  for (const char* key : {"ejection_fraction_percent", "cardiac_output_l_min", "stroke_volume_ml", "edv_ml", "esv_ml",
                          "lv_peak_pressure_mmhg", "aortic_pressure_max_mmhg", "aortic_pressure_min_mmhg",
                          "heart_rate_bpm", "beats_simulated", "wall_time_s"})
    EXPECT_TRUE(result.metrics().contains(key)) << key;
  EXPECT_GT(result.metrics().at("ejection_fraction_percent"), 40.0);
  EXPECT_LT(result.metrics().at("ejection_fraction_percent"), 80.0);
  ASSERT_GE(result.time_series_size(), 2);
  EXPECT_EQ(result.time_series(0).name(), "time_s");
  EXPECT_GT(result.time_series(0).values_size(), 100);
  EXPECT_GE(result.beats_size(), 1);

  std::set<std::string> names;
  for (const auto& a : result.artifacts()) names.insert(a.name());
  EXPECT_EQ(names, (std::set<std::string>{"metrics.json", "pv_loop.csv", "result.h5", "time_series.csv"}));
  // Download result.h5 over gRPC and check its sha256 end to end.
  v1::DownloadArtifactRequest dl;
  dl.set_id(id);
  dl.set_name("result.h5");
  auto ctx = deadline_context();
  auto reader = server_->stub().DownloadArtifact(ctx.get(), dl);
  v1::ArtifactChunk chunk;
  service::Sha256 hash;
  int64_t bytes = 0;
  std::string declared;
  while (reader->Read(&chunk)) {
    hash.update(chunk.data());
    bytes += static_cast<int64_t>(chunk.data().size());
    declared = chunk.sha256();
  }
  ASSERT_TRUE(reader->Finish().ok());
  EXPECT_GT(bytes, 1000);
  EXPECT_EQ(hash.hex_digest(), declared);
  // HDF5 magic number.
  httplib::Client http("127.0.0.1", server_->http_port());
  auto res = http.Get("/v1/jobs/" + id + "/artifacts/result.h5");
  ASSERT_TRUE(res);
  EXPECT_EQ(res->status, 200);
  EXPECT_EQ(res->body.substr(0, 8), std::string("\x89HDF\r\n\x1a\n", 8));
  EXPECT_EQ(res->get_header_value("X-Sha256"), declared);
  // REST result.
  auto rest = http.Get("/v1/jobs/" + id + "/result");
  ASSERT_TRUE(rest);
  EXPECT_EQ(rest->status, 200);
  const auto body = nlohmann::json::parse(rest->body);
  EXPECT_TRUE(body["metrics"].contains("cardiac_output_l_min"));
}

TEST_F(ServiceE2E, ElectromechanicsJobRunsOnTheWorkersWithPerBeatMetricsAndFields) {
  // A short, coarse electromechanics job (issue #8): 2 beats of 250 ms on the 3 mm heart (the
  // calibrated wall crumples at 0.49 s on the 4 mm mesh: docs/electromechanics.md).
  const nlohmann::json scenario{{"scene", "electromechanics"},
                                {"beats", 2},
                                {"periodicity_tolerance", 0},
                                {"heart_rate_bpm", 240},
                                {"geometry", {{"target_edge_mm", 3}}},
                                {"electro", {{"model", "monodomain"}, {"time_step_ms", 0.1}}},
                                {"electromechanics", {{"la_chamber", "lumped"}, {"field_interval_ms", 50}}}};
  const std::string id = submit(*server_, scenario);
  ASSERT_TRUE(wait_for_state(*server_, id, v1::SUCCEEDED, std::chrono::seconds(300))) << server_->log();
  const v1::Result result = get_result(*server_, id);
  for (const char* key : {"ejection_fraction_percent", "cardiac_output_l_min", "lv_peak_pressure_mmhg",
                          "lv_twist_end_systole_deg", "global_longitudinal_strain_percent", "max_volume_mismatch_ml",
                          "beats_simulated", "wall_time_s"})
    EXPECT_TRUE(result.metrics().contains(key)) << key;
  EXPECT_EQ(result.metrics().at("beats_simulated"), 2);
  EXPECT_EQ(result.beats_size(), 2);
  std::set<std::string> names;
  for (const auto& a : result.artifacts()) names.insert(a.name());
  for (const char* f : {"metrics.json", "pv_loop.csv", "result.h5", "time_series.csv", "em_fields.h5", "em_fields.xmf"})
    EXPECT_TRUE(names.count(f)) << f;
}

TEST_F(ServiceE2E, FsiJobRunsOnTheWorkersWithChamberMetricsAndFields) {
  // Scene "fsi" through the service (issue #9): the first millisecond of the coarse heart in
  // blood, fields every 0.5 ms. The physics of the scene is tested in tests/coupling.
  const nlohmann::json scenario{{"scene", "fsi"}, {"fsei", {{"end_time_ms", 1}, {"field_interval_ms", 0.5}}}};
  const std::string id = submit(*server_, scenario);
  ASSERT_TRUE(wait_for_state(*server_, id, v1::SUCCEEDED, std::chrono::seconds(300))) << server_->log();
  const v1::Result result = get_result(*server_, id);
  for (const char* key : {"lv_pressure_max_mmhg", "aortic_root_pressure_max_mmhg", "lv_volume_end_ml",
                          "aortic_cusps_wss_max_pa", "wall_time_s"})
    EXPECT_TRUE(result.metrics().contains(key)) << key;
  for (const auto& [key, value] : result.metrics()) EXPECT_TRUE(std::isfinite(value)) << key;
  std::set<std::string> names;
  for (const auto& a : result.artifacts()) names.insert(a.name());
  for (const char* f : {"metrics.json", "result.h5", "time_series.csv", "fsei_bodies.h5", "fsei_fields.xmf"})
    EXPECT_TRUE(names.count(f)) << f;
}

TEST_F(ServiceE2E, FseiJobRunsOnTheWorkersWithItsElectrophysiology) {
  // Scene "fsei" (EP-driven tension) through the service: the first millisecond after the EP's
  // pre-run from the LA stimulus, one field frame at its end. The physics: tests/coupling.
  const nlohmann::json scenario{{"scene", "fsei"}, {"fsei", {{"end_time_ms", 1}, {"field_interval_ms", 1}}}};
  const std::string id = submit(*server_, scenario);
  ASSERT_TRUE(wait_for_state(*server_, id, v1::SUCCEEDED, std::chrono::seconds(300))) << server_->log();
  const v1::Result result = get_result(*server_, id);
  ASSERT_TRUE(result.metrics().contains("ep_steps"));
  EXPECT_GT(result.metrics().at("ep_steps"), 0);  // the EP ran at its own step
  EXPECT_EQ(result.metrics().at("field_frames"), 2);  // t = 0 and 1 ms
  for (const auto& [key, value] : result.metrics()) EXPECT_TRUE(std::isfinite(value)) << key;
  std::set<std::string> names;
  for (const auto& a : result.artifacts()) names.insert(a.name());
  for (const char* f : {"metrics.json", "result.h5", "time_series.csv", "fsei_bodies.h5", "fsei_fields.xmf"})
    EXPECT_TRUE(names.count(f)) << f;
}

TEST_F(ServiceE2E, WatchStreamsStatesInOrderAndResumes) {
  const std::string id = submit(*server_, {{"scene", "lumped"}, {"beats", 5}, {"periodicity_tolerance", 0}});
  std::vector<v1::JobEvent> events;
  {
    auto context = deadline_context(60);
    v1::WatchJobRequest request;
    request.set_id(id);
    auto reader = server_->stub().WatchJob(context.get(), request);
    v1::JobEvent e;
    while (reader->Read(&e)) events.push_back(e);
    ASSERT_TRUE(reader->Finish().ok());
  }
  ASSERT_GE(events.size(), 4u);
  EXPECT_EQ(events.front().kind(), "snapshot");
  EXPECT_EQ(events.back().state(), v1::SUCCEEDED);
  int progress = 0;
  std::vector<v1::JobState> states;
  for (size_t i = 1; i < events.size(); ++i) {
    EXPECT_GT(events[i].sequence(), i > 1 ? events[i - 1].sequence() : 0);
    if (events[i].kind() == "progress") ++progress;
    if (events[i].kind() == "state") states.push_back(events[i].state());
  }
  EXPECT_EQ(states, (std::vector<v1::JobState>{v1::QUEUED, v1::RUNNING, v1::SUCCEEDED}));
  EXPECT_GE(progress, 1);
  // Resume after the second event: exactly the later ones come back.
  const int64_t resume_after = events[2].sequence();
  auto context = deadline_context(30);
  v1::WatchJobRequest request;
  request.set_id(id);
  request.set_after_sequence(resume_after);
  auto reader = server_->stub().WatchJob(context.get(), request);
  v1::JobEvent e;
  std::vector<int64_t> resumed;
  while (reader->Read(&e))
    if (e.kind() != "snapshot") resumed.push_back(e.sequence());
  ASSERT_TRUE(reader->Finish().ok());
  ASSERT_FALSE(resumed.empty());
  EXPECT_EQ(resumed.front(), resume_after + 1);
  EXPECT_EQ(resumed.back(), events.back().sequence());
}

TEST_F(ServiceE2E, RestWatchAsNdjsonAndSse) {
  const std::string id = submit(*server_, {{"scene", "lumped"}, {"beats", 3}, {"periodicity_tolerance", 0}});
  ASSERT_TRUE(wait_for_state(*server_, id, v1::SUCCEEDED, std::chrono::seconds(60)));
  httplib::Client http("127.0.0.1", server_->http_port());
  auto nd = http.Get("/v1/jobs/" + id + ":watch");
  ASSERT_TRUE(nd);
  EXPECT_EQ(nd->status, 200);
  std::istringstream lines(nd->body);
  std::string line, last;
  int n = 0;
  while (std::getline(lines, line)) {
    if (line.empty()) continue;
    EXPECT_NO_THROW((void)nlohmann::json::parse(line)) << line;
    last = line;
    ++n;
  }
  EXPECT_GE(n, 4);
  EXPECT_EQ(nlohmann::json::parse(last)["state"], "SUCCEEDED");
  auto sse = http.Get("/v1/jobs/" + id + ":watch", {{"Accept", "text/event-stream"}});
  ASSERT_TRUE(sse);
  EXPECT_NE(sse->body.find("data: {"), std::string::npos);
  EXPECT_NE(sse->body.find("id: "), std::string::npos);
}

TEST_F(ServiceE2E, BadInputGetsClearErrorsAndChangesNothing) {
  const int64_t before = job_count(*server_);
  httplib::Client http("127.0.0.1", server_->http_port());
  // Malformed JSON.
  auto r = http.Post("/v1/jobs", "{\"scenario\": {", "application/json");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 400);
  EXPECT_EQ(nlohmann::json::parse(r->body)["code"], 3);
  // Unknown field.
  r = http.Post("/v1/jobs", R"({"scenario": {"heart_rate_bmp": 70}})", "application/json");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 400);
  EXPECT_NE(r->body.find("heart_rate_bmp"), std::string::npos) << r->body;
  // Out of range: the message names the field, the value and the range.
  r = http.Post("/v1/jobs", R"({"scenario": {"heart_rate_bpm": 400}})", "application/json");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 400);
  EXPECT_NE(r->body.find("heart_rate_bpm = 400 is out of range [20, 240]"), std::string::npos) << r->body;
  // Unimplemented scene: an error, not a fallback.
  r = http.Post("/v1/jobs", R"({"scenario": {"scene": "geometry"}})", "application/json");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 400);
  EXPECT_NE(r->body.find("not implemented"), std::string::npos) << r->body;
  // 100 MB request: refused by both front ends.
  const std::string huge(100u << 20, ' ');
  r = http.Post("/v1/jobs", "{\"request_id\": \"" + huge + "\"}", "application/json");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 413);
  {
    v1::SubmitJobRequest request;
    request.set_request_id(huge);
    v1::SubmitJobResponse response;
    auto context = deadline_context(60);
    const auto status = server_->stub().SubmitJob(context.get(), request, &response);
    EXPECT_EQ(status.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << status.error_message();
  }
  // Out of range over gRPC.
  {
    v1::SubmitJobRequest request;
    request.mutable_scenario()->set_beats(0);
    v1::SubmitJobResponse response;
    auto context = deadline_context();
    const auto status = server_->stub().SubmitJob(context.get(), request, &response);
    EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
    EXPECT_NE(status.error_message().find("beats = 0"), std::string::npos) << status.error_message();
  }
  // Unknown job id.
  {
    auto context = deadline_context();
    v1::GetJobRequest request;
    request.set_id("j-doesnotexist");
    v1::Job job;
    EXPECT_EQ(server_->stub().GetJob(context.get(), request, &job).error_code(), grpc::StatusCode::NOT_FOUND);
    r = http.Get("/v1/jobs/j-doesnotexist");
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 404);
    r = http.Post("/v1/jobs/j-doesnotexist:cancel", "", "application/json");
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 404);
  }
  EXPECT_EQ(job_count(*server_), before);
  // Duplicate request_id: the same job, then a conflict for a different scenario.
  const std::string first = submit(*server_, {{"scene", "lumped"}, {"beats", 2}}, "dup-1");
  const std::string again = submit(*server_, {{"scene", "lumped"}, {"beats", 2}}, "dup-1");
  EXPECT_EQ(first, again);
  {
    v1::SubmitJobRequest request;
    *request.mutable_scenario() = scenario_from_json({{"scene", "lumped"}, {"beats", 3}});
    request.set_request_id("dup-1");
    v1::SubmitJobResponse response;
    auto context = deadline_context();
    EXPECT_EQ(server_->stub().SubmitJob(context.get(), request, &response).error_code(),
              grpc::StatusCode::ALREADY_EXISTS);
  }
  EXPECT_EQ(job_count(*server_), before + 1);
}

// Every rule that depends only on the scenario runs at submit (solver/config/fsei_rules.h): a
// bad fsi scenario is refused with 400 / INVALID_ARGUMENT naming both fields, and no job is
// created. A body's misspelt keys are all named, each with its path and a suggestion.
TEST_F(ServiceE2E, BadFsiScenarioAndMisspeltKeysAreRefusedAtSubmitNamingEveryOne) {
  const int64_t before = job_count(*server_);
  httplib::Client http("127.0.0.1", server_->http_port());
  const std::string loose_shells_first =
      R"({"scene": "fsi", "fsei": {"defaults": "seed", "coupling_order": "structure_first"}})";
  auto r = http.Post("/v1/jobs", "{\"scenario\": " + loose_shells_first + "}", "application/json");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 400) << r->body;
  const std::string message = nlohmann::json::parse(r->body)["message"];
  std::printf("  [message] %s\n", message.c_str());
  EXPECT_NE(message.find("fsei.coupling_order = \"structure_first\" needs fsei.strong_coupling = true"), std::string::npos)
      << message;
  {  // the same over gRPC
    v1::SubmitJobRequest request;
    *request.mutable_scenario() = scenario_from_json(nlohmann::json::parse(loose_shells_first));
    v1::SubmitJobResponse response;
    auto context = deadline_context();
    const auto status = server_->stub().SubmitJob(context.get(), request, &response);
    EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
    EXPECT_NE(status.error_message().find("needs fsei.strong_coupling = true"), std::string::npos) << status.error_message();
  }
  // Three misspelt keys, and the rule above: four problems in one answer.
  r = http.Post("/v1/jobs",
                R"({"scenario": {"scene": "fsi", "heart_rate_bmp": 70,
                                 "fsei": {"defaults": "seed", "coupling_ordr": "fluid_first",
                                          "coupling_order": "structure_first", "strong_couplng": true}}})",
                "application/json");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 400) << r->body;
  const nlohmann::json body = nlohmann::json::parse(r->body);
  EXPECT_EQ(body["code"], 3);
  const std::string all = body["message"];
  std::printf("  [message] %s\n", all.c_str());
  EXPECT_NE(all.find("(4 problems)"), std::string::npos) << all;
  EXPECT_NE(all.find("unknown field 'scenario.heart_rate_bmp'; did you mean 'heart_rate_bpm'? allowed: "), std::string::npos)
      << all;
  EXPECT_NE(all.find("unknown field 'scenario.fsei.coupling_ordr'; did you mean 'coupling_order'? allowed: "),
            std::string::npos)
      << all;
  EXPECT_NE(all.find("unknown field 'scenario.fsei.strong_couplng'; did you mean 'strong_coupling'? allowed: "),
            std::string::npos)
      << all;
  EXPECT_NE(all.find("scenario: fsei.coupling_order = \"structure_first\" needs fsei.strong_coupling = true"),
            std::string::npos)
      << all;
  EXPECT_EQ(job_count(*server_), before);
}

TEST_F(ServiceE2E, CliRunStatusListResults) {
  const std::string cli = (bin_dir() / "systole").string() + " --server " + server_->address();
  const fs::path out = dir_ / "cli-out";
  const auto [code, output] = run_command(cli + " run " + (source_dir() / "examples/healthy-0d.json").string() +
                                          " --set heart_rate_bpm=75 --out " + out.string());
  ASSERT_EQ(code, 0) << output;
  EXPECT_NE(output.find("ejection fraction"), std::string::npos) << output;
  EXPECT_NE(output.find("cardiac output"), std::string::npos) << output;
  EXPECT_TRUE(fs::exists(out / "result.h5"));
  EXPECT_TRUE(fs::exists(out / "metrics.json"));
  EXPECT_TRUE(fs::exists(out / "pv_loop.csv"));
  const auto metrics = nlohmann::json::parse(std::ifstream(out / "metrics.json"));
  EXPECT_DOUBLE_EQ(metrics["heart_rate_bpm"].get<double>(), 75.0);
  const std::string id = output.substr(output.find("submitted ") + 10, 18);
  auto [c1, status] = run_command(cli + " status " + id);
  EXPECT_EQ(c1, 0);
  EXPECT_NE(status.find("SUCCEEDED"), std::string::npos) << status;
  auto [c2, list] = run_command(cli + " list --state SUCCEEDED");
  EXPECT_EQ(c2, 0);
  EXPECT_NE(list.find(id), std::string::npos) << list;
  auto [c3, csv] = run_command(cli + " results " + id + " --csv");
  EXPECT_EQ(c3, 0);
  EXPECT_EQ(csv.rfind("time_s,", 0), 0u) << csv.substr(0, 200);
  auto [c4, bad] = run_command(cli + " submit " + (source_dir() / "examples/healthy-0d.json").string() +
                               " --set lumped.lv.emax_mmhg_per_ml=-1");
  EXPECT_EQ(c4, 2);
  EXPECT_NE(bad.find("lumped.lv.emax_mmhg_per_ml = -1 is out of range"), std::string::npos) << bad;
  auto [c5, unreachable] = run_command((bin_dir() / "systole").string() + " --server 127.0.0.1:1 list");
  EXPECT_EQ(c5, 3);
  EXPECT_NE(unreachable.find("cannot reach systole-server"), std::string::npos) << unreachable;
}

TEST_F(ServiceE2E, IdenticalScenarioReusesTheFinishedResultUnlessNoCache) {
  // Defaults written out explicitly are the same canonical scenario as defaults left out.
  const std::string first = submit(*server_, {{"scene", "lumped"}, {"heart_rate_bpm", 66}});
  ASSERT_TRUE(wait_for_state(*server_, first, v1::SUCCEEDED, std::chrono::seconds(60)));
  const std::string again = submit(*server_, {{"heart_rate_bpm", 66.0}, {"av_delay_ms", 100}});
  const v1::Job cached = get_job(*server_, again);
  EXPECT_EQ(cached.state(), v1::SUCCEEDED);
  EXPECT_EQ(cached.cached_from(), first);
  EXPECT_EQ(cached.attempts(), 0);  // never ran
  const v1::Result result = get_result(*server_, again);
  EXPECT_EQ(result.artifacts_size(), 4);  // result.h5, metrics.json, time_series.csv, pv_loop.csv
  // no_cache runs it again.
  v1::SubmitJobRequest fresh;
  *fresh.mutable_scenario() = scenario_from_json({{"heart_rate_bpm", 66}});
  fresh.set_no_cache(true);
  v1::SubmitJobResponse response;
  auto ctx = deadline_context();
  ASSERT_TRUE(server_->stub().SubmitJob(ctx.get(), fresh, &response).ok());
  EXPECT_TRUE(response.job().cached_from().empty());
  ASSERT_TRUE(wait_for_state(*server_, response.job().id(), v1::SUCCEEDED, std::chrono::seconds(60)));
  EXPECT_EQ(get_job(*server_, response.job().id()).attempts(), 1);
}

}  // namespace
}  // namespace systole::e2e
