// UQ campaigns end to end: real server, real MPI workers, the analytic (Ishigami) scene for
// exact answers, the 0-D scene for physiology, bad input, failing samples, cache, faults.
#include <httplib.h>

#include <cmath>

#include "systole/v1/campaign.grpc.pb.h"
#include "tests/e2e/harness.h"
#include "uq/ishigami.h"

namespace systole::e2e {
namespace {

using std::chrono::seconds;

v1::CampaignSpec spec_from_json(const nlohmann::json& j) {
  v1::CampaignSpec spec;
  const auto status = google::protobuf::util::JsonStringToMessage(j.dump(), &spec);
  if (!status.ok()) throw std::runtime_error("bad test spec: " + std::string(status.message()));
  return spec;
}

nlohmann::json ishigami_spec(int n, int seed) {
  const double pi = M_PI;
  nlohmann::json params = nlohmann::json::array();
  for (const char* x : {"analytic.x1", "analytic.x2", "analytic.x3"})
    params.push_back({{"path", x}, {"uniform", {{"min", -pi}, {"max", pi}}}});
  return {{"base_scenario", {{"scene", "analytic"}}}, {"parameters", params}, {"design", "SALTELLI"},
          {"samples", n}, {"seed", seed}, {"quantities_of_interest", {"f"}}, {"bootstrap_resamples", 1000}};
}

nlohmann::json zero_d_spec(int n, const std::string& design) {
  return {{"base_scenario", {{"scene", "lumped"}, {"outputs", {{"time_series", false}}}}},
          {"parameters",
           {{{"path", "lumped.lv.emax_mmhg_per_ml"}, {"uniform", {{"min", 2.0}, {"max", 3.5}}}},
            {{"path", "heart_rate_bpm"}, {"uniform", {{"min", 60}, {"max", 90}}}},
            {{"path", "lumped.systemic_resistance_mmhg_s_per_ml"}, {"uniform", {{"min", 0.8}, {"max", 1.3}}}}}},
          {"design", design}, {"samples", n}, {"seed", 1},
          {"quantities_of_interest", {"ejection_fraction_percent", "cardiac_output_l_min"}}};
}

class CampaignE2E : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = make_temp_dir("campaign");
    server_ = new ServerProcess(dir_, /*local_workers=*/2, /*ranks=*/1, /*lease_ms=*/3000);
  }
  static void TearDownTestSuite() {
    delete server_;
    fs::remove_all(dir_);
  }
  static std::unique_ptr<v1::Campaigns::Stub> stub() { return v1::Campaigns::NewStub(server_->channel()); }
  static grpc::Status submit(const nlohmann::json& spec, v1::SubmitCampaignResponse* out, const std::string& rid = "") {
    v1::SubmitCampaignRequest request;
    *request.mutable_spec() = spec_from_json(spec);
    request.set_request_id(rid);
    auto context = deadline_context(60);
    return stub()->SubmitCampaign(context.get(), request, out);
  }
  static v1::GetCampaignResponse get(const std::string& id) {
    v1::GetCampaignRequest request;
    request.set_id(id);
    v1::GetCampaignResponse response;
    auto context = deadline_context(60);
    const auto status = stub()->GetCampaign(context.get(), request, &response);
    if (!status.ok()) throw std::runtime_error(status.error_message());
    return response;
  }
  static v1::GetCampaignResponse wait_finished(const std::string& id, seconds timeout) {
    wait_until([&] { return get(id).campaign().finished(); }, timeout, std::chrono::milliseconds(300));
    return get(id);
  }
  static inline fs::path dir_;
  static inline ServerProcess* server_ = nullptr;
};

TEST_F(CampaignE2E, IshigamiSobolIndicesContainTheExactValues) {
  v1::SubmitCampaignResponse submitted;
  ASSERT_TRUE(submit(ishigami_spec(64, 3), &submitted).ok());
  EXPECT_EQ(submitted.campaign().jobs_total(), 64 * 5);
  const auto done = wait_finished(submitted.campaign().id(), seconds(120));
  ASSERT_TRUE(done.campaign().finished()) << server_->log();
  const auto& stats = done.statistics();
  EXPECT_EQ(stats.samples_succeeded(), 320);
  EXPECT_EQ(stats.sobol_rows_used(), 64);
  ASSERT_EQ(stats.qoi_size(), 1);
  const auto exact = uq::ishigami_exact();
  for (int i = 0; i < 3; ++i) {
    const auto& s = stats.qoi(0).sensitivities(i);
    EXPECT_LE(s.sobol_first().low(), exact.first_order[i]) << s.path();
    EXPECT_GE(s.sobol_first().high(), exact.first_order[i]) << s.path();
    EXPECT_LE(s.sobol_total().low(), exact.total[i]) << s.path();
    EXPECT_GE(s.sobol_total().high(), exact.total[i]) << s.path();
  }
  EXPECT_NEAR(stats.qoi(0).mean(), exact.mean, 4 * std::sqrt(exact.variance / 128));
}

TEST_F(CampaignE2E, ZeroDStatisticsMakePhysiologicalSense) {
  v1::SubmitCampaignResponse submitted;
  ASSERT_TRUE(submit(zero_d_spec(60, "LATIN_HYPERCUBE"), &submitted).ok());
  const auto done = wait_finished(submitted.campaign().id(), seconds(120));
  ASSERT_TRUE(done.campaign().finished());
  const auto& stats = done.statistics();
  EXPECT_EQ(stats.samples_succeeded(), 60);
  ASSERT_EQ(stats.qoi_size(), 2);
  // EF is set by contractility (Emax) against afterload: the largest |rank correlation| is
  // Emax's, positive; a higher heart rate shortens filling and lowers EF.
  const auto& ef = stats.qoi(0);
  EXPECT_EQ(ef.name(), "ejection_fraction_percent");
  EXPECT_GT(ef.sensitivities(0).spearman(), 0.4);
  EXPECT_GT(std::abs(ef.sensitivities(0).spearman()), std::abs(ef.sensitivities(2).spearman()));
  EXPECT_LT(ef.sensitivities(1).spearman(), 0);
  // CO = SV x HR: the resistance lowers it, the heart rate raises it.
  const auto& co = stats.qoi(1);
  EXPECT_LT(co.sensitivities(2).spearman(), -0.4);
  EXPECT_GT(co.sensitivities(1).spearman(), 0);
  EXPECT_GT(ef.mean(), 45);
  EXPECT_LT(ef.mean(), 70);
  EXPECT_LE(ef.percentiles().p5(), ef.percentiles().p50());
  EXPECT_LE(ef.percentiles().p50(), ef.percentiles().p95());
}

TEST_F(CampaignE2E, BadInputNamesTheOffenderAndStoresNothing) {
  v1::ListCampaignsRequest list;
  v1::ListCampaignsResponse before;
  auto ctx = deadline_context();
  ASSERT_TRUE(stub()->ListCampaigns(ctx.get(), list, &before).ok());
  auto expect_invalid = [&](nlohmann::json spec, const std::string& needle) {
    v1::SubmitCampaignResponse out;
    const auto status = submit(spec, &out);
    EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << needle;
    EXPECT_NE(status.error_message().find(needle), std::string::npos) << status.error_message();
  };
  auto spec = zero_d_spec(10, "MONTE_CARLO");
  spec["parameters"][0]["path"] = "lumped.lv.emax";
  expect_invalid(spec, "parameters[0].path 'lumped.lv.emax' is not a scenario field; did you mean "
                       "'lumped.lv.emax_mmhg_per_ml'?");
  spec = zero_d_spec(10, "MONTE_CARLO");
  spec["parameters"][1] = {{"path", "heart_rate_bpm"}, {"normal", {{"mean", 70}, {"std", 10}}}};
  expect_invalid(spec, "outside the allowed range [20, 240] of heart_rate_bpm");
  spec = zero_d_spec(0, "MONTE_CARLO");
  expect_invalid(spec, "samples = 0 is out of range");
  spec = zero_d_spec(10, "MONTE_CARLO");
  spec["quantities_of_interest"] = {"ef"};
  expect_invalid(spec, "quantities_of_interest[0] 'ef' is not a metric of scene 'lumped'");
  spec["quantities_of_interest"] = {"ejection_fraction"};
  expect_invalid(spec, "'ejection_fraction' is not a metric of scene 'lumped'; did you mean 'ejection_fraction_percent'?");
  // The base scenario's problems come with the spec's own, each named.
  spec = zero_d_spec(0, "MONTE_CARLO");
  spec["base_scenario"]["beats"] = 0;
  expect_invalid(spec, "base_scenario: beats = 0 is out of range");
  expect_invalid(spec, "samples = 0 is out of range");
  // REST: every unknown key of the spec named with a suggestion, with the spec's other problems.
  {
    httplib::Client http("127.0.0.1", server_->http_port());
    nlohmann::json body = {{"spec", zero_d_spec(0, "MONTE_CARLO")}};
    body["spec"]["parameters"][1]["unifrom"] = body["spec"]["parameters"][1]["uniform"];
    body["spec"]["parameters"][1].erase("uniform");
    body["spec"]["base_scenario"]["heart_rate_bmp"] = 70;
    auto r = http.Post("/v1/campaigns", body.dump(), "application/json");
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 400) << r->body;
    const std::string message = nlohmann::json::parse(r->body)["message"];
    for (const char* part : {"unknown field 'spec.parameters[1].unifrom'; did you mean 'uniform'?",
                             "unknown field 'spec.base_scenario.heart_rate_bmp'; did you mean 'heart_rate_bpm'?",
                             "spec: parameters[1] (heart_rate_bpm): no distribution", "spec: samples = 0 is out of range"})
      EXPECT_NE(message.find(part), std::string::npos) << part << " in " << message;
  }
  spec = zero_d_spec(10, "MONTE_CARLO");
  spec["parameters"][2] = {{"path", "outputs.metrics"}, {"uniform", {{"min", 0}, {"max", 1}}}};
  expect_invalid(spec, "only real-valued fields can be uncertain");
  v1::ListCampaignsResponse after;
  auto ctx2 = deadline_context();
  ASSERT_TRUE(stub()->ListCampaigns(ctx2.get(), list, &after).ok());
  EXPECT_EQ(after.campaigns_size(), before.campaigns_size());
}

TEST_F(CampaignE2E, FailingSamplesAreReportedNotFatalAndCanBeRetried) {
  // Emin above the default Emax 2.7 breaks "emax must exceed emin": those draws fail.
  nlohmann::json spec = {{"base_scenario", {{"scene", "lumped"}, {"outputs", {{"time_series", false}}}}},
                         {"parameters", {{{"path", "lumped.lv.emin_mmhg_per_ml"}, {"uniform", {{"min", 0.05}, {"max", 5}}}}}},
                         {"design", "LATIN_HYPERCUBE"}, {"samples", 20}, {"seed", 5},
                         {"quantities_of_interest", {"edv_ml"}}};
  v1::SubmitCampaignResponse submitted;
  ASSERT_TRUE(submit(spec, &submitted).ok());
  const auto done = wait_finished(submitted.campaign().id(), seconds(120));
  ASSERT_TRUE(done.campaign().finished());
  const auto& stats = done.statistics();
  EXPECT_GT(stats.samples_failed(), 0);
  EXPECT_GT(stats.samples_succeeded(), 0);
  EXPECT_EQ(stats.samples_failed() + stats.samples_succeeded(), 20);
  EXPECT_EQ(stats.failed_size(), stats.samples_failed());
  EXPECT_NE(stats.failed(0).error().find("must exceed lumped.lv.emin_mmhg_per_ml"), std::string::npos)
      << stats.failed(0).error();
  EXPECT_EQ(stats.qoi(0).samples_used(), stats.samples_succeeded());
  // Retry puts the failed ones back in the queue (they fail again, deterministically).
  v1::RetryFailedRequest retry;
  retry.set_id(submitted.campaign().id());
  v1::Campaign campaign;
  auto ctx = deadline_context();
  ASSERT_TRUE(stub()->RetryFailed(ctx.get(), retry, &campaign).ok());
  EXPECT_FALSE(campaign.finished());
  const auto again = wait_finished(submitted.campaign().id(), seconds(120));
  EXPECT_EQ(again.statistics().samples_failed(), stats.samples_failed());
}

TEST_F(CampaignE2E, RepeatedCampaignIsServedFromTheCache) {
  v1::SubmitCampaignResponse first;
  ASSERT_TRUE(submit(zero_d_spec(12, "SOBOL"), &first, "cache-a").ok());
  ASSERT_TRUE(wait_finished(first.campaign().id(), seconds(120)).campaign().finished());
  // Same request_id: the same campaign.
  v1::SubmitCampaignResponse same;
  ASSERT_TRUE(submit(zero_d_spec(12, "SOBOL"), &same, "cache-a").ok());
  EXPECT_FALSE(same.created());
  EXPECT_EQ(same.campaign().id(), first.campaign().id());
  // A new campaign with the same samples: every job reuses a finished result.
  v1::SubmitCampaignResponse second;
  ASSERT_TRUE(submit(zero_d_spec(12, "SOBOL"), &second, "cache-b").ok());
  EXPECT_TRUE(second.created());
  EXPECT_EQ(second.campaign().jobs_cached(), 12);
  EXPECT_TRUE(second.campaign().finished());
  const auto stats = get(second.campaign().id()).statistics();
  const auto stats_first = get(first.campaign().id()).statistics();
  EXPECT_DOUBLE_EQ(stats.qoi(0).mean(), stats_first.qoi(0).mean());
}

TEST(CampaignFaultsE2E, KilledWorkerAndServerLoseNoSample) {
  const fs::path dir = make_temp_dir("campaign-faults");
  {
    ServerProcess server(dir, 2, 1, /*lease_ms=*/3000);
    auto stub = v1::Campaigns::NewStub(server.channel());
    // Slow samples (a fine 0-D step) so that the kills land mid-campaign.
    nlohmann::json spec = zero_d_spec(16, "LATIN_HYPERCUBE");
    spec["base_scenario"]["lumped"] = {{"time_step_ms", 0.02}};
    spec["base_scenario"]["beats"] = 4;
    spec["base_scenario"]["periodicity_tolerance"] = 0;
    v1::SubmitCampaignRequest request;
    *request.mutable_spec() = spec_from_json(spec);
    v1::SubmitCampaignResponse submitted;
    auto ctx = deadline_context();
    ASSERT_TRUE(stub->SubmitCampaign(ctx.get(), request, &submitted).ok());
    const std::string id = submitted.campaign().id();
    auto state_count = [&](const char* state) {
      v1::GetCampaignRequest get;
      get.set_id(id);
      v1::GetCampaignResponse response;
      auto c = deadline_context();
      if (!stub->GetCampaign(c.get(), get, &response).ok()) return -1;
      const auto& m = response.campaign().jobs_by_state();
      return m.count(state) ? m.at(state) : 0;
    };
    ASSERT_TRUE(wait_until([&] { return state_count("SUCCEEDED") >= 2; }, seconds(120)));
    for (pid_t pid : server.worker_pids()) ::kill(pid, SIGKILL);
    ASSERT_TRUE(wait_until([&] { return state_count("SUCCEEDED") >= 6; }, seconds(120))) << server.log();
    server.stop(SIGKILL);
    server.start(2, 1, 3000);
    stub = v1::Campaigns::NewStub(server.channel());
    ASSERT_TRUE(wait_until([&] { return state_count("SUCCEEDED") == 16; }, seconds(240))) << server.log();
    v1::GetCampaignSamplesRequest samples_request;
    samples_request.set_id(id);
    v1::GetCampaignSamplesResponse samples;
    auto c = deadline_context();
    ASSERT_TRUE(stub->GetCampaignSamples(c.get(), samples_request, &samples).ok());
    ASSERT_EQ(samples.samples_size(), 16);
    std::set<std::string> jobs;
    for (const auto& s : samples.samples()) {
      EXPECT_EQ(s.state(), v1::SUCCEEDED);
      EXPECT_EQ(s.outputs().size(), 2u);
      jobs.insert(s.job_id());
      // Exactly one SUCCEEDED transition per job: no sample completed twice.
      v1::WatchJobRequest watch;
      watch.set_id(s.job_id());
      auto wctx = deadline_context();
      auto reader = server.stub().WatchJob(wctx.get(), watch);
      v1::JobEvent e;
      int succeeded = 0;
      while (reader->Read(&e))
        if (e.kind() == "state" && e.state() == v1::SUCCEEDED) ++succeeded;
      EXPECT_TRUE(reader->Finish().ok());
      EXPECT_EQ(succeeded, 1) << s.job_id();
    }
    EXPECT_EQ(jobs.size(), 16u);
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace systole::e2e
