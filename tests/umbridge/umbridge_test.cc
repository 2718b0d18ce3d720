// The UM-Bridge gateway over a real JobStore (temp dir) and JobService, on an ephemeral port.
// The test plays the worker itself: it leases each job through JobService::lease and completes
// it with fake metrics computed from the inputs -- or, for sentinel heart rates, fails it,
// holds it, cancels it or reports a non-finite metric -- so every endpoint and every error type
// is exercised without MPI or the solver.
#include <gtest/gtest.h>
#include <httplib.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <random>
#include <thread>

#include "proto/bridge/scenario_bridge.h"
#include "service/server/job_service.h"
#include "service/server/umbridge_gateway.h"
#include "solver/config/parameter_table.h"

namespace systole::service {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// Sentinel heart rates (bpm) that make the fake worker misbehave.
constexpr double kFailFinal = 201;      // FailJob, not retryable (an unstable point)
constexpr double kFailRetryable = 202;  // FailJob, retryable, every attempt
constexpr double kHold = 203;           // never finishes
constexpr double kNaN = 204;            // completes with EF = NaN
constexpr double kCancel = 205;         // cancelled while RUNNING

double field(config::Scenario& s, const char* path) { return config::find_parameter(path)->real(s); }

// The fake model: what the worker reports for a scenario.
std::map<std::string, double> fake_metrics(double emax, double hr, double r) {
  return {{"ejection_fraction_percent", 20 * emax + 0.1 * hr},
          {"cardiac_output_l_min", hr * emax / (100 * r)},
          {"stroke_volume_ml", 70 + emax},
          {"heart_rate_bpm", hr}};
}

class FakeWorker {
 public:
  explicit FakeWorker(JobService& jobs) : jobs_(jobs), thread_([this] { loop(); }) {}
  ~FakeWorker() {
    stop_ = true;
    thread_.join();
  }
  void pause(bool paused) { paused_ = paused; }
  // Runs (leases) per heart rate.
  int runs(double hr) {
    std::lock_guard lock(mu_);
    return runs_[hr];
  }

 private:
  void loop() {
    while (!stop_) {
      if (paused_) {
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
        continue;
      }
      v1::LeaseJobRequest request;
      request.set_worker_id("fake");
      const auto lease = jobs_.lease(request, std::chrono::milliseconds(100));
      if (!lease.has_job()) continue;
      config::Scenario s = bridge::validate(lease.scenario());
      const double emax = field(s, "lumped.lv.emax_mmhg_per_ml");
      const double hr = field(s, "heart_rate_bpm");
      const double r = field(s, "lumped.systemic_resistance_mmhg_s_per_ml");
      {
        std::lock_guard lock(mu_);
        ++runs_[hr];
      }
      if (hr == kHold) continue;
      if (hr == kFailFinal || hr == kFailRetryable) {
        v1::FailJobRequest fail;
        fail.set_worker_id("fake");
        fail.set_job_id(lease.job_id());
        fail.set_error(hr == kFailFinal ? "lumped: LV volume became negative at t = 0.3 s" : "MPI rank lost");
        fail.set_retryable(hr == kFailRetryable);
        jobs_.fail(fail);
        continue;
      }
      if (hr == kCancel) {
        jobs_.cancel(lease.job_id());
        v1::ReleaseJobRequest release;
        release.set_worker_id("fake");
        release.set_job_id(lease.job_id());
        release.set_cancelled(true);
        jobs_.release(release);
        continue;
      }
      v1::CompleteJobRequest complete;
      complete.set_worker_id("fake");
      complete.set_job_id(lease.job_id());
      for (const auto& [name, value] : fake_metrics(emax, hr, r))
        (*complete.mutable_result()->mutable_metrics())[name] = value;
      if (hr == kNaN) (*complete.mutable_result()->mutable_metrics())["ejection_fraction_percent"] = std::nan("");
      jobs_.complete(complete);
    }
  }

  JobService& jobs_;
  std::atomic<bool> stop_{false};
  std::atomic<bool> paused_{false};
  std::mutex mu_;
  std::map<double, int> runs_;
  std::thread thread_;
};

struct Reply {
  int status = 0;
  json body;
  std::string job_id;
  std::string cached_from;
  std::string error_type() const { return body.contains("error") ? body["error"].value("type", "") : ""; }
  std::string error_message() const { return body.contains("error") ? body["error"].value("message", "") : ""; }
};

class UmBridgeTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("systole-umbridge-test-" + std::to_string(std::random_device{}()));
    fs::create_directories(dir_);
    store_ = std::make_unique<store::JobStore>((dir_ / "jobs.db").string());
    jobs_ = std::make_unique<JobService>(*store_, notifier_, ServiceOptions{dir_ / "data", 15000, 3});
    worker_ = std::make_unique<FakeWorker>(*jobs_);
    start(json::object());
  }
  void TearDown() override {
    gateway_.reset();
    worker_.reset();
    jobs_.reset();
    store_.reset();
    std::error_code ignored;
    fs::remove_all(dir_, ignored);
  }
  void start(const json& preset, MetricCatalog catalog = {}) {
    gateway_.reset();
    gateway_ = std::make_unique<UmBridgeGateway>(*jobs_, notifier_, "127.0.0.1", 0, preset, std::chrono::seconds(20),
                                                 std::move(catalog));
    port_ = gateway_->port();
  }

  Reply call(const std::string& method, const std::string& path, const std::string& body = "") {
    httplib::Client client("127.0.0.1", port_);
    client.set_read_timeout(std::chrono::seconds(60));
    const auto result =
        method == "GET" ? client.Get(path.c_str()) : client.Post(path.c_str(), body, "application/json");
    Reply reply;
    if (!result) {
      ADD_FAILURE() << method << " " << path << ": no HTTP response";
      return reply;
    }
    reply.status = result->status;
    reply.body = json::parse(result->body, nullptr, false);
    EXPECT_FALSE(reply.body.is_discarded()) << "not JSON: " << result->body;
    EXPECT_EQ(result->get_header_value("Content-Type"), "application/json");
    reply.job_id = result->get_header_value("X-Systole-Job-Id");
    reply.cached_from = result->get_header_value("X-Systole-Cached-From");
    return reply;
  }
  Reply post(const std::string& path, const json& body) { return call("POST", path, body.dump()); }
  Reply evaluate(const std::vector<double>& x, const json& config = json::object()) {
    return post("/Evaluate", {{"name", "forward"}, {"input", json::array({x})}, {"config", config}});
  }
  static void expect_error(const Reply& r, int status, const std::string& type, const std::string& needle) {
    EXPECT_EQ(r.status, status) << r.body.dump();
    EXPECT_EQ(r.error_type(), type) << r.body.dump();
    EXPECT_NE(r.error_message().find(needle), std::string::npos)
        << "message '" << r.error_message() << "' lacks '" << needle << "'";
    EXPECT_FALSE(r.body.contains("output"));
  }

  fs::path dir_;
  std::unique_ptr<store::JobStore> store_;
  ChangeNotifier notifier_;
  std::unique_ptr<JobService> jobs_;
  std::unique_ptr<FakeWorker> worker_;
  std::unique_ptr<UmBridgeGateway> gateway_;
  int port_ = 0;
};

TEST_F(UmBridgeTest, InfoAndModelInfo) {
  const Reply info = call("GET", "/Info");
  EXPECT_EQ(info.status, 200);
  EXPECT_EQ(info.body, (json{{"protocolVersion", 1.0}, {"models", {"forward"}}}));
  const Reply model = post("/ModelInfo", {{"name", "forward"}});
  EXPECT_EQ(model.status, 200);
  EXPECT_EQ(model.body["support"],
            (json{{"Evaluate", true}, {"Gradient", false}, {"ApplyJacobian", false}, {"ApplyHessian", false}}));
  expect_error(post("/ModelInfo", {{"name", "backward"}}), 400, "ModelNotFound", "backward");
  expect_error(post("/ModelInfo", json::object()), 400, "InvalidInput", "name");
}

TEST_F(UmBridgeTest, SizesFollowTheConfig) {
  EXPECT_EQ(post("/InputSizes", {{"name", "forward"}, {"config", json::object()}}).body, (json{{"inputSizes", {3}}}));
  EXPECT_EQ(post("/OutputSizes", {{"name", "forward"}}).body, (json{{"outputSizes", {2}}}));
  const json config{{"inputs", {"heart_rate_bpm"}}, {"outputs", {"stroke_volume_ml", "edv_ml", "esv_ml", "edv_ml2"}}};
  EXPECT_EQ(post("/InputSizes", {{"name", "forward"}, {"config", config}}).body["inputSizes"], json::array({1}));
  EXPECT_EQ(post("/OutputSizes", {{"name", "forward"}, {"config", config}}).body["outputSizes"], json::array({4}));
  expect_error(post("/InputSizes", {{"name", "inverse"}}), 400, "ModelNotFound", "inverse");
  expect_error(post("/OutputSizes", {{"name", "inverse"}}), 400, "ModelNotFound", "inverse");
  expect_error(post("/InputSizes", {{"name", "forward"}, {"config", {{"inputs", {"lumped.lv.emax"}}}}}), 400,
               "InvalidInput", "lumped.lv.emax");
}

TEST_F(UmBridgeTest, EvaluateRunsAJobThroughTheQueueAndReturnsTheMetrics) {
  const Reply r = evaluate({2.7, 70, 1.05});
  ASSERT_EQ(r.status, 200) << r.body.dump();
  const auto expected = fake_metrics(2.7, 70, 1.05);
  ASSERT_EQ(r.body["output"].size(), 1u);
  ASSERT_EQ(r.body["output"][0].size(), 2u);
  EXPECT_DOUBLE_EQ(r.body["output"][0][0].get<double>(), expected.at("ejection_fraction_percent"));
  EXPECT_DOUBLE_EQ(r.body["output"][0][1].get<double>(), expected.at("cardiac_output_l_min"));
  ASSERT_FALSE(r.job_id.empty());
  const v1::Job job = jobs_->get(r.job_id);
  EXPECT_EQ(job.state(), v1::SUCCEEDED);
  EXPECT_EQ(job.scenario().heart_rate_bpm(), 70);
  EXPECT_EQ(job.scenario().lumped().lv().emax_mmhg_per_ml(), 2.7);
  EXPECT_EQ(job.scenario().lumped().systemic_resistance_mmhg_s_per_ml(), 1.05);
  EXPECT_EQ(job.scene(), "lumped");
  EXPECT_EQ(worker_->runs(70), 1);

  // Custom mapping, order as configured; integers are numbers too.
  const json config{{"inputs", {"heart_rate_bpm", "lumped.lv.emax_mmhg_per_ml"}},
                    {"outputs", {"stroke_volume_ml", "heart_rate_bpm", "ejection_fraction_percent"}},
                    {"priority", 5}};
  const Reply custom = evaluate({80, 3}, config);
  ASSERT_EQ(custom.status, 200) << custom.body.dump();
  const auto m = fake_metrics(3, 80, 1.05);  // resistance: the scene default
  EXPECT_EQ(custom.body["output"][0],
            json::array({m.at("stroke_volume_ml"), m.at("heart_rate_bpm"), m.at("ejection_fraction_percent")}));
  EXPECT_EQ(jobs_->get(custom.job_id).priority(), 5);
}

TEST_F(UmBridgeTest, IdenticalEvaluationsShareOneRunAndEquivalentOnesHitTheResultCache) {
  worker_->pause(true);
  std::vector<Reply> replies(4);
  std::vector<std::thread> clients;
  for (auto& reply : replies) clients.emplace_back([&] { reply = evaluate({2.5, 99, 1.1}); });
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  worker_->pause(false);
  for (auto& t : clients) t.join();
  for (const auto& reply : replies) {
    ASSERT_EQ(reply.status, 200) << reply.body.dump();
    EXPECT_EQ(reply.body, replies[0].body);
    EXPECT_EQ(reply.job_id, replies[0].job_id);
  }
  EXPECT_EQ(worker_->runs(99), 1);

  // Again later: the same job, no new run.
  const Reply again = evaluate({2.5, 99, 1.1});
  EXPECT_EQ(again.job_id, replies[0].job_id);
  EXPECT_EQ(worker_->runs(99), 1);

  // A different scenario text with the same canonical scenario (a default spelled out): a new
  // job, served from the result cache, and it says so.
  const double av_delay = config::find_parameter("av_delay_ms")->default_number;
  const Reply cached = evaluate({2.5, 99, 1.1}, {{"base_scenario", {{"scene", "lumped"}, {"av_delay_ms", av_delay}}}});
  ASSERT_EQ(cached.status, 200) << cached.body.dump();
  EXPECT_NE(cached.job_id, replies[0].job_id);
  EXPECT_EQ(cached.cached_from, replies[0].job_id);
  EXPECT_EQ(cached.body, replies[0].body);
  EXPECT_EQ(worker_->runs(99), 1);
}

TEST_F(UmBridgeTest, PresetIsTheDefaultAndTheRequestOverridesIt) {
  start({{"inputs", {"heart_rate_bpm"}},
         {"outputs", {"stroke_volume_ml"}},
         {"base_scenario", {{"scene", "lumped"}, {"lumped", {{"lv", {{"emax_mmhg_per_ml", 4.0}}}}}}}});
  EXPECT_EQ(post("/InputSizes", {{"name", "forward"}}).body["inputSizes"], json::array({1}));
  const Reply r = evaluate({60});
  ASSERT_EQ(r.status, 200) << r.body.dump();
  EXPECT_DOUBLE_EQ(r.body["output"][0][0].get<double>(), fake_metrics(4.0, 60, 1.05).at("stroke_volume_ml"));
  const Reply o = evaluate({60}, {{"outputs", {"heart_rate_bpm", "stroke_volume_ml"}}});
  ASSERT_EQ(o.status, 200) << o.body.dump();
  EXPECT_EQ(o.body["output"][0], json::array({60.0, 74.0}));

  EXPECT_THROW(
      UmBridgeGateway(*jobs_, notifier_, "127.0.0.1", 0, {{"inputs", {"tissue.lv.nope"}}}, std::chrono::seconds(1)),
      std::invalid_argument);
  EXPECT_THROW(UmBridgeGateway(*jobs_, notifier_, "127.0.0.1", 0, {{"colour", "red"}}, std::chrono::seconds(1)),
               std::invalid_argument);
  EXPECT_THROW(UmBridgeGateway(*jobs_, notifier_, "127.0.0.1", 0, json::array(), std::chrono::seconds(1)),
               std::invalid_argument);
}

TEST_F(UmBridgeTest, ModelNotFoundAndUnsupportedFeatures) {
  expect_error(post("/Evaluate", {{"name", "backward"}, {"input", {{1, 2, 3}}}}), 400, "ModelNotFound", "backward");
  for (const char* feature : {"/Gradient", "/ApplyJacobian", "/ApplyHessian"}) {
    expect_error(post(feature, {{"name", "forward"},
                                {"inWrt", 0},
                                {"outWrt", 0},
                                {"input", {{1, 2, 3}}},
                                {"sens", {1, 1}},
                                {"vec", {1, 1, 1}}}),
                 400, "UnsupportedFeature", std::string(feature).substr(1));
    expect_error(post(feature, {{"name", "backward"}}), 400, "ModelNotFound", "backward");
  }
  expect_error(call("POST", "/EvaluateShMem", "{}"), 404, "UnsupportedFeature", "/EvaluateShMem");
  expect_error(call("GET", "/Evaluate"), 404, "UnsupportedFeature", "GET /Evaluate");
}

TEST_F(UmBridgeTest, InvalidInputNamesTheOffender) {
  expect_error(call("POST", "/Evaluate", "{not json"), 400, "InvalidInput", "not valid JSON");
  expect_error(call("POST", "/Evaluate", "[1]"), 400, "InvalidInput", "JSON object");
  expect_error(post("/Evaluate", {{"name", "forward"}}), 400, "InvalidInput", "\"input\" is required");
  expect_error(post("/Evaluate", {{"name", "forward"}, {"input", {1, 2, 3}}}), 400, "InvalidInput", "array of arrays");
  expect_error(post("/Evaluate", {{"name", "forward"}, {"input", {{1, 2, 3}, {4}}}}), 400, "InvalidInput", "2 vectors");
  expect_error(evaluate({2.7, 70}), 400, "InvalidInput", "length 2, expected 3");
  expect_error(post("/Evaluate", {{"name", "forward"}, {"input", {{2.7, "fast", 1}}}}), 400, "InvalidInput",
               "heart_rate_bpm");
  expect_error(evaluate({1}, {{"inputs", {"lumped.lv.emaxx_mmhg_per_ml"}}}), 400, "InvalidInput",
               "unknown scenario field 'lumped.lv.emaxx_mmhg_per_ml'");
  expect_error(evaluate({1}, {{"inputs", {"beats"}}}), 400, "InvalidInput", "'beats' is not real-valued");
  expect_error(evaluate({1, 2}, {{"inputs", {"heart_rate_bpm", "heart_rate_bpm"}}}), 400, "InvalidInput",
               "listed twice");
  expect_error(evaluate({1, 2, 3}, {{"outputs", json::array()}}), 400, "InvalidInput", "config.outputs");
  expect_error(evaluate({1, 2, 3}, {{"colour", "red"}}), 400, "InvalidInput", "unknown config key 'colour'");
  expect_error(evaluate({1, 2, 3}, {{"priority", 5000}}), 400, "InvalidInput", "config.priority");
  expect_error(evaluate({1, 2, 3}, {{"timeout_s", -1}}), 400, "InvalidInput", "config.timeout_s");
  expect_error(evaluate({1, 2, 3}, {{"base_scenario", {{"scene", "lumped"}, {"heart_rate", 70}}}}), 400, "InvalidInput",
               "heart_rate");
  expect_error(evaluate({1, 2, 3}, "lumped"), 400, "InvalidInput", "\"config\" must be a JSON object");
  // Out of the field's range: rejected before anything is queued, naming the field.
  expect_error(evaluate({1000, 70, 1.05}), 400, "InvalidInput", "lumped.lv.emax_mmhg_per_ml");
  expect_error(evaluate({2.7, 10, 1.05}), 400, "InvalidInput", "heart_rate_bpm");
  EXPECT_EQ(store_->count(std::nullopt), 0);

  // An output the scene does not report: found when the job ends, naming it and the known ones.
  const Reply r = evaluate({2.7, 70, 1.05}, {{"outputs", {"ejection_fraction_percent", "qrs_width_ms"}}});
  expect_error(r, 400, "InvalidInput", "output 'qrs_width_ms' is not a metric of scene 'lumped'");
  EXPECT_NE(r.error_message().find("stroke_volume_ml"), std::string::npos);
}

TEST_F(UmBridgeTest, AMetricCatalogRejectsUnknownOutputsBeforeRunning) {
  start(json::object(), [](const std::string& scene) {
    return scene == "lumped" ? std::vector<std::string>{"ejection_fraction_percent", "cardiac_output_l_min"}
                             : std::vector<std::string>{};
  });
  expect_error(post("/OutputSizes", {{"name", "forward"}, {"config", {{"outputs", {"qrs_width_ms"}}}}}), 400,
               "InvalidInput", "'qrs_width_ms' is not a metric of scene 'lumped'");
  expect_error(evaluate({2.7, 70, 1.05}, {{"outputs", {"qrs_width_ms"}}}), 400, "InvalidInput", "qrs_width_ms");
  EXPECT_EQ(store_->count(std::nullopt), 0);
  EXPECT_EQ(evaluate({2.7, 70, 1.05}).status, 200);
}

TEST_F(UmBridgeTest, AFinalFailureIsInvalidInputAndIsNotRunAgain) {
  const Reply r = evaluate({2.7, kFailFinal, 1.05});
  expect_error(r, 400, "InvalidInput", "LV volume became negative");
  EXPECT_NE(r.error_message().find(r.job_id), std::string::npos);
  EXPECT_EQ(jobs_->get(r.job_id).state(), v1::FAILED);
  const Reply again = evaluate({2.7, kFailFinal, 1.05});
  expect_error(again, 400, "InvalidInput", "LV volume became negative");
  EXPECT_EQ(again.job_id, r.job_id);
  EXPECT_EQ(worker_->runs(kFailFinal), 1);
}

TEST_F(UmBridgeTest, TransientFailuresAndCancellationAreModelErrorsAndGetAFreshJob) {
  const Reply r = evaluate({2.7, kFailRetryable, 1.05});
  expect_error(r, 500, "ModelError", "after 3 attempt(s): MPI rank lost");
  EXPECT_EQ(worker_->runs(kFailRetryable), 3);
  const Reply again = evaluate({2.7, kFailRetryable, 1.05});
  expect_error(again, 500, "ModelError", "MPI rank lost");
  EXPECT_NE(again.job_id, r.job_id);  // a new job, not the exhausted one
  EXPECT_EQ(worker_->runs(kFailRetryable), 6);

  const Reply c = evaluate({2.7, kCancel, 1.05});
  expect_error(c, 500, "ModelError", "CANCELLED");
  EXPECT_EQ(jobs_->get(c.job_id).state(), v1::CANCELLED);
  const Reply c2 = evaluate({2.7, kCancel, 1.05});
  EXPECT_NE(c2.job_id, c.job_id);
}

TEST_F(UmBridgeTest, ANonFiniteMetricIsInvalidOutput) {
  expect_error(evaluate({2.7, kNaN, 1.05}), 500, "InvalidOutput", "ejection_fraction_percent");
}

TEST_F(UmBridgeTest, TimeoutNamesTheJobAndARepeatWaitsForTheSameJob) {
  const auto start = std::chrono::steady_clock::now();
  const Reply r = evaluate({2.7, kHold, 1.05}, {{"timeout_s", 0.3}});
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(5));
  expect_error(r, 504, "Timeout", "job " + r.job_id + " did not finish within 0.3 s");
  EXPECT_FALSE(r.job_id.empty());
  EXPECT_EQ(jobs_->get(r.job_id).state(), v1::RUNNING);
  const Reply again = evaluate({2.7, kHold, 1.05}, {{"timeout_s", 0.2}});
  expect_error(again, 504, "Timeout", r.job_id);
  EXPECT_EQ(again.job_id, r.job_id);
  EXPECT_EQ(worker_->runs(kHold), 1);
}

TEST_F(UmBridgeTest, ShutdownAnswersWaitingEvaluates) {
  Reply reply;
  std::thread client([&] { reply = evaluate({2.7, kHold, 1.05}); });
  std::this_thread::sleep_for(std::chrono::milliseconds(400));
  const auto start = std::chrono::steady_clock::now();
  gateway_.reset();
  client.join();
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(5));
  expect_error(reply, 503, "ModelError", "shutting down");
}

}  // namespace
}  // namespace systole::service
