// Unit tests of the SQLite job store (service/store). Every test gets a fresh database file in
// its own directory under temp_directory_path(), removed afterwards. Time is injected: tests
// pass now_ms explicitly and never sleep.
#include "service/store/job_store.h"

#include <gtest/gtest.h>
#include <sqlite3.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <csignal>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

namespace systole::store {
namespace {

namespace fs = std::filesystem;
using Code = StoreError::Code;
using nlohmann::json;

constexpr int64_t kT0 = 1'700'000'000'000;  // a plausible "now" in ms
constexpr int64_t kLease = 30'000;

const char* code_name(Code code) {
  switch (code) {
    case Code::kNotFound:
      return "kNotFound";
    case Code::kFailedPrecondition:
      return "kFailedPrecondition";
    case Code::kAlreadyExists:
      return "kAlreadyExists";
    case Code::kInvalidArgument:
      return "kInvalidArgument";
    case Code::kInternal:
      return "kInternal";
  }
  return "?";
}

// Runs fn and checks that it throws a StoreError with `code` whose message contains every one
// of `fragments`.
void expect_error(const std::function<void()>& fn, Code code,
                  const std::vector<std::string>& fragments = {}) {
  try {
    fn();
  } catch (const StoreError& e) {
    EXPECT_EQ(code_name(e.code()), std::string(code_name(code))) << e.what();
    for (const std::string& fragment : fragments) {
      EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos)
          << "message '" << e.what() << "' lacks '" << fragment << "'";
    }
    return;
  } catch (const std::exception& e) {
    ADD_FAILURE() << "expected StoreError(" << code_name(code) << "), got " << e.what();
    return;
  }
  ADD_FAILURE() << "expected StoreError(" << code_name(code) << "), nothing was thrown";
}

// Raw SQLite access to the same file, for what the API deliberately does not expose.
class RawDb {
 public:
  explicit RawDb(const fs::path& path) {
    if (sqlite3_open(path.c_str(), &db_) != SQLITE_OK) {
      ADD_FAILURE() << "cannot open " << path;
    }
  }
  ~RawDb() { sqlite3_close(db_); }
  int64_t scalar(const std::string& sql) {
    sqlite3_stmt* stmt = nullptr;
    EXPECT_EQ(sqlite3_prepare_v2(db_, sql.c_str(), -1, &stmt, nullptr), SQLITE_OK) << sql;
    int64_t value = -1;
    if (stmt != nullptr && sqlite3_step(stmt) == SQLITE_ROW) value = sqlite3_column_int64(stmt, 0);
    sqlite3_finalize(stmt);
    return value;
  }
  std::string text(const std::string& sql) {
    sqlite3_stmt* stmt = nullptr;
    EXPECT_EQ(sqlite3_prepare_v2(db_, sql.c_str(), -1, &stmt, nullptr), SQLITE_OK) << sql;
    std::string value;
    if (stmt != nullptr && sqlite3_step(stmt) == SQLITE_ROW) {
      value = reinterpret_cast<const char*>(sqlite3_column_text(stmt, 0));
    }
    sqlite3_finalize(stmt);
    return value;
  }
  void exec(const std::string& sql) {
    EXPECT_EQ(sqlite3_exec(db_, sql.c_str(), nullptr, nullptr, nullptr), SQLITE_OK)
        << sql << ": " << sqlite3_errmsg(db_);
  }

 private:
  sqlite3* db_ = nullptr;
};

class JobStoreTest : public ::testing::Test {
 protected:
  void SetUp() override {
    std::random_device rd;
    std::ostringstream name;
    name << "systole_store_test_" << ::getpid() << "_" << std::hex << rd() << rd();
    dir_ = fs::temp_directory_path() / name.str();
    ASSERT_TRUE(fs::create_directories(dir_)) << dir_;
    path_ = dir_ / "jobs.db";
  }
  void TearDown() override {
    store_.reset();
    std::error_code ec;
    fs::remove_all(dir_, ec);
    EXPECT_FALSE(ec) << "cannot remove " << dir_ << ": " << ec.message();
  }

  JobStore& store() {
    if (!store_) store_ = std::make_unique<JobStore>(path_.string());
    return *store_;
  }
  void reopen() {
    store_.reset();
    store_ = std::make_unique<JobStore>(path_.string());
  }

  JobRecord submit(int priority = 0, int64_t now = kT0, int max_attempts = 3,
                   const std::string& request_id = "") {
    return store().submit(request_id, "lumped", R"({"heart_rate_bpm":70})", priority,
                          max_attempts, now).job;
  }
  // Submits one job and leases it (it must be the only QUEUED one).
  JobRecord running(const std::string& worker = "w1", int max_attempts = 3, int64_t now = kT0) {
    const JobRecord queued = submit(0, now, max_attempts);
    std::optional<Lease> lease = store().lease(worker, kLease, now + 1);
    EXPECT_TRUE(lease.has_value());
    if (!lease) return queued;
    EXPECT_EQ(lease->job.id, queued.id);
    return lease->job;
  }
  std::vector<json> state_events(const std::string& id) {
    std::vector<json> out;
    for (const Event& e : store().events(id, 0, 1000)) {
      if (e.kind == "state") out.push_back(json::parse(e.payload_json));
    }
    return out;
  }

  fs::path dir_;
  fs::path path_;
  std::unique_ptr<JobStore> store_;
};

// ---- JobState ------------------------------------------------------------------------------

TEST(JobStoreStateTest, RoundTripsThroughText) {
  for (const JobState s : {JobState::kQueued, JobState::kRunning, JobState::kSucceeded,
                           JobState::kFailed, JobState::kCancelled}) {
    EXPECT_EQ(from_string(to_string(s)), s);
  }
  EXPECT_EQ(to_string(JobState::kCancelled), "CANCELLED");
  EXPECT_FALSE(from_string("queued").has_value());
  EXPECT_FALSE(from_string("").has_value());
  EXPECT_FALSE(is_terminal(JobState::kQueued));
  EXPECT_FALSE(is_terminal(JobState::kRunning));
  EXPECT_TRUE(is_terminal(JobState::kSucceeded));
  EXPECT_TRUE(is_terminal(JobState::kFailed));
  EXPECT_TRUE(is_terminal(JobState::kCancelled));
}

// ---- migrations ----------------------------------------------------------------------------

TEST_F(JobStoreTest, MigrationsRecordVersionAndReopenIsIdempotent) {
  const std::string id = submit().id;
  store_.reset();
  {
    RawDb raw(path_);
    EXPECT_GE(JobStore::schema_version(), 1);
    EXPECT_EQ(raw.scalar("PRAGMA user_version"), JobStore::schema_version());
    EXPECT_EQ(raw.text("PRAGMA journal_mode"), "wal");
    EXPECT_EQ(raw.scalar("SELECT COUNT(*) FROM sqlite_schema WHERE name IN "
                         "('jobs','events','results','artifacts')"),
              4);
    EXPECT_EQ(raw.scalar("SELECT COUNT(*) FROM sqlite_schema WHERE type = 'index' AND name IN "
                         "('jobs_for_lease','jobs_by_request_id')"),
              2);
  }
  reopen();  // a second open must not re-run (and fail on) the migrations
  reopen();
  EXPECT_TRUE(store().get(id).has_value());
  EXPECT_EQ(store().count(std::nullopt), 1);
  store_.reset();
  RawDb raw(path_);
  EXPECT_EQ(raw.scalar("PRAGMA user_version"), JobStore::schema_version());
}

TEST_F(JobStoreTest, MigrationsRejectNewerSchema) {
  submit();
  store_.reset();
  {
    RawDb raw(path_);
    raw.exec("PRAGMA user_version = " + std::to_string(JobStore::schema_version() + 1));
  }
  expect_error([&] { JobStore s(path_.string()); }, Code::kFailedPrecondition,
               {std::to_string(JobStore::schema_version() + 1), "newer"});
  // The refusal must not have touched the file.
  RawDb raw(path_);
  EXPECT_EQ(raw.scalar("PRAGMA user_version"), JobStore::schema_version() + 1);
  EXPECT_EQ(raw.scalar("SELECT COUNT(*) FROM jobs"), 1);
}

TEST_F(JobStoreTest, MigrationsRejectForeignDatabase) {
  {
    RawDb raw(path_);
    raw.exec("CREATE TABLE something_else (x INTEGER)");
  }
  expect_error([&] { JobStore s(path_.string()); }, Code::kFailedPrecondition,
               {"not a systole job store"});
}

TEST_F(JobStoreTest, OpenFailsCleanlyOnGarbageOrMissingDirectory) {
  {
    std::FILE* f = std::fopen(path_.c_str(), "wb");
    ASSERT_NE(f, nullptr);
    const std::string junk(4096, 'x');
    std::fwrite(junk.data(), 1, junk.size(), f);
    std::fclose(f);
  }
  expect_error([&] { JobStore s(path_.string()); }, Code::kInternal);
  expect_error([&] { JobStore s((dir_ / "no" / "such" / "dir.db").string()); }, Code::kInternal);
}

// ---- submit / get --------------------------------------------------------------------------

TEST_F(JobStoreTest, SubmitAndGet) {
  const SubmitOutcome out = store().submit("req-1", "lumped", R"({"a":1})", 5, 3, kT0);
  EXPECT_TRUE(out.created);
  const JobRecord& job = out.job;
  EXPECT_EQ(job.id.size(), 18u);
  EXPECT_EQ(job.id.rfind("j-", 0), 0u);
  EXPECT_EQ(job.id.find_first_not_of("0123456789abcdef", 2), std::string::npos) << job.id;
  EXPECT_EQ(job.request_id, "req-1");
  EXPECT_EQ(job.scene, "lumped");
  EXPECT_EQ(job.scenario_json, R"({"a":1})");
  EXPECT_EQ(job.state, JobState::kQueued);
  EXPECT_EQ(job.priority, 5);
  EXPECT_EQ(job.attempts, 0);
  EXPECT_EQ(job.max_attempts, 3);
  EXPECT_FALSE(job.cancel_requested);
  EXPECT_EQ(job.created_ms, kT0);
  EXPECT_EQ(job.updated_ms, kT0);
  EXPECT_EQ(job.started_ms, 0);
  EXPECT_EQ(job.finished_ms, 0);
  EXPECT_EQ(job.lease_expires_ms, 0);
  EXPECT_EQ(job.worker_id, "");
  EXPECT_EQ(job.error, "");
  EXPECT_EQ(job.progress_json, "");

  const std::optional<JobRecord> got = store().get(job.id);
  ASSERT_TRUE(got.has_value());
  EXPECT_EQ(got->id, job.id);
  EXPECT_EQ(got->scenario_json, job.scenario_json);
  EXPECT_EQ(got->state, JobState::kQueued);
  EXPECT_FALSE(store().get("j-0000000000000000").has_value());

  const std::vector<Event> events = store().events(job.id, 0, 0);
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events[0].seq, 1);
  EXPECT_EQ(events[0].job_id, job.id);
  EXPECT_EQ(events[0].time_ms, kT0);
  EXPECT_EQ(events[0].kind, "state");
  EXPECT_EQ(json::parse(events[0].payload_json), json({{"state", "QUEUED"}}));

  // Empty request_id: always a new job, with distinct ids.
  std::set<std::string> ids{job.id};
  for (int i = 0; i < 20; ++i) {
    const SubmitOutcome o = store().submit("", "lumped", R"({"a":1})", 5, 3, kT0);
    EXPECT_TRUE(o.created);
    EXPECT_EQ(o.job.request_id, "");
    ids.insert(o.job.id);
  }
  EXPECT_EQ(ids.size(), 21u);
  EXPECT_EQ(store().count(std::nullopt), 21);
  EXPECT_EQ(store().count(JobState::kQueued), 21);
  EXPECT_EQ(store().count(JobState::kRunning), 0);
}

TEST_F(JobStoreTest, SubmitIsIdempotentOnRequestId) {
  const SubmitOutcome first = store().submit("req-7", "lumped", R"({"a":1,"b":[1,2]})", 2, 3, kT0);
  ASSERT_TRUE(first.created);
  // Same request: same job, even with different JSON spelling and a later clock.
  const SubmitOutcome again =
      store().submit("req-7", "lumped", R"({ "b": [1, 2], "a": 1 })", 2, 3, kT0 + 500);
  EXPECT_FALSE(again.created);
  EXPECT_EQ(again.job.id, first.job.id);
  EXPECT_EQ(again.job.created_ms, kT0);
  EXPECT_EQ(again.job.scenario_json, first.job.scenario_json);
  EXPECT_EQ(store().count(std::nullopt), 1);
  EXPECT_EQ(store().events(first.job.id, 0, 0).size(), 1u);

  // Same request_id, different scenario / scene / priority: refused, nothing changes.
  expect_error([&] { store().submit("req-7", "lumped", R"({"a":2})", 2, 3, kT0 + 600); },
               Code::kAlreadyExists, {"req-7", first.job.id, "different scenario"});
  expect_error([&] { store().submit("req-7", "fsi", R"({"a":1,"b":[1,2]})", 2, 3, kT0 + 600); },
               Code::kAlreadyExists, {"req-7", first.job.id, "scene"});
  expect_error(
      [&] { store().submit("req-7", "lumped", R"({"a":1,"b":[1,2]})", 3, 3, kT0 + 600); },
      Code::kAlreadyExists, {"priority"});
  EXPECT_EQ(store().count(std::nullopt), 1);
  const JobRecord unchanged = *store().get(first.job.id);
  EXPECT_EQ(unchanged.scenario_json, R"({"a":1,"b":[1,2]})");
  EXPECT_EQ(unchanged.updated_ms, kT0);
  EXPECT_EQ(store().events(first.job.id, 0, 0).size(), 1u);

  // A different request_id is a different job.
  const SubmitOutcome other = store().submit("req-8", "lumped", R"({"a":2})", 2, 3, kT0);
  EXPECT_TRUE(other.created);
  EXPECT_NE(other.job.id, first.job.id);
  EXPECT_EQ(store().count(std::nullopt), 2);
}

TEST_F(JobStoreTest, SubmitValidatesArguments) {
  const std::string ok = R"({"a":1})";
  expect_error([&] { store().submit("", "lumped", ok, 1001, 3, kT0); }, Code::kInvalidArgument,
               {"priority", "1001", "[-1000, 1000]"});
  expect_error([&] { store().submit("", "lumped", ok, -1001, 3, kT0); }, Code::kInvalidArgument,
               {"priority", "-1001"});
  expect_error([&] { store().submit("", "lumped", ok, 0, 0, kT0); }, Code::kInvalidArgument,
               {"max_attempts", "0", "[1, 100]"});
  expect_error([&] { store().submit("", "lumped", ok, 0, 101, kT0); }, Code::kInvalidArgument,
               {"max_attempts", "101"});
  expect_error([&] { store().submit("", "lumped", "{not json", 0, 3, kT0); },
               Code::kInvalidArgument, {"scenario_json"});
  expect_error([&] { store().submit("", "", ok, 0, 3, kT0); }, Code::kInvalidArgument,
               {"scene"});
  EXPECT_EQ(store().count(std::nullopt), 0);
  // The bounds themselves are valid.
  EXPECT_TRUE(store().submit("", "lumped", ok, -1000, 1, kT0).created);
  EXPECT_TRUE(store().submit("", "lumped", ok, 1000, 100, kT0).created);
  EXPECT_EQ(store().count(std::nullopt), 2);
}

// ---- list ----------------------------------------------------------------------------------

TEST_F(JobStoreTest, ListPagesNewestFirstWithoutGapsOrDuplicates) {
  // 25 jobs; created_ms repeats (pairs share a millisecond) to exercise the id tie-break.
  std::vector<JobRecord> all;
  for (int i = 0; i < 25; ++i) all.push_back(submit(0, kT0 + i / 2));
  std::vector<JobRecord> expected = all;
  std::sort(expected.begin(), expected.end(), [](const JobRecord& a, const JobRecord& b) {
    if (a.created_ms != b.created_ms) return a.created_ms > b.created_ms;
    return a.id < b.id;
  });

  std::vector<std::string> seen;
  std::string token;
  int pages = 0;
  do {
    const ListPage page = store().list(std::nullopt, 10, token);
    ++pages;
    EXPECT_EQ(page.jobs.size(), pages < 3 ? 10u : 5u) << "page " << pages;
    for (const JobRecord& j : page.jobs) seen.push_back(j.id);
    token = page.next_page_token;
    ASSERT_LE(pages, 3) << "too many pages";
  } while (!token.empty());
  EXPECT_EQ(pages, 3);
  ASSERT_EQ(seen.size(), expected.size());
  for (size_t i = 0; i < expected.size(); ++i) EXPECT_EQ(seen[i], expected[i].id) << i;
  EXPECT_EQ(std::set<std::string>(seen.begin(), seen.end()).size(), 25u);

  // A job submitted while paging (newer than everything) does not shift later pages.
  const ListPage p1 = store().list(std::nullopt, 10, "");
  submit(0, kT0 + 1000);
  const ListPage p2 = store().list(std::nullopt, 10, p1.next_page_token);
  ASSERT_EQ(p2.jobs.size(), 10u);
  EXPECT_EQ(p2.jobs.front().id, expected[10].id);

  // Default and maximum page sizes.
  EXPECT_EQ(store().list(std::nullopt, 0, "").jobs.size(), 26u);
  EXPECT_TRUE(store().list(std::nullopt, 0, "").next_page_token.empty());
  EXPECT_EQ(store().list(std::nullopt, 1000, "").jobs.size(), 26u);
  expect_error([&] { store().list(std::nullopt, 1001, ""); }, Code::kInvalidArgument,
               {"page_size", "1001"});
  expect_error([&] { store().list(std::nullopt, -1, ""); }, Code::kInvalidArgument,
               {"page_size"});
}

TEST_F(JobStoreTest, ListFiltersByState) {
  for (int i = 0; i < 7; ++i) submit(0, kT0 + i);
  std::set<std::string> leased;
  for (int i = 0; i < 3; ++i) leased.insert(store().lease("w", kLease, kT0 + 100)->job.id);

  std::set<std::string> running;
  std::string token;
  do {
    const ListPage page = store().list(JobState::kRunning, 2, token);
    for (const JobRecord& j : page.jobs) {
      EXPECT_EQ(j.state, JobState::kRunning);
      EXPECT_TRUE(running.insert(j.id).second) << "duplicate " << j.id;
    }
    token = page.next_page_token;
  } while (!token.empty());
  EXPECT_EQ(running, leased);

  const ListPage queued = store().list(JobState::kQueued, 100, "");
  EXPECT_EQ(queued.jobs.size(), 4u);
  for (const JobRecord& j : queued.jobs) EXPECT_EQ(j.state, JobState::kQueued);
  EXPECT_TRUE(store().list(JobState::kSucceeded, 100, "").jobs.empty());
  EXPECT_EQ(store().count(JobState::kRunning), 3);
  EXPECT_EQ(store().count(JobState::kQueued), 4);

  // A token is bound to its filter.
  const ListPage first = store().list(JobState::kQueued, 1, "");
  ASSERT_FALSE(first.next_page_token.empty());
  expect_error([&] { store().list(JobState::kRunning, 1, first.next_page_token); },
               Code::kInvalidArgument, {"page_token"});
  expect_error([&] { store().list(std::nullopt, 1, first.next_page_token); },
               Code::kInvalidArgument, {"page_token"});
}

TEST_F(JobStoreTest, ListRejectsBadPageTokens) {
  for (int i = 0; i < 3; ++i) submit(0, kT0 + i);
  const std::string good = store().list(std::nullopt, 1, "").next_page_token;
  ASSERT_FALSE(good.empty());
  for (const std::string& bad : {std::string("zz"), std::string("abc"), std::string("not-a-token"),
                                good.substr(0, good.size() - 2), good + "00",
                                std::string("7631"),  // hex of "v1"
                                std::string(good.size(), 'f')}) {
    expect_error([&] { store().list(std::nullopt, 1, bad); }, Code::kInvalidArgument,
                 {"page_token"});
  }
  EXPECT_EQ(store().list(std::nullopt, 1, good).jobs.size(), 1u);
}

// ---- lease ---------------------------------------------------------------------------------

TEST_F(JobStoreTest, LeaseOrderIsPriorityThenAge) {
  const JobRecord old_low = submit(0, kT0);
  const JobRecord new_high = submit(10, kT0 + 30);
  const JobRecord old_high = submit(10, kT0 + 20);
  const JobRecord negative = submit(-5, kT0 - 100);
  const JobRecord new_low = submit(0, kT0 + 40);

  std::vector<std::string> order;
  while (std::optional<Lease> l = store().lease("w1", kLease, kT0 + 1000)) {
    order.push_back(l->job.id);
  }
  EXPECT_EQ(order, (std::vector<std::string>{old_high.id, new_high.id, old_low.id, new_low.id,
                                             negative.id}));

  // Same priority and created_ms: smallest id first.
  const JobRecord a = submit(0, kT0 + 5000);
  const JobRecord b = submit(0, kT0 + 5000);
  EXPECT_EQ(store().lease("w1", kLease, kT0 + 6000)->job.id, std::min(a.id, b.id));
}

TEST_F(JobStoreTest, LeaseSetsRunningAndRecordsAttempt) {
  const JobRecord job = submit(0, kT0, 3);
  const std::optional<Lease> lease = store().lease("worker-a", 5000, kT0 + 100);
  ASSERT_TRUE(lease.has_value());
  EXPECT_EQ(lease->job.id, job.id);
  EXPECT_EQ(lease->job.state, JobState::kRunning);
  EXPECT_EQ(lease->job.worker_id, "worker-a");
  EXPECT_EQ(lease->job.attempts, 1);
  EXPECT_EQ(lease->job.started_ms, kT0 + 100);
  EXPECT_EQ(lease->job.lease_expires_ms, kT0 + 5100);
  EXPECT_EQ(lease->job.updated_ms, kT0 + 100);
  const std::vector<json> states = state_events(job.id);
  ASSERT_EQ(states.size(), 2u);
  EXPECT_EQ(states[1], json({{"state", "RUNNING"}, {"worker", "worker-a"}, {"attempt", 1}}));
  expect_error([&] { store().lease("", 5000, kT0); }, Code::kInvalidArgument, {"worker_id"});
  expect_error([&] { store().lease("w", 0, kT0); }, Code::kInvalidArgument, {"lease_ms"});
}

TEST_F(JobStoreTest, LeaseOnEmptyQueueReturnsNothing) {
  EXPECT_FALSE(store().lease("w1", kLease, kT0).has_value());
  const JobRecord run = running("w1");
  store().complete(run.id, "w1", "{}", "", kT0 + 10);
  const JobRecord other = running("w1");
  // Only RUNNING and SUCCEEDED jobs exist: nothing to lease, and nothing changed.
  EXPECT_FALSE(store().lease("w2", kLease, kT0 + 20).has_value());
  EXPECT_EQ(store().get(other.id)->worker_id, "w1");
  EXPECT_EQ(store().count(JobState::kRunning), 1);
}

// ---- heartbeat, ownership, progress ---------------------------------------------------------

TEST_F(JobStoreTest, HeartbeatExtendsTheLease) {
  const JobRecord job = running("w1");  // leased at kT0 + 1 for kLease
  EXPECT_EQ(job.lease_expires_ms, kT0 + 1 + kLease);
  const HeartbeatAnswer ok = store().heartbeat(job.id, "w1", 60'000, kT0 + 20'000);
  EXPECT_TRUE(ok.lease_valid);
  EXPECT_FALSE(ok.cancel_requested);
  EXPECT_EQ(store().get(job.id)->lease_expires_ms, kT0 + 80'000);
  // Past the original expiry, but within the extended one: not reclaimed.
  EXPECT_TRUE(store().requeue_expired(kT0 + 50'000).empty());
  EXPECT_EQ(store().get(job.id)->state, JobState::kRunning);
  // Only the events of submit and lease: heartbeats are not events.
  EXPECT_EQ(store().events(job.id, 0, 0).size(), 2u);

  // Wrong worker or unknown job: not valid, nothing changes.
  const HeartbeatAnswer other = store().heartbeat(job.id, "w2", 60'000, kT0 + 30'000);
  EXPECT_FALSE(other.lease_valid);
  EXPECT_EQ(store().get(job.id)->lease_expires_ms, kT0 + 80'000);
  EXPECT_FALSE(store().heartbeat("j-ffffffffffffffff", "w1", 60'000, kT0).lease_valid);
  expect_error([&] { store().heartbeat(job.id, "w1", 0, kT0); }, Code::kInvalidArgument,
               {"lease_ms"});

  // After completion the lease is gone.
  store().complete(job.id, "w1", "{}", "", kT0 + 40'000);
  EXPECT_FALSE(store().heartbeat(job.id, "w1", 60'000, kT0 + 41'000).lease_valid);
}

TEST_F(JobStoreTest, WorkerCallsRequireTheLeaseOwner) {
  const JobRecord job = running("w1");
  const JobRecord queued = submit();
  const Artifact artifact{"mesh", "/data/mesh.h5", "abc", 10};
  const std::vector<std::function<void(const std::string&, const std::string&)>> calls = {
      [&](const std::string& id, const std::string& w) { store().progress(id, w, "{}", kT0); },
      [&](const std::string& id, const std::string& w) { store().add_artifact(id, w, artifact); },
      [&](const std::string& id, const std::string& w) { store().complete(id, w, "{}", "", kT0); },
      [&](const std::string& id, const std::string& w) { store().fail(id, w, "x", true, kT0); },
      [&](const std::string& id, const std::string& w) { store().acknowledge_cancel(id, w, kT0); },
      [&](const std::string& id, const std::string& w) { store().release(id, w, kT0); },
  };
  for (size_t i = 0; i < calls.size(); ++i) {
    SCOPED_TRACE("call " + std::to_string(i));
    expect_error([&] { calls[i](job.id, "w2"); }, Code::kFailedPrecondition,
                 {job.id, "'w1'", "'w2'"});
    expect_error([&] { calls[i](queued.id, "w1"); }, Code::kFailedPrecondition,
                 {queued.id, "QUEUED"});
    expect_error([&] { calls[i]("j-0123456789abcdef", "w1"); }, Code::kNotFound,
                 {"j-0123456789abcdef"});
  }
  const JobRecord after = *store().get(job.id);
  EXPECT_EQ(after.state, JobState::kRunning);
  EXPECT_EQ(after.worker_id, "w1");
  EXPECT_EQ(after.attempts, 1);
  EXPECT_EQ(after.progress_json, "");
  EXPECT_EQ(store().events(job.id, 0, 0).size(), 2u);
  EXPECT_EQ(store().get(queued.id)->state, JobState::kQueued);
}

TEST_F(JobStoreTest, ProgressStoresPayloadAppendsEventAndExtendsLease) {
  const JobRecord job = running("w1");  // lease_ms = kLease
  store().progress(job.id, "w1", R"({"cycle":1,"t_s":0.8})", kT0 + 10'000);
  store().progress(job.id, "w1", R"({"cycle":2,"t_s":1.6})", kT0 + 20'000);
  const JobRecord after = *store().get(job.id);
  EXPECT_EQ(json::parse(after.progress_json), json({{"cycle", 2}, {"t_s", 1.6}}));
  EXPECT_EQ(after.lease_expires_ms, kT0 + 20'000 + kLease);
  const std::vector<Event> events = store().events(job.id, 0, 0);
  ASSERT_EQ(events.size(), 4u);
  EXPECT_EQ(events[2].kind, "progress");
  EXPECT_EQ(events[2].time_ms, kT0 + 10'000);
  EXPECT_EQ(json::parse(events[2].payload_json)["cycle"], 1);
  EXPECT_EQ(events[3].kind, "progress");
  EXPECT_EQ(json::parse(events[3].payload_json)["cycle"], 2);
  expect_error([&] { store().progress(job.id, "w1", "{cycle", kT0); }, Code::kInvalidArgument,
               {"payload_json"});
  // The lease length used by progress is the one of the latest heartbeat.
  store().heartbeat(job.id, "w1", 5'000, kT0 + 21'000);
  store().progress(job.id, "w1", R"({"cycle":3})", kT0 + 22'000);
  EXPECT_EQ(store().get(job.id)->lease_expires_ms, kT0 + 27'000);
}

// ---- complete, result, artifacts -------------------------------------------------------------

TEST_F(JobStoreTest, CompleteStoresResultAndArtifacts) {
  const JobRecord job = running("w1");
  EXPECT_FALSE(store().result(job.id).has_value());
  store().add_artifact(job.id, "w1", Artifact{"volumes", "/r/volumes.csv", "aa", 100});
  store().add_artifact(job.id, "w1", Artifact{"fields", "/r/fields.h5", "bb", 2000});
  store().add_artifact(job.id, "w1", Artifact{"volumes", "/r/volumes-v2.csv", "cc", 120});
  expect_error([&] { store().add_artifact(job.id, "w1", Artifact{"", "/x", "", 1}); },
               Code::kInvalidArgument, {"name"});
  expect_error([&] { store().add_artifact(job.id, "w1", Artifact{"x", "/x", "", -1}); },
               Code::kInvalidArgument, {"size_bytes"});
  EXPECT_FALSE(store().result(job.id).has_value()) << "no result before complete()";

  const JobRecord done =
      store().complete(job.id, "w1", R"({"ef":0.61})", R"({"t":[0,1]})", kT0 + 9000);
  EXPECT_EQ(done.state, JobState::kSucceeded);
  EXPECT_EQ(done.finished_ms, kT0 + 9000);
  EXPECT_EQ(done.lease_expires_ms, 0);
  EXPECT_EQ(done.worker_id, "w1");
  EXPECT_EQ(done.attempts, 1);

  const std::optional<ResultRecord> result = store().result(job.id);
  ASSERT_TRUE(result.has_value());
  EXPECT_EQ(result->job_id, job.id);
  EXPECT_EQ(json::parse(result->metrics_json), json({{"ef", 0.61}}));
  EXPECT_EQ(result->timeseries_json, R"({"t":[0,1]})");
  EXPECT_EQ(result->created_ms, kT0 + 9000);
  ASSERT_EQ(result->artifacts.size(), 2u);
  EXPECT_EQ(result->artifacts[0].name, "fields");
  EXPECT_EQ(result->artifacts[0].path, "/r/fields.h5");
  EXPECT_EQ(result->artifacts[0].sha256, "bb");
  EXPECT_EQ(result->artifacts[0].size_bytes, 2000);
  EXPECT_EQ(result->artifacts[1].name, "volumes");
  EXPECT_EQ(result->artifacts[1].path, "/r/volumes-v2.csv");  // replaced by name
  EXPECT_EQ(result->artifacts[1].sha256, "cc");
  EXPECT_EQ(result->artifacts[1].size_bytes, 120);

  EXPECT_EQ(state_events(job.id).back(), json({{"state", "SUCCEEDED"}}));
  // Terminal: no second completion, no more artifacts.
  expect_error([&] { store().complete(job.id, "w1", "{}", "", kT0 + 9500); },
               Code::kFailedPrecondition, {job.id, "SUCCEEDED"});
  expect_error([&] { store().add_artifact(job.id, "w1", Artifact{"late", "/l", "", 1}); },
               Code::kFailedPrecondition, {"SUCCEEDED"});
  expect_error([&] { store().complete(running("w9").id, "w9", "{bad", "", kT0); },
               Code::kInvalidArgument, {"metrics_json"});
  EXPECT_FALSE(store().result("j-0123456789abcdef").has_value());
}

// ---- fail / retry ---------------------------------------------------------------------------

TEST_F(JobStoreTest, RetryableFailureRequeuesUntilAttemptsAreExhausted) {
  const JobRecord job = running("w1", /*max_attempts=*/2);
  store().add_artifact(job.id, "w1", Artifact{"partial", "/p", "", 1});
  store().progress(job.id, "w1", R"({"cycle":1})", kT0 + 5);

  const JobRecord retry = store().fail(job.id, "w1", "solver diverged", true, kT0 + 10);
  EXPECT_EQ(retry.state, JobState::kQueued);
  EXPECT_EQ(retry.attempts, 1);
  EXPECT_EQ(retry.worker_id, "");
  EXPECT_EQ(retry.lease_expires_ms, 0);
  EXPECT_EQ(retry.finished_ms, 0);
  EXPECT_EQ(retry.error, "");
  EXPECT_EQ(retry.progress_json, "");
  EXPECT_EQ(state_events(job.id).back(),
            json({{"state", "QUEUED"}, {"reason", "solver diverged"}}));

  const std::optional<Lease> second = store().lease("w2", kLease, kT0 + 20);
  ASSERT_TRUE(second.has_value());
  EXPECT_EQ(second->job.id, job.id);
  EXPECT_EQ(second->job.attempts, 2);
  EXPECT_EQ(second->job.started_ms, kT0 + 1) << "started_ms is the first lease";
  EXPECT_EQ(state_events(job.id).back()["attempt"], 2);

  const JobRecord failed = store().fail(job.id, "w2", "solver diverged again", true, kT0 + 30);
  EXPECT_EQ(failed.state, JobState::kFailed);
  EXPECT_EQ(failed.error, "solver diverged again");
  EXPECT_EQ(failed.finished_ms, kT0 + 30);
  EXPECT_EQ(failed.attempts, 2);
  EXPECT_EQ(state_events(job.id).back()["state"], "FAILED");
  EXPECT_EQ(state_events(job.id).back()["error"], "solver diverged again");
  EXPECT_FALSE(store().result(job.id).has_value());
  EXPECT_FALSE(store().lease("w3", kLease, kT0 + 40).has_value());

  // Non-retryable: FAILED at once, whatever attempts remain.
  const JobRecord other = running("w1", /*max_attempts=*/5);
  const JobRecord final_fail = store().fail(other.id, "w1", "bad mesh", false, kT0 + 50);
  EXPECT_EQ(final_fail.state, JobState::kFailed);
  EXPECT_EQ(final_fail.attempts, 1);
  EXPECT_EQ(final_fail.error, "bad mesh");
  EXPECT_EQ(store().count(JobState::kFailed), 2);
}

TEST_F(JobStoreTest, RetryableFailureOfACancelledJobCancelsIt) {
  const JobRecord job = running("w1", 3);
  store().cancel(job.id, kT0 + 5);
  const JobRecord after = store().fail(job.id, "w1", "interrupted", true, kT0 + 10);
  EXPECT_EQ(after.state, JobState::kCancelled);
  EXPECT_EQ(store().count(JobState::kQueued), 0);
}

// ---- cancel ---------------------------------------------------------------------------------

TEST_F(JobStoreTest, CancelQueuedRunningAndTerminal) {
  // QUEUED: cancelled at once.
  const JobRecord queued = submit();
  const JobRecord cancelled = store().cancel(queued.id, kT0 + 10);
  EXPECT_EQ(cancelled.state, JobState::kCancelled);
  EXPECT_EQ(cancelled.finished_ms, kT0 + 10);
  EXPECT_EQ(state_events(queued.id).back(), json({{"state", "CANCELLED"}}));
  EXPECT_FALSE(store().lease("w1", kLease, kT0 + 11).has_value());

  // RUNNING: only requested; the worker learns it from the heartbeat.
  const JobRecord run = running("w1");
  const JobRecord requested = store().cancel(run.id, kT0 + 20);
  EXPECT_EQ(requested.state, JobState::kRunning);
  EXPECT_TRUE(requested.cancel_requested);
  EXPECT_EQ(requested.finished_ms, 0);
  std::vector<Event> events = store().events(run.id, 0, 0);
  ASSERT_EQ(events.size(), 3u);
  EXPECT_EQ(events[2].kind, "cancel_requested");
  EXPECT_EQ(events[2].time_ms, kT0 + 20);
  // Asking twice is harmless and does not log twice.
  EXPECT_TRUE(store().cancel(run.id, kT0 + 25).cancel_requested);
  EXPECT_EQ(store().events(run.id, 0, 0).size(), 3u);

  const HeartbeatAnswer hb = store().heartbeat(run.id, "w1", kLease, kT0 + 30);
  EXPECT_TRUE(hb.lease_valid);
  EXPECT_TRUE(hb.cancel_requested);

  const JobRecord acked = store().acknowledge_cancel(run.id, "w1", kT0 + 40);
  EXPECT_EQ(acked.state, JobState::kCancelled);
  EXPECT_EQ(acked.finished_ms, kT0 + 40);
  EXPECT_EQ(acked.lease_expires_ms, 0);
  EXPECT_EQ(state_events(run.id).back(), json({{"state", "CANCELLED"}}));
  EXPECT_FALSE(store().heartbeat(run.id, "w1", kLease, kT0 + 50).lease_valid);

  // Terminal: refused with a message naming the job and its state.
  const JobRecord done = running("w1");
  store().complete(done.id, "w1", "{}", "", kT0 + 60);
  expect_error([&] { store().cancel(done.id, kT0 + 70); }, Code::kFailedPrecondition,
               {done.id, "SUCCEEDED", "only QUEUED or RUNNING jobs can be cancelled"});
  expect_error([&] { store().cancel(queued.id, kT0 + 70); }, Code::kFailedPrecondition,
               {"CANCELLED"});
  expect_error([&] { store().cancel("j-0123456789abcdef", kT0); }, Code::kNotFound,
               {"j-0123456789abcdef"});
  EXPECT_EQ(store().get(done.id)->state, JobState::kSucceeded);
}

TEST_F(JobStoreTest, AcknowledgeCancelNeedsARequest) {
  const JobRecord run = running("w1");
  expect_error([&] { store().acknowledge_cancel(run.id, "w1", kT0 + 10); },
               Code::kFailedPrecondition, {run.id, "no cancel request"});
  store().cancel(run.id, kT0 + 20);
  expect_error([&] { store().acknowledge_cancel(run.id, "w2", kT0 + 30); },
               Code::kFailedPrecondition, {"'w2'"});
  EXPECT_EQ(store().acknowledge_cancel(run.id, "w1", kT0 + 40).state, JobState::kCancelled);
}

// ---- release --------------------------------------------------------------------------------

TEST_F(JobStoreTest, ReleaseRequeuesWithoutSpendingAnAttempt) {
  const JobRecord job = running("w1", /*max_attempts=*/1);
  store().add_artifact(job.id, "w1", Artifact{"partial", "/p", "", 1});
  const JobRecord released = store().release(job.id, "w1", kT0 + 100);
  EXPECT_EQ(released.state, JobState::kQueued);
  EXPECT_EQ(released.attempts, 0);
  EXPECT_EQ(released.worker_id, "");
  EXPECT_EQ(released.lease_expires_ms, 0);
  EXPECT_EQ(state_events(job.id).back(),
            json({{"state", "QUEUED"}, {"reason", "released by worker w1"}}));

  // With max_attempts = 1 the job can still run to completion after a release.
  const std::optional<Lease> again = store().lease("w2", kLease, kT0 + 200);
  ASSERT_TRUE(again.has_value());
  EXPECT_EQ(again->job.attempts, 1);
  store().complete(job.id, "w2", "{}", "", kT0 + 300);
  // The artifact of the released attempt is not part of the result.
  EXPECT_TRUE(store().result(job.id)->artifacts.empty());

  // A release after a cancel request ends the job.
  const JobRecord other = running("w1");
  store().cancel(other.id, kT0 + 400);
  const JobRecord ended = store().release(other.id, "w1", kT0 + 500);
  EXPECT_EQ(ended.state, JobState::kCancelled);
  EXPECT_EQ(ended.finished_ms, kT0 + 500);
}

// ---- lease expiry ---------------------------------------------------------------------------

TEST_F(JobStoreTest, RequeueExpiredHandlesRetryExhaustionAndCancel) {
  // Leased at kT0 + 1 with kLease; expiry at kT0 + 1 + kLease.
  const JobRecord retry = running("w-retry", 3);
  const JobRecord exhausted = running("w-last", 1);
  const JobRecord cancelling = running("w-cancel", 3);
  const JobRecord alive = running("w-alive", 3);
  store().cancel(cancelling.id, kT0 + 10);
  store().heartbeat(alive.id, "w-alive", 10 * kLease, kT0 + 20);
  const int64_t expiry = kT0 + 1 + kLease;

  EXPECT_TRUE(store().requeue_expired(expiry).empty()) << "expiry is strict: lease < now";
  std::vector<std::string> affected = store().requeue_expired(expiry + 1);
  std::sort(affected.begin(), affected.end());
  std::vector<std::string> want{retry.id, exhausted.id, cancelling.id};
  std::sort(want.begin(), want.end());
  EXPECT_EQ(affected, want);

  const JobRecord r = *store().get(retry.id);
  EXPECT_EQ(r.state, JobState::kQueued);
  EXPECT_EQ(r.attempts, 1);
  EXPECT_EQ(r.worker_id, "");
  EXPECT_EQ(state_events(retry.id).back(),
            json({{"state", "QUEUED"}, {"reason", "lease expired (worker w-retry lost)"}}));

  const JobRecord x = *store().get(exhausted.id);
  EXPECT_EQ(x.state, JobState::kFailed);
  EXPECT_NE(x.error.find("lease expired after 1"), std::string::npos) << x.error;
  EXPECT_EQ(x.finished_ms, expiry + 1);

  const JobRecord c = *store().get(cancelling.id);
  EXPECT_EQ(c.state, JobState::kCancelled);
  EXPECT_EQ(c.finished_ms, expiry + 1);

  EXPECT_EQ(store().get(alive.id)->state, JobState::kRunning);

  // The lost worker comes back: its lease is gone and it cannot complete.
  EXPECT_FALSE(store().heartbeat(retry.id, "w-retry", kLease, expiry + 2).lease_valid);
  expect_error([&] { store().complete(retry.id, "w-retry", "{}", "", expiry + 3); },
               Code::kFailedPrecondition, {"QUEUED"});
  // Nothing left to reclaim.
  EXPECT_TRUE(store().requeue_expired(expiry + 1).empty());

  // Exhaustion after several attempts is reported with the count.
  const std::optional<Lease> l2 = store().lease("w-b", 100, expiry + 10);
  ASSERT_TRUE(l2.has_value());
  ASSERT_EQ(l2->job.id, retry.id);
  store().requeue_expired(expiry + 200);
  ASSERT_EQ(store().lease("w-c", 100, expiry + 300)->job.attempts, 3);
  EXPECT_EQ(store().requeue_expired(expiry + 500), std::vector<std::string>{retry.id});
  const JobRecord gone = *store().get(retry.id);
  EXPECT_EQ(gone.state, JobState::kFailed);
  EXPECT_EQ(gone.error, "lease expired after 3 attempts");
}

// ---- events ---------------------------------------------------------------------------------

TEST_F(JobStoreTest, EventsResumeFromASequenceNumber) {
  const JobRecord job = running("w1");  // events 1 (QUEUED), 2 (RUNNING)
  for (int i = 1; i <= 5; ++i) {
    store().progress(job.id, "w1", json({{"cycle", i}}).dump(), kT0 + 100 * i);  // 3..7
  }
  store().complete(job.id, "w1", "{}", "", kT0 + 1000);  // 8
  const JobRecord other = submit();  // its own sequence starts at 1

  const std::vector<Event> all = store().events(job.id, 0, 0);
  ASSERT_EQ(all.size(), 8u);
  for (size_t i = 0; i < all.size(); ++i) {
    EXPECT_EQ(all[i].seq, static_cast<int64_t>(i + 1));
    EXPECT_EQ(all[i].job_id, job.id);
    if (i > 0) {
      EXPECT_GE(all[i].time_ms, all[i - 1].time_ms);
    }
  }

  const std::vector<Event> tail = store().events(job.id, 4, 0);
  ASSERT_EQ(tail.size(), 4u);
  EXPECT_EQ(tail.front().seq, 5);
  EXPECT_EQ(json::parse(tail.front().payload_json)["cycle"], 3);
  EXPECT_EQ(tail.back().seq, 8);
  EXPECT_EQ(json::parse(tail.back().payload_json)["state"], "SUCCEEDED");

  // Paging through with a small limit sees each event once.
  std::vector<int64_t> seqs;
  int64_t after = 0;
  for (;;) {
    const std::vector<Event> batch = store().events(job.id, after, 3);
    if (batch.empty()) break;
    EXPECT_LE(batch.size(), 3u);
    for (const Event& e : batch) seqs.push_back(e.seq);
    after = batch.back().seq;
  }
  EXPECT_EQ(seqs, (std::vector<int64_t>{1, 2, 3, 4, 5, 6, 7, 8}));
  EXPECT_TRUE(store().events(job.id, 8, 0).empty());
  EXPECT_TRUE(store().events(job.id, 100, 0).empty());

  const std::vector<Event> other_events = store().events(other.id, 0, 0);
  ASSERT_EQ(other_events.size(), 1u);
  EXPECT_EQ(other_events[0].seq, 1);

  expect_error([&] { store().events("j-0123456789abcdef", 0, 0); }, Code::kNotFound,
               {"j-0123456789abcdef"});
  expect_error([&] { store().events(job.id, -1, 0); }, Code::kInvalidArgument, {"after_seq"});
  expect_error([&] { store().events(job.id, 0, 1001); }, Code::kInvalidArgument, {"limit"});
}

// ---- durability -----------------------------------------------------------------------------

TEST_F(JobStoreTest, EverythingPersistsAcrossReopen) {
  const JobRecord done = running("w1");
  store().progress(done.id, "w1", R"({"cycle":4})", kT0 + 50);
  store().add_artifact(done.id, "w1", Artifact{"fields", "/r/f.h5", "beef", 42});
  store().complete(done.id, "w1", R"({"ef":0.6})", R"({"t":[]})", kT0 + 100);
  const JobRecord run = running("w2");
  store().cancel(run.id, kT0 + 110);
  const JobRecord queued = store().submit("req-q", "fsi", R"({"x":true})", 7, 4, kT0 + 120).job;
  const std::vector<Event> events_before = store().events(done.id, 0, 0);

  reopen();

  const JobRecord d = *store().get(done.id);
  EXPECT_EQ(d.state, JobState::kSucceeded);
  EXPECT_EQ(d.finished_ms, kT0 + 100);
  EXPECT_EQ(d.progress_json, R"({"cycle":4})");
  const std::optional<ResultRecord> result = store().result(done.id);
  ASSERT_TRUE(result.has_value());
  EXPECT_EQ(result->metrics_json, R"({"ef":0.6})");
  ASSERT_EQ(result->artifacts.size(), 1u);
  EXPECT_EQ(result->artifacts[0].sha256, "beef");
  const std::vector<Event> events_after = store().events(done.id, 0, 0);
  ASSERT_EQ(events_after.size(), events_before.size());
  for (size_t i = 0; i < events_after.size(); ++i) {
    EXPECT_EQ(events_after[i].seq, events_before[i].seq);
    EXPECT_EQ(events_after[i].kind, events_before[i].kind);
    EXPECT_EQ(events_after[i].payload_json, events_before[i].payload_json);
  }

  const JobRecord r = *store().get(run.id);
  EXPECT_EQ(r.state, JobState::kRunning);
  EXPECT_TRUE(r.cancel_requested);
  EXPECT_EQ(r.worker_id, "w2");
  EXPECT_TRUE(store().heartbeat(run.id, "w2", kLease, kT0 + 130).cancel_requested);

  const JobRecord q = *store().get(queued.id);
  EXPECT_EQ(q.request_id, "req-q");
  EXPECT_EQ(q.priority, 7);
  EXPECT_EQ(q.max_attempts, 4);
  // Idempotency survives a restart.
  const SubmitOutcome repeat = store().submit("req-q", "fsi", R"({"x":true})", 7, 4, kT0 + 140);
  EXPECT_FALSE(repeat.created);
  EXPECT_EQ(repeat.job.id, queued.id);
  // New events continue the per-job sequence.
  store().acknowledge_cancel(run.id, "w2", kT0 + 150);
  EXPECT_EQ(store().events(run.id, 0, 0).back().seq, 4);
  EXPECT_EQ(store().count(std::nullopt), 3);
}

namespace {
void write_all(int fd, const std::string& text) {
  size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n <= 0) ::_exit(4);
    done += static_cast<size_t>(n);
  }
}
}  // namespace

// A child process writes through the store and SIGKILLs itself half-way. Every operation it
// reported as acknowledged (returned from the store) must be in the file afterwards.
TEST_F(JobStoreTest, AcknowledgedWritesSurviveSigkill) {
  int fds[2];
  ASSERT_EQ(::pipe(fds), 0);
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    // Child: no gtest assertions here, only _exit codes.
    ::close(fds[0]);
    try {
      JobStore child(path_.string());
      for (int i = 0; i < 50; ++i) {
        const JobRecord job = child.submit("crash-" + std::to_string(i), "lumped",
                                           json({{"i", i}}).dump(), 0, 3, kT0 + i).job;
        write_all(fds[1], "S " + job.id + "\n");
        if (i % 3 == 0) {
          const std::optional<Lease> lease = child.lease("crash-worker", kLease, kT0 + i);
          if (!lease) ::_exit(5);
          child.progress(lease->job.id, "crash-worker", json({{"i", i}}).dump(), kT0 + i);
          child.complete(lease->job.id, "crash-worker", json({{"i", i}}).dump(), "", kT0 + i);
          write_all(fds[1], "C " + lease->job.id + "\n");
        }
        if (i == 37) {
          write_all(fds[1], "N " + std::to_string(i + 1) + "\n");
          std::raise(SIGKILL);
        }
      }
    } catch (...) {
      ::_exit(3);
    }
    ::_exit(6);  // not reached: SIGKILL above
  }
  ::close(fds[1]);
  std::string output;
  char buffer[4096];
  for (ssize_t n; (n = ::read(fds[0], buffer, sizeof buffer)) > 0;) output.append(buffer, n);
  ::close(fds[0]);
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFSIGNALED(status)) << "child exited with " << WEXITSTATUS(status);
  EXPECT_EQ(WTERMSIG(status), SIGKILL);

  std::vector<std::string> submitted;
  std::vector<std::string> completed;
  int acknowledged = -1;
  std::istringstream lines(output);
  std::string tag, value;
  while (lines >> tag >> value) {
    if (tag == "S") submitted.push_back(value);
    if (tag == "C") completed.push_back(value);
    if (tag == "N") acknowledged = std::stoi(value);
  }
  EXPECT_EQ(acknowledged, 38);
  ASSERT_EQ(submitted.size(), 38u);
  EXPECT_EQ(completed.size(), 13u);  // i = 0, 3, ..., 36

  // The killed process left its WAL behind; opening recovers it.
  EXPECT_EQ(store().count(std::nullopt), 38);
  for (size_t i = 0; i < submitted.size(); ++i) {
    const std::optional<JobRecord> job = store().get(submitted[i]);
    ASSERT_TRUE(job.has_value()) << "acknowledged job " << submitted[i] << " lost";
    EXPECT_EQ(job->request_id, "crash-" + std::to_string(i));
    EXPECT_EQ(json::parse(job->scenario_json)["i"], static_cast<int>(i));
  }
  for (const std::string& id : completed) {
    const JobRecord job = *store().get(id);
    EXPECT_EQ(job.state, JobState::kSucceeded) << id;
    EXPECT_TRUE(store().result(id).has_value()) << id;
    EXPECT_EQ(store().events(id, 0, 0).size(), 4u) << id;  // QUEUED, RUNNING, progress, SUCCEEDED
  }
  EXPECT_EQ(store().count(JobState::kSucceeded), 13);
  EXPECT_EQ(store().count(JobState::kQueued), 25);
  // And the store is fully usable afterwards.
  EXPECT_TRUE(store().lease("after-crash", kLease, kT0 + 100).has_value());
}

// ---- concurrency ----------------------------------------------------------------------------

TEST_F(JobStoreTest, ConcurrentLeasingHandsOutEachJobExactlyOnce) {
  constexpr int kJobs = 200;
  constexpr int kThreads = 4;
  std::set<std::string> submitted;
  for (int i = 0; i < kJobs; ++i) submitted.insert(submit(i % 7, kT0 + i).id);
  ASSERT_EQ(submitted.size(), static_cast<size_t>(kJobs));

  // Threads 0 and 1 share this process's store object (its mutex); threads 2 and 3 use a
  // second connection to the same file, as another server process would (SQLite locking).
  JobStore second(path_.string());
  std::vector<JobStore*> stores{&store(), &store(), &second, &second};

  std::vector<std::vector<std::string>> leased(kThreads);
  std::atomic<int> errors{0};
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t) {
    threads.emplace_back([&, t] {
      const std::string worker = "w" + std::to_string(t);
      JobStore& s = *stores[t];
      try {
        while (std::optional<Lease> l = s.lease(worker, kLease, kT0 + 1000)) {
          if (l->job.worker_id != worker || l->job.attempts != 1) ++errors;
          leased[t].push_back(l->job.id);
          if (leased[t].size() % 2 == 0) s.complete(l->job.id, worker, "{}", "", kT0 + 2000);
        }
      } catch (const std::exception&) {
        ++errors;
      }
    });
  }
  for (std::thread& t : threads) t.join();
  EXPECT_EQ(errors.load(), 0);
  // (No per-thread fairness is asserted: SQLite's busy handler sleeps, so the second
  // connection may find the queue already drained. What matters is exactly-once.)

  std::multiset<std::string> all;
  for (const auto& ids : leased) all.insert(ids.begin(), ids.end());
  EXPECT_EQ(all.size(), static_cast<size_t>(kJobs));
  EXPECT_EQ(std::set<std::string>(all.begin(), all.end()), submitted);
  for (const std::string& id : submitted) EXPECT_EQ(all.count(id), 1u) << id;
  EXPECT_EQ(store().count(JobState::kQueued), 0);
  EXPECT_EQ(store().count(JobState::kRunning) + store().count(JobState::kSucceeded), kJobs);
  for (const std::string& id : submitted) {
    const std::vector<Event> events = store().events(id, 0, 0);
    ASSERT_GE(events.size(), 2u);
    EXPECT_EQ(events[0].seq, 1);
    EXPECT_EQ(events[1].seq, 2);
    EXPECT_EQ(json::parse(events[1].payload_json)["attempt"], 1);
  }
}

}  // namespace

// ---- result cache and campaigns (schema 2) ---------------------------------------------------

NewJob cached_job(const std::string& key, const std::string& scenario = R"({"heart_rate_bpm":70})") {
  NewJob job;
  job.scene = "lumped";
  job.scenario_json = scenario;
  job.cache_key = key;
  return job;
}

TEST_F(JobStoreTest, CacheReusesASucceededJobsResultAndSaysSo) {
  const JobRecord first = store().submit_job(cached_job("key-a"), kT0).job;
  EXPECT_EQ(first.state, JobState::kQueued);
  EXPECT_TRUE(first.cached_from.empty());
  // Not yet succeeded: a second job with the same key is queued too.
  const JobRecord second = store().submit_job(cached_job("key-a"), kT0 + 1).job;
  EXPECT_EQ(second.state, JobState::kQueued);
  auto lease = store().lease("w1", kLease, kT0 + 2);
  ASSERT_TRUE(lease && lease->job.id == first.id);
  store().add_artifact(first.id, "w1", Artifact{"result.h5", "/data/a/result.h5", "abc", 10});
  store().complete(first.id, "w1", R"({"metrics":{"edv_ml":125}})", "", kT0 + 3);
  const JobRecord third = store().submit_job(cached_job("key-a"), kT0 + 4).job;
  EXPECT_EQ(third.state, JobState::kSucceeded);
  EXPECT_EQ(third.cached_from, first.id);
  const auto result = store().result(third.id);
  ASSERT_TRUE(result.has_value());
  EXPECT_EQ(result->metrics_json, R"({"metrics":{"edv_ml":125}})");
  ASSERT_EQ(result->artifacts.size(), 1u);
  EXPECT_EQ(result->artifacts[0].path, "/data/a/result.h5");
  const auto states = state_events(third.id);
  ASSERT_EQ(states.size(), 2u);
  EXPECT_EQ(states[1]["cached_from"], first.id);
  // Another key, or no key, never reuses.
  EXPECT_EQ(store().submit_job(cached_job("key-b"), kT0 + 5).job.state, JobState::kQueued);
  EXPECT_EQ(store().submit_job(cached_job(""), kT0 + 6).job.state, JobState::kQueued);
}

TEST_F(JobStoreTest, CampaignInsertsAllJobsAtomicallyAndCountsStates) {
  std::vector<NewJob> jobs;
  std::vector<std::string> inputs;
  for (int i = 0; i < 5; ++i) {
    jobs.push_back(cached_job("", "{\"heart_rate_bpm\":" + std::to_string(60 + i) + "}"));
    inputs.push_back("{\"heart_rate_bpm\":" + std::to_string(60 + i) + "}");
  }
  const auto outcome = store().create_campaign("camp-1", R"({"samples":5})", jobs, inputs, kT0);
  EXPECT_TRUE(outcome.created);
  EXPECT_EQ(outcome.campaign.jobs_total, 5);
  EXPECT_EQ(store().count(JobState::kQueued), 5);
  // Idempotent; a different spec under the same request_id is refused and adds nothing.
  EXPECT_FALSE(store().create_campaign("camp-1", R"({"samples":5})", jobs, inputs, kT0 + 1).created);
  try {
    store().create_campaign("camp-1", R"({"samples":6})", jobs, inputs, kT0 + 1);
    FAIL() << "expected kAlreadyExists";
  } catch (const StoreError& e) {
    EXPECT_EQ(e.code(), StoreError::Code::kAlreadyExists);
  }
  EXPECT_EQ(store().count(std::nullopt), 5);
  // A bad input row rejects the whole campaign.
  inputs[2] = "not json";
  EXPECT_THROW(store().create_campaign("", R"({})", jobs, inputs, kT0 + 2), StoreError);
  EXPECT_EQ(store().count(std::nullopt), 5);

  const std::string id = outcome.campaign.id;
  auto lease = store().lease("w1", kLease, kT0 + 3);
  ASSERT_TRUE(lease.has_value());
  const std::string done = lease->job.id;
  store().complete(done, "w1", R"({"metrics":{"edv_ml":120}})", "", kT0 + 4);
  lease = store().lease("w1", kLease, kT0 + 5);
  const std::string failed = lease->job.id;
  store().fail(failed, "w1", "unstable", false, kT0 + 6);
  const auto rows = store().campaign_samples(id);
  ASSERT_EQ(rows.size(), 5u);
  std::map<std::string, CampaignSampleRow> by_job;
  for (size_t i = 0; i < rows.size(); ++i) {
    EXPECT_EQ(rows[i].index, static_cast<int64_t>(i));
    EXPECT_EQ(rows[i].inputs_json, "{\"heart_rate_bpm\":" + std::to_string(60 + i) + "}");
    EXPECT_EQ(store().get(rows[i].job_id)->campaign_id, id);
    by_job[rows[i].job_id] = rows[i];
  }
  EXPECT_EQ(by_job[done].state, JobState::kSucceeded);
  EXPECT_EQ(by_job[done].metrics_json, R"({"metrics":{"edv_ml":120}})");
  EXPECT_EQ(by_job[failed].state, JobState::kFailed);
  EXPECT_EQ(by_job[failed].error, "unstable");

  // Cancel: the queued ones are cancelled, the running one asked to stop; retry brings the
  // failed and cancelled ones back.
  lease = store().lease("w1", kLease, kT0 + 7);
  const std::string running = lease->job.id;
  const CampaignRecord cancelled = store().cancel_campaign(id, kT0 + 8);
  EXPECT_TRUE(cancelled.cancelled);
  EXPECT_TRUE(store().get(running)->cancel_requested);
  EXPECT_EQ(store().count(JobState::kCancelled), 2);
  store().acknowledge_cancel(running, "w1", kT0 + 9);
  const CampaignRecord retried = store().retry_failed(id, kT0 + 10);
  EXPECT_FALSE(retried.cancelled);
  EXPECT_EQ(store().get(failed)->state, JobState::kQueued);
  EXPECT_EQ(store().get(failed)->attempts, 0);
  EXPECT_EQ(store().get(running)->state, JobState::kQueued);
  EXPECT_EQ(store().get(done)->state, JobState::kSucceeded);
  EXPECT_EQ(store().count(JobState::kQueued), 4);
  // Listing and persistence.
  reopen();
  const auto page = store().list_campaigns(10, "");
  ASSERT_EQ(page.campaigns.size(), 1u);
  EXPECT_EQ(page.campaigns[0].id, id);
  EXPECT_EQ(page.campaigns[0].jobs_total, 5);
  EXPECT_THROW(store().campaign_samples("c-missing"), StoreError);
}

}  // namespace systole::store
