// Fault tolerance end to end: kill -9 a worker mid-job, kill -9 the server mid-run, cancel a
// running job. Each test has its own server, SQLite file and workers.
#include <future>

#include <grpcpp/generic/generic_stub.h>

#include "tests/e2e/harness.h"

namespace systole::e2e {
namespace {

using std::chrono::milliseconds;
using std::chrono::seconds;

bool has_progress(ServerProcess& server, const std::string& id) {
  const v1::Job job = get_job(server, id);
  return job.state() == v1::RUNNING && job.has_progress() && job.progress().beat() >= 2;
}

TEST(FaultsE2E, CancelRunningJobWithinFiveSeconds) {
  const fs::path dir = make_temp_dir("cancel");
  {
    ServerProcess server(dir, 1, 2);
    const std::string id = submit(server, slow_scenario(1000));
    ASSERT_TRUE(wait_until([&] { return has_progress(server, id); }, seconds(60), milliseconds(100))) << server.log();
    const auto start = std::chrono::steady_clock::now();
    v1::CancelJobRequest request;
    request.set_id(id);
    v1::Job job;
    auto context = deadline_context();
    ASSERT_TRUE(server.stub().CancelJob(context.get(), request, &job).ok());
    EXPECT_TRUE(job.cancel_requested());
    ASSERT_TRUE(wait_for_state(server, id, v1::CANCELLED, seconds(5))) << server.log();
    const double took_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    EXPECT_LT(took_s, 5.0);
    // The worker is free again: the next job runs.
    const std::string next = submit(server, {{"scene", "lumped"}, {"beats", 2}, {"periodicity_tolerance", 0}});
    EXPECT_TRUE(wait_for_state(server, next, v1::SUCCEEDED, seconds(60))) << server.log();
    // Cancelling a finished job is refused and changes nothing.
    v1::CancelJobRequest again;
    again.set_id(next);
    auto ctx = deadline_context();
    EXPECT_EQ(server.stub().CancelJob(ctx.get(), again, &job).error_code(), grpc::StatusCode::FAILED_PRECONDITION);
    EXPECT_EQ(get_job(server, next).state(), v1::SUCCEEDED);
  }
  fs::remove_all(dir);
}

TEST(FaultsE2E, KilledWorkerJobIsRequeuedAndCompletes) {
  const fs::path dir = make_temp_dir("killworker");
  {
    ServerProcess server(dir, 1, 2, /*lease_ms=*/3000);
    const std::string id = submit(server, slow_scenario(150));
    ASSERT_TRUE(wait_until([&] { return has_progress(server, id); }, seconds(60), milliseconds(100))) << server.log();
    const auto pids = server.worker_pids();
    ASSERT_FALSE(pids.empty()) << "no worker process found";
    for (pid_t pid : pids) ::kill(pid, SIGKILL);
    // The lease expires, the job is requeued, the restarted worker runs it to the end.
    ASSERT_TRUE(wait_for_state(server, id, v1::SUCCEEDED, seconds(180))) << server.log();
    const v1::Job job = get_job(server, id);
    EXPECT_EQ(job.attempts(), 2);
    EXPECT_NE(server.log().find("lease expired"), std::string::npos);
  }
  fs::remove_all(dir);
}

TEST(FaultsE2E, KilledWorkerFsiJobResumesFromItsCheckpoint) {
  // Scene fsi checkpoints into the server's data dir (the local workers' --checkpoint-dir); a
  // worker killed after a checkpoint leaves it, and the requeued job resumes from it instead of
  // starting over (issue #9). The first 3 ms of the coarse heart, a checkpoint every 0.5 ms.
  const fs::path dir = make_temp_dir("killfsi");
  {
    ServerProcess server(dir, 1, 2, /*lease_ms=*/3000);
    const nlohmann::json scenario{{"scene", "fsi"},
                                  {"fsei", {{"end_time_ms", 3}, {"checkpoint_interval_ms", 0.5}}},
                                  {"outputs", {{"time_series_interval_ms", 0.5}}}};
    const std::string id = submit(server, scenario);
    const fs::path checkpoint = dir / "data" / "checkpoints" / id / "latest" / "state.h5";
    ASSERT_TRUE(wait_until([&] { return fs::exists(checkpoint); }, seconds(120), milliseconds(100))) << server.log();
    const auto pids = server.worker_pids();
    ASSERT_FALSE(pids.empty()) << "no worker process found";
    for (pid_t pid : pids) ::kill(pid, SIGKILL);
    ASSERT_TRUE(wait_for_state(server, id, v1::SUCCEEDED, seconds(240))) << server.log();
    EXPECT_EQ(get_job(server, id).attempts(), 2);
    const v1::Result result = get_result(server, id);
    EXPECT_GT(result.metrics().at("resumed_from_ms"), 0.0);
    EXPECT_EQ(result.metrics().at("simulated_time_ms"), 3.0);
    // a finished job's checkpoints are removed
    EXPECT_FALSE(fs::exists(dir / "data" / "checkpoints" / id));
  }
  fs::remove_all(dir);
}

TEST(FaultsE2E, KilledServerKeepsEveryJobAndResult) {
  const fs::path dir = make_temp_dir("killserver");
  std::string done_id, running_id, queued_id, done_sha;
  {
    ServerProcess server(dir, 1, 1, /*lease_ms=*/3000);
    done_id = submit(server, {{"scene", "lumped"}, {"beats", 3}, {"periodicity_tolerance", 0}});
    ASSERT_TRUE(wait_for_state(server, done_id, v1::SUCCEEDED, seconds(60))) << server.log();
    running_id = submit(server, slow_scenario(150));
    queued_id = submit(server, {{"scene", "lumped"}, {"beats", 2}, {"periodicity_tolerance", 0}});
    ASSERT_TRUE(wait_until([&] { return has_progress(server, running_id); }, seconds(60), milliseconds(100)))
        << "job " << running_id << " state " << get_job(server, running_id).state() << "\n" << server.log();
    EXPECT_EQ(get_job(server, queued_id).state(), v1::QUEUED);
    const v1::Result result = get_result(server, done_id);
    for (const auto& a : result.artifacts())
      if (a.name() == "result.h5") done_sha = a.sha256();
    ASSERT_FALSE(done_sha.empty());
    server.stop(SIGKILL);  // a crash: no shutdown code runs
    // Restart on the same database and data directory (new ports).
    server.start(1, 1, 3000);
    EXPECT_EQ(get_job(server, done_id).state(), v1::SUCCEEDED);
    const auto running_state = get_job(server, running_id).state();
    EXPECT_TRUE(running_state == v1::RUNNING || running_state == v1::QUEUED) << v1::JobState_Name(running_state);
    // The finished result is still downloadable, byte for byte.
    v1::DownloadArtifactRequest dl;
    dl.set_id(done_id);
    dl.set_name("result.h5");
    auto ctx = deadline_context();
    auto reader = server.stub().DownloadArtifact(ctx.get(), dl);
    v1::ArtifactChunk chunk;
    std::string sha;
    int64_t bytes = 0;
    while (reader->Read(&chunk)) {
      sha = chunk.sha256();
      bytes += static_cast<int64_t>(chunk.data().size());
    }
    ASSERT_TRUE(reader->Finish().ok());
    EXPECT_EQ(sha, done_sha);
    EXPECT_GT(bytes, 0);
    // The interrupted job and the queued one both finish after the restart.
    EXPECT_TRUE(wait_for_state(server, running_id, v1::SUCCEEDED, seconds(180))) << server.log();
    EXPECT_TRUE(wait_for_state(server, queued_id, v1::SUCCEEDED, seconds(60))) << server.log();
  }
  fs::remove_all(dir);
}

TEST(FaultsE2E, GracefulStopReleasesTheRunningJob) {
  const fs::path dir = make_temp_dir("sigterm");
  {
    ServerProcess server(dir, 1, 2, /*lease_ms=*/60000);
    const std::string id = submit(server, slow_scenario(1000));
    ASSERT_TRUE(wait_until([&] { return has_progress(server, id); }, seconds(60), milliseconds(100))) << server.log();
    const auto start = std::chrono::steady_clock::now();
    server.stop(SIGTERM);  // the server SIGTERMs its workers, which give the job back
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 10.0);
    server.start(/*local_workers=*/0, 1, 60000);
    const v1::Job job = get_job(server, id);
    // Released, not waiting for a 60 s lease to expire; a release is not a failed attempt.
    EXPECT_EQ(job.state(), v1::QUEUED) << server.log();
    EXPECT_EQ(job.attempts(), 0);
  }
  fs::remove_all(dir);
}

TEST(FaultsE2E, HealthServiceReportsServing) {
  const fs::path dir = make_temp_dir("health");
  {
    ServerProcess server(dir, 0, 1);
    grpc::GenericStub generic(server.channel());
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + seconds(10));
    grpc::ByteBuffer request;  // HealthCheckRequest{service: ""} encodes to zero bytes
    grpc::Slice empty("");
    request = grpc::ByteBuffer(&empty, 1);
    grpc::ByteBuffer response;
    std::promise<grpc::Status> done;
    generic.UnaryCall(&context, "/grpc.health.v1.Health/Check", grpc::StubOptions(), &request, &response,
                      [&](grpc::Status status) { done.set_value(status); });
    const grpc::Status status = done.get_future().get();
    ASSERT_TRUE(status.ok()) << status.error_message();
    std::vector<grpc::Slice> slices;
    ASSERT_TRUE(response.Dump(&slices).ok());
    std::string bytes;
    for (const auto& s : slices) bytes.append(reinterpret_cast<const char*>(s.begin()), s.size());
    EXPECT_EQ(bytes, std::string("\x08\x01"));  // HealthCheckResponse{status: SERVING}
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace systole::e2e
