#pragma once
// The durable job store of the systole service: jobs, their event log, results and artifacts,
// in one SQLite file (WAL, synchronous=FULL). Plain C++; the gRPC server maps StoreError::Code
// onto status codes. See service/store/README.md for the schema, the state machine and the
// durability contract.
//
// Conventions:
//  - Every mutating call is exactly one SQLite transaction: it either commits completely or
//    leaves the database untouched (and throws).
//  - Times are int64 milliseconds since the Unix epoch. The store never reads a clock: every
//    mutating call takes `now_ms`, so tests (and the server) own time.
//  - "Worker" calls (heartbeat, progress, add_artifact, complete, fail, acknowledge_cancel,
//    release) are only accepted from the lease owner of a RUNNING job. A lease whose
//    lease_expires_ms has passed still belongs to its worker until requeue_expired() reclaims
//    it; requeue_expired() is the only place where a lease expires.
//  - All methods are thread-safe (one connection serialised by a mutex).
#include <cstdint>
#include <mutex>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

struct sqlite3;
struct sqlite3_stmt;

namespace systole::store {

// QUEUED -> RUNNING -> SUCCEEDED | FAILED | CANCELLED; RUNNING -> QUEUED on a retry, a release
// or an expired lease; QUEUED -> CANCELLED on cancel.
enum class JobState { kQueued, kRunning, kSucceeded, kFailed, kCancelled };

// "QUEUED", "RUNNING", "SUCCEEDED", "FAILED", "CANCELLED".
std::string_view to_string(JobState state);
// Inverse of to_string (exact, upper case); nullopt for anything else.
std::optional<JobState> from_string(std::string_view text);
// SUCCEEDED, FAILED and CANCELLED.
bool is_terminal(JobState state);

class StoreError : public std::runtime_error {
 public:
  enum class Code { kNotFound, kFailedPrecondition, kAlreadyExists, kInvalidArgument, kInternal };
  StoreError(Code code, const std::string& message) : std::runtime_error(message), code_(code) {}
  Code code() const { return code_; }

 private:
  Code code_;
};

struct JobRecord {
  std::string id;
  std::string request_id;     // "" if the client gave none
  std::string scene;
  std::string scenario_json;  // exactly as submitted
  std::string worker_id;      // current (RUNNING) or last (terminal) lease owner; "" if none
  std::string error;          // set when FAILED; "" otherwise
  JobState state = JobState::kQueued;
  int priority = 0;
  int attempts = 0;  // number of leases that counted as an attempt
  int max_attempts = 1;
  bool cancel_requested = false;
  int64_t created_ms = 0;
  int64_t updated_ms = 0;
  int64_t started_ms = 0;        // first lease; 0 if never leased
  int64_t finished_ms = 0;       // entering a terminal state; 0 otherwise
  int64_t lease_expires_ms = 0;  // while RUNNING; 0 otherwise
  std::string progress_json;     // latest progress payload, "" if none yet
  std::string cache_key;         // "" if the job may not reuse or be reused
  std::string cached_from;       // the job whose result this one reuses; "" if it ran itself
  std::string campaign_id;       // "" unless the job is a sample of a campaign
};

// A job to insert (submit_job, create_campaign).
struct NewJob {
  std::string request_id;  // "" for none (campaign jobs have none)
  std::string scene;
  std::string scenario_json;
  int priority = 0;
  int max_attempts = 3;
  // Canonical scenario + solver version digest. Non-empty: if a SUCCEEDED job has the same
  // key, the new job is created SUCCEEDED with a copy of that job's result (same artifact
  // files) and cached_from set, instead of being queued.
  std::string cache_key;
};

struct CampaignRecord {
  std::string id;
  std::string request_id;
  std::string spec_json;
  int64_t created_ms = 0;
  bool cancelled = false;
  int64_t jobs_total = 0;
  int64_t jobs_cached = 0;
  std::vector<std::pair<JobState, int64_t>> jobs_by_state;  // states with at least one job
};

struct CampaignOutcome {
  CampaignRecord campaign;
  bool created = false;
};

struct CampaignSampleRow {
  int64_t index = 0;
  std::string job_id;
  std::string inputs_json;
  JobState state = JobState::kQueued;
  std::string error;
  std::string cached_from;
  std::string metrics_json;  // the job's result metrics; "" unless SUCCEEDED
};

struct CampaignPage {
  std::vector<CampaignRecord> campaigns;
  std::string next_page_token;
};

struct SubmitOutcome {
  JobRecord job;
  bool created = false;  // false: an earlier submit with the same request_id was returned
};

struct ListPage {
  std::vector<JobRecord> jobs;
  std::string next_page_token;  // "" on the last page
};

struct Lease {
  JobRecord job;
};

struct HeartbeatAnswer {
  bool lease_valid = false;       // false: stop working on the job, it is no longer yours
  bool cancel_requested = false;  // true: the client asked to cancel; acknowledge_cancel()
};

struct Artifact {
  std::string name;  // unique per job
  std::string path;
  std::string sha256;
  int64_t size_bytes = 0;
};

struct ResultRecord {
  std::string job_id;
  std::string metrics_json;
  std::string timeseries_json;
  std::vector<Artifact> artifacts;  // ordered by name
  int64_t created_ms = 0;
};

struct Event {
  int64_t seq = 0;  // per job: 1, 2, 3, ...
  std::string job_id;
  int64_t time_ms = 0;
  std::string kind;          // "state", "progress", "cancel_requested"
  std::string payload_json;  // JSON text (an object, or the worker's payload for "progress")
};

class JobStore {
 public:
  static constexpr int kMinPriority = -1000;
  static constexpr int kMaxPriority = 1000;
  static constexpr int kMinMaxAttempts = 1;
  static constexpr int kMaxMaxAttempts = 100;
  static constexpr int kDefaultPageSize = 100;
  static constexpr int kMaxPageSize = 1000;
  static constexpr int64_t kMaxLeaseMs = 24LL * 3600 * 1000;

  // Opens or creates the database file and migrates it to schema_version(). Throws StoreError:
  // kFailedPrecondition if the file was written by a newer systole (unknown schema version),
  // kInternal if it cannot be opened, is not a database, or WAL cannot be enabled.
  explicit JobStore(const std::string& db_path);
  ~JobStore();
  JobStore(const JobStore&) = delete;
  JobStore& operator=(const JobStore&) = delete;
  JobStore(JobStore&&) = delete;
  JobStore& operator=(JobStore&&) = delete;

  // The schema version this code writes (PRAGMA user_version after migration).
  static int schema_version();

  // New QUEUED job (event "state" {"state":"QUEUED"}). Idempotent on a non-empty request_id:
  // a repeat with the same scene, priority and scenario (compared as JSON values) returns the
  // first job with created=false; a repeat with different ones throws kAlreadyExists.
  // kInvalidArgument: empty scene, scenario_json not valid JSON, priority outside
  // [-1000,1000], max_attempts outside [1,100].
  SubmitOutcome submit(const std::string& request_id, const std::string& scene,
                       const std::string& scenario_json, int priority, int max_attempts,
                       int64_t now_ms);

  std::optional<JobRecord> get(const std::string& id);

  // Newest first: created_ms descending, then id ascending. page_size in [1,1000], 0 means 100.
  // page_token is "" for the first page, else a next_page_token returned by a list() with the
  // same filter (kInvalidArgument otherwise).
  ListPage list(std::optional<JobState> state, int page_size, const std::string& page_token);

  // QUEUED -> CANCELLED. RUNNING -> cancel_requested (once; event "cancel_requested"), the
  // worker then calls acknowledge_cancel(). Terminal -> kFailedPrecondition; unknown -> kNotFound.
  JobRecord cancel(const std::string& id, int64_t now_ms);

  // Leases the QUEUED job with the highest priority, then the oldest created_ms, then the
  // smallest id: RUNNING, attempts += 1, lease_expires_ms = now + lease_ms. nullopt if the
  // queue is empty. kInvalidArgument: empty worker_id, lease_ms outside [1, kMaxLeaseMs].
  std::optional<Lease> lease(const std::string& worker_id, int64_t lease_ms, int64_t now_ms);

  // Extends the lease to now + lease_ms if the job is RUNNING and leased by worker_id; else
  // lease_valid=false (also for an unknown job) and nothing changes. Heartbeats are not
  // events. kInvalidArgument: lease_ms outside [1, kMaxLeaseMs].
  HeartbeatAnswer heartbeat(const std::string& job_id, const std::string& worker_id,
                            int64_t lease_ms, int64_t now_ms);

  // Lease owner only. Stores payload_json (a JSON value) as the job's progress_json, appends
  // event "progress" with it, and extends the lease like heartbeat(), by the lease_ms of the
  // last lease()/heartbeat() of this attempt.
  // kNotFound / kFailedPrecondition (not RUNNING, not the owner) / kInvalidArgument (bad JSON).
  void progress(const std::string& job_id, const std::string& worker_id,
                const std::string& payload_json, int64_t now_ms);

  // Lease owner only. Attaches (or replaces, by name) an artifact of the running attempt.
  // No event, no time (the signature has no now_ms). Artifacts of an attempt that goes back to
  // QUEUED are dropped. kInvalidArgument: empty name or path, negative size.
  void add_artifact(const std::string& job_id, const std::string& worker_id,
                    const Artifact& artifact);

  // Lease owner only. RUNNING -> SUCCEEDED with the result row (metrics/timeseries are JSON
  // text, "" allowed for "none"); the artifacts already added stay attached.
  JobRecord complete(const std::string& job_id, const std::string& worker_id,
                     const std::string& metrics_json, const std::string& timeseries_json,
                     int64_t now_ms);

  // Lease owner only. retryable and attempts < max_attempts -> QUEUED (event reason = error),
  // unless a cancel was requested -> CANCELLED; otherwise -> FAILED with `error`.
  JobRecord fail(const std::string& job_id, const std::string& worker_id, const std::string& error,
                 bool retryable, int64_t now_ms);

  // Lease owner only, and a cancel must have been requested. RUNNING -> CANCELLED.
  JobRecord acknowledge_cancel(const std::string& job_id, const std::string& worker_id,
                               int64_t now_ms);

  // Lease owner only (a worker shutting down). RUNNING -> QUEUED with attempts -= 1, or
  // -> CANCELLED if a cancel was requested.
  JobRecord release(const std::string& job_id, const std::string& worker_id, int64_t now_ms);

  // Every RUNNING job with lease_expires_ms < now_ms: cancel requested -> CANCELLED; else
  // attempts < max_attempts -> QUEUED; else FAILED ("lease expired after N attempts").
  // Returns the affected ids (one transaction for all of them).
  std::vector<std::string> requeue_expired(int64_t now_ms);

  // The result of a SUCCEEDED job; nullopt otherwise (also for an unknown job).
  std::optional<ResultRecord> result(const std::string& job_id);

  // Events with seq > after_seq, in order, at most `limit` (0 means 100; range [1,1000]).
  // kNotFound for an unknown job, kInvalidArgument for after_seq < 0 or a bad limit.
  std::vector<Event> events(const std::string& job_id, int64_t after_seq, int limit);

  // Number of jobs, all or in one state.
  int64_t count(std::optional<JobState> state);

  // ---- result cache and campaigns (schema 2) ----------------------------------------------

  // submit() with a cache key (see NewJob). request_id idempotency as in submit().
  SubmitOutcome submit_job(const NewJob& job, int64_t now_ms);

  // Inserts a campaign and all its jobs (one per sample, inputs_json[i] for sample i) in one
  // transaction. Idempotent on a non-empty request_id: the same spec_json returns the first
  // campaign (created=false), a different one throws kAlreadyExists.
  CampaignOutcome create_campaign(const std::string& request_id, const std::string& spec_json,
                                  const std::vector<NewJob>& jobs,
                                  const std::vector<std::string>& inputs_json, int64_t now_ms);
  std::optional<CampaignRecord> get_campaign(const std::string& id);
  CampaignPage list_campaigns(int page_size, const std::string& page_token);
  // Every sample, by index, with its job's state, error and result metrics.
  std::vector<CampaignSampleRow> campaign_samples(const std::string& id);
  // Cancels every QUEUED job and requests cancel of every RUNNING one; marks the campaign.
  CampaignRecord cancel_campaign(const std::string& id, int64_t now_ms);
  // FAILED and CANCELLED samples go back to QUEUED with attempts = 0 (event "retry").
  CampaignRecord retry_failed(const std::string& id, int64_t now_ms);

 private:
  // All of these require mu_ (or run in the constructor/destructor, before/after sharing).
  sqlite3_stmt* prepare(const char* sql);  // cached per SQL text
  void close();
  int read_user_version();
  void migrate(const std::string& db_path);
  std::optional<JobRecord> get_locked(const std::string& id);
  JobRecord require_job(const std::string& id);  // kNotFound
  // kNotFound, or kFailedPrecondition unless RUNNING and leased by worker_id.
  JobRecord require_owned_running(const std::string& job_id, const std::string& worker_id,
                                  std::string_view action);
  void append_event(const std::string& job_id, int64_t now_ms, std::string_view kind,
                    const std::string& payload_json);
  // RUNNING -> QUEUED (clears worker, lease, progress and the attempt's artifacts) + event.
  void requeue_locked(const JobRecord& job, int attempts, const std::string& reason,
                      int64_t now_ms);
  // -> a terminal state (clears the lease, sets finished_ms) + event.
  void finish_locked(const JobRecord& job, JobState state, const std::string& error,
                     const std::string& event_payload, int64_t now_ms);
  std::string new_job_id();
  // Inserts one job (QUEUED, or SUCCEEDED from the cache); requires mu_ and a write Txn.
  JobRecord insert_job_locked(const NewJob& job, const std::string& campaign_id, int64_t now_ms);
  std::optional<CampaignRecord> get_campaign_locked(const std::string& id);

  std::mutex mu_;
  // Guarded by mu_: the connection (and every statement prepared on it), the statement cache
  // and the id generator. Every public method takes mu_ for its whole duration.
  sqlite3* db_ = nullptr;
  std::unordered_map<std::string, sqlite3_stmt*> stmts_;
  std::random_device random_;
};

}  // namespace systole::store
