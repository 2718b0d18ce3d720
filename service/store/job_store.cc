#include "service/store/job_store.h"

#include <sqlite3.h>

#include <array>
#include <charconv>
#include <cstdio>
#include <limits>
#include <utility>

#include <nlohmann/json.hpp>

namespace systole::store {

namespace {

using Code = StoreError::Code;
using nlohmann::json;

constexpr int kBusyTimeoutMs = 5000;
// "syst" in ASCII: marks the file as a systole job store (PRAGMA application_id).
constexpr int32_t kApplicationId = 0x73797374;

// ---- schema migrations -------------------------------------------------------------------
// Append-only: never edit a step that has shipped, add a new one. Step N brings the schema from
// version N-1 to N and runs in its own transaction together with `PRAGMA user_version = N`.
struct Migration {
  int version;
  const char* description;
  const char* sql;
};

constexpr Migration kMigrations[] = {
    {1, "jobs, events, results, artifacts", R"sql(
CREATE TABLE jobs (
  id               TEXT    PRIMARY KEY,
  request_id       TEXT,   -- NULL when the client gave none
  scene            TEXT    NOT NULL,
  scenario_json    TEXT    NOT NULL,
  state            TEXT    NOT NULL
                   CHECK (state IN ('QUEUED','RUNNING','SUCCEEDED','FAILED','CANCELLED')),
  priority         INTEGER NOT NULL,
  attempts         INTEGER NOT NULL DEFAULT 0,
  max_attempts     INTEGER NOT NULL,
  cancel_requested INTEGER NOT NULL DEFAULT 0,
  worker_id        TEXT    NOT NULL DEFAULT '',
  error            TEXT    NOT NULL DEFAULT '',
  progress_json    TEXT    NOT NULL DEFAULT '',
  created_ms       INTEGER NOT NULL,
  updated_ms       INTEGER NOT NULL,
  started_ms       INTEGER NOT NULL DEFAULT 0,
  finished_ms      INTEGER NOT NULL DEFAULT 0,
  lease_expires_ms INTEGER NOT NULL DEFAULT 0,
  lease_ms         INTEGER NOT NULL DEFAULT 0   -- length of the current lease, for progress()
);
CREATE UNIQUE INDEX jobs_by_request_id ON jobs (request_id) WHERE request_id IS NOT NULL;
CREATE INDEX jobs_for_lease ON jobs (state, priority DESC, created_ms, id);
CREATE INDEX jobs_by_lease_expiry ON jobs (state, lease_expires_ms);
CREATE INDEX jobs_newest_first ON jobs (created_ms DESC, id);
CREATE INDEX jobs_by_state_newest_first ON jobs (state, created_ms DESC, id);

CREATE TABLE events (
  job_id       TEXT    NOT NULL REFERENCES jobs (id) ON DELETE CASCADE,
  seq          INTEGER NOT NULL,
  time_ms      INTEGER NOT NULL,
  kind         TEXT    NOT NULL,
  payload_json TEXT    NOT NULL,
  PRIMARY KEY (job_id, seq)
) WITHOUT ROWID;

CREATE TABLE results (
  job_id          TEXT    PRIMARY KEY REFERENCES jobs (id) ON DELETE CASCADE,
  metrics_json    TEXT    NOT NULL,
  timeseries_json TEXT    NOT NULL,
  created_ms      INTEGER NOT NULL
);

CREATE TABLE artifacts (
  job_id     TEXT    NOT NULL REFERENCES jobs (id) ON DELETE CASCADE,
  name       TEXT    NOT NULL,
  path       TEXT    NOT NULL,
  sha256     TEXT    NOT NULL,
  size_bytes INTEGER NOT NULL,
  PRIMARY KEY (job_id, name)
) WITHOUT ROWID;
)sql"},
    {2, "result cache and campaigns", R"sql(
ALTER TABLE jobs ADD COLUMN cache_key   TEXT NOT NULL DEFAULT '';
ALTER TABLE jobs ADD COLUMN cached_from TEXT NOT NULL DEFAULT '';
ALTER TABLE jobs ADD COLUMN campaign_id TEXT NOT NULL DEFAULT '';
CREATE INDEX jobs_by_cache_key ON jobs (cache_key, state, finished_ms) WHERE cache_key != '';

CREATE TABLE campaigns (
  id         TEXT    PRIMARY KEY,
  request_id TEXT,
  spec_json  TEXT    NOT NULL,
  cancelled  INTEGER NOT NULL DEFAULT 0,
  created_ms INTEGER NOT NULL,
  updated_ms INTEGER NOT NULL
);
CREATE UNIQUE INDEX campaigns_by_request_id ON campaigns (request_id) WHERE request_id IS NOT NULL;
CREATE INDEX campaigns_newest_first ON campaigns (created_ms DESC, id);

CREATE TABLE campaign_samples (
  campaign_id  TEXT    NOT NULL REFERENCES campaigns (id) ON DELETE CASCADE,
  sample_index INTEGER NOT NULL,
  job_id       TEXT    NOT NULL REFERENCES jobs (id),
  inputs_json  TEXT    NOT NULL,
  PRIMARY KEY (campaign_id, sample_index)
) WITHOUT ROWID;
)sql"},
};

constexpr int kLatestVersion = kMigrations[std::size(kMigrations) - 1].version;

// ---- small SQLite helpers ----------------------------------------------------------------

[[noreturn]] void throw_sqlite(sqlite3* db, int rc, std::string_view what) {
  std::string message = "job store: ";
  message += what;
  message += " failed: ";
  message += sqlite3_errstr(rc);
  if (db != nullptr) {
    message += " (";
    message += sqlite3_errmsg(db);
    message += ")";
  }
  throw StoreError(Code::kInternal, message);
}

// One use of a cached prepared statement: bind, step, read columns; reset on scope exit so the
// statement never holds a read snapshot or stale bindings afterwards.
class Stmt {
 public:
  Stmt(sqlite3* db, sqlite3_stmt* stmt) : db_(db), stmt_(stmt) {}
  ~Stmt() {
    sqlite3_reset(stmt_);
    sqlite3_clear_bindings(stmt_);
  }
  Stmt(const Stmt&) = delete;
  Stmt& operator=(const Stmt&) = delete;

  Stmt& bind_int(int index, int64_t value) {
    check(sqlite3_bind_int64(stmt_, index, value), "bind");
    return *this;
  }
  Stmt& bind_text(int index, std::string_view value) {
    check(sqlite3_bind_text(stmt_, index, value.data(), static_cast<int>(value.size()),
                            SQLITE_TRANSIENT),
          "bind");
    return *this;
  }
  Stmt& bind_null(int index) {
    check(sqlite3_bind_null(stmt_, index), "bind");
    return *this;
  }

  // True while there is a row to read.
  bool step() {
    const int rc = sqlite3_step(stmt_);
    if (rc == SQLITE_ROW) return true;
    if (rc == SQLITE_DONE) return false;
    throw_sqlite(db_, rc, sqlite3_sql(stmt_));
  }
  // For statements that return no rows.
  void run() {
    while (step()) {
    }
  }

  int64_t col_int(int column) const { return sqlite3_column_int64(stmt_, column); }
  std::string col_text(int column) const {
    const auto* text = reinterpret_cast<const char*>(sqlite3_column_text(stmt_, column));
    if (text == nullptr) return {};
    return std::string(text, static_cast<size_t>(sqlite3_column_bytes(stmt_, column)));
  }

 private:
  void check(int rc, std::string_view what) {
    if (rc != SQLITE_OK) throw_sqlite(db_, rc, what);
  }
  sqlite3* db_;
  sqlite3_stmt* stmt_;
};

void exec_sql(sqlite3* db, const char* sql) {
  char* err = nullptr;
  const int rc = sqlite3_exec(db, sql, nullptr, nullptr, &err);
  if (rc != SQLITE_OK) {
    std::string what = std::string("'") + sql + "'";
    if (err != nullptr) {
      what += ": ";
      what += err;
      sqlite3_free(err);
    }
    throw_sqlite(db, rc, what);
  }
}

// BEGIN on construction, ROLLBACK on destruction unless commit() succeeded. Writers use
// IMMEDIATE so that the write lock is taken up front (no deadlock-prone lock upgrade when
// another process shares the file); readers use DEFERRED for one consistent snapshot.
class Txn {
 public:
  enum class Kind { kRead, kWrite };
  Txn(sqlite3* db, Kind kind) : db_(db) {
    exec_sql(db_, kind == Kind::kWrite ? "BEGIN IMMEDIATE" : "BEGIN DEFERRED");
  }
  ~Txn() {
    if (!done_) sqlite3_exec(db_, "ROLLBACK", nullptr, nullptr, nullptr);
  }
  Txn(const Txn&) = delete;
  Txn& operator=(const Txn&) = delete;
  void commit() {
    exec_sql(db_, "COMMIT");
    done_ = true;
  }

 private:
  sqlite3* db_;
  bool done_ = false;
};

// ---- job rows ----------------------------------------------------------------------------

#define SYSTOLE_JOB_COLUMNS                                                               \
  "id, COALESCE(request_id, ''), scene, scenario_json, worker_id, error, state, priority, " \
  "attempts, max_attempts, cancel_requested, created_ms, updated_ms, started_ms, "         \
  "finished_ms, lease_expires_ms, progress_json, cache_key, cached_from, campaign_id"

JobRecord read_job(const Stmt& s) {
  JobRecord job;
  job.id = s.col_text(0);
  job.request_id = s.col_text(1);
  job.scene = s.col_text(2);
  job.scenario_json = s.col_text(3);
  job.worker_id = s.col_text(4);
  job.error = s.col_text(5);
  const std::string state = s.col_text(6);
  const std::optional<JobState> parsed = from_string(state);
  if (!parsed) {
    throw StoreError(Code::kInternal,
                     "job store: job " + job.id + " has an unknown state '" + state + "'");
  }
  job.state = *parsed;
  job.priority = static_cast<int>(s.col_int(7));
  job.attempts = static_cast<int>(s.col_int(8));
  job.max_attempts = static_cast<int>(s.col_int(9));
  job.cancel_requested = s.col_int(10) != 0;
  job.created_ms = s.col_int(11);
  job.updated_ms = s.col_int(12);
  job.started_ms = s.col_int(13);
  job.finished_ms = s.col_int(14);
  job.lease_expires_ms = s.col_int(15);
  job.progress_json = s.col_text(16);
  job.cache_key = s.col_text(17);
  job.cached_from = s.col_text(18);
  job.campaign_id = s.col_text(19);
  return job;
}

std::string state_text(JobState state) { return std::string(to_string(state)); }

std::string dump(const json& value) { return value.dump(); }

// Parses JSON text given by a caller; kInvalidArgument naming the field if it is not JSON.
json parse_json_arg(const std::string& text, std::string_view field) {
  json value = json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (value.is_discarded()) {
    throw StoreError(Code::kInvalidArgument,
                     std::string(field) + " is not valid JSON (" + std::to_string(text.size()) +
                         " bytes)");
  }
  return value;
}

void check_range(std::string_view field, int64_t value, int64_t lo, int64_t hi) {
  if (value < lo || value > hi) {
    throw StoreError(Code::kInvalidArgument, std::string(field) + " = " + std::to_string(value) +
                                                 " is out of range; allowed [" +
                                                 std::to_string(lo) + ", " + std::to_string(hi) +
                                                 "]");
  }
}

[[noreturn]] void throw_not_found(const std::string& id) {
  throw StoreError(Code::kNotFound, "job " + id + " not found");
}

// ---- job ids ------------------------------------------------------------------------------
// "j-" followed by 16 lower-case hex digits (64 random bits).
constexpr std::string_view kJobIdPrefix = "j-";
constexpr size_t kJobIdHexDigits = 16;

bool is_job_id(std::string_view id) {
  return id.size() == kJobIdPrefix.size() + kJobIdHexDigits && id.substr(0, 2) == kJobIdPrefix &&
         id.find_first_not_of("0123456789abcdef", kJobIdPrefix.size()) == std::string_view::npos;
}

// ---- page tokens -------------------------------------------------------------------------
// Opaque to clients: hex of "v1|<filter state or *>|<created_ms>|<id>" of the last job of the
// page. Binding the filter into the token makes a token reused with another filter an error
// instead of a silently wrong page.

std::string hex_encode(std::string_view raw) {
  static constexpr char kDigits[] = "0123456789abcdef";
  std::string out;
  out.reserve(raw.size() * 2);
  for (const char c : raw) {
    const auto byte = static_cast<unsigned char>(c);
    out += kDigits[byte >> 4];
    out += kDigits[byte & 0xF];
  }
  return out;
}

std::optional<std::string> hex_decode(std::string_view hex) {
  if (hex.size() % 2 != 0) return std::nullopt;
  auto nibble = [](char c) -> int {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    return -1;
  };
  std::string out;
  out.reserve(hex.size() / 2);
  for (size_t i = 0; i < hex.size(); i += 2) {
    const int hi = nibble(hex[i]);
    const int lo = nibble(hex[i + 1]);
    if (hi < 0 || lo < 0) return std::nullopt;
    out += static_cast<char>((hi << 4) | lo);
  }
  return out;
}

std::string filter_text(std::optional<JobState> state) {
  return state ? state_text(*state) : std::string("*");
}

std::string make_page_token(std::optional<JobState> filter, const JobRecord& last) {
  return hex_encode("v1|" + filter_text(filter) + "|" + std::to_string(last.created_ms) + "|" +
                    last.id);
}

struct PageCursor {
  int64_t created_ms;
  std::string id;
};

PageCursor parse_page_token(const std::string& token, std::optional<JobState> filter) {
  const auto bad = [&](std::string_view why) {
    return StoreError(Code::kInvalidArgument,
                      "invalid page_token '" + token.substr(0, 64) + "': " + std::string(why));
  };
  const std::optional<std::string> raw = hex_decode(token);
  if (!raw) throw bad("not a token returned by list()");
  std::vector<std::string_view> parts;
  std::string_view rest = *raw;
  for (size_t pos; (pos = rest.find('|')) != std::string_view::npos;) {
    parts.push_back(rest.substr(0, pos));
    rest.remove_prefix(pos + 1);
  }
  parts.push_back(rest);
  if (parts.size() != 4 || parts[0] != "v1" || !is_job_id(parts[3])) {
    throw bad("not a token returned by list()");
  }
  if (parts[1] != filter_text(filter)) {
    throw bad("it was issued for state filter " + std::string(parts[1]) + ", not " +
              filter_text(filter));
  }
  PageCursor cursor{0, std::string(parts[3])};
  const auto [end, ec] =
      std::from_chars(parts[2].data(), parts[2].data() + parts[2].size(), cursor.created_ms);
  if (ec != std::errc() || end != parts[2].data() + parts[2].size() || cursor.created_ms < 0) {
    throw bad("not a token returned by list()");
  }
  return cursor;
}

}  // namespace

// ---- JobState ----------------------------------------------------------------------------

std::string_view to_string(JobState state) {
  switch (state) {
    case JobState::kQueued:
      return "QUEUED";
    case JobState::kRunning:
      return "RUNNING";
    case JobState::kSucceeded:
      return "SUCCEEDED";
    case JobState::kFailed:
      return "FAILED";
    case JobState::kCancelled:
      return "CANCELLED";
  }
  return "UNKNOWN";
}

std::optional<JobState> from_string(std::string_view text) {
  for (const JobState state : {JobState::kQueued, JobState::kRunning, JobState::kSucceeded,
                               JobState::kFailed, JobState::kCancelled}) {
    if (to_string(state) == text) return state;
  }
  return std::nullopt;
}

bool is_terminal(JobState state) {
  return state == JobState::kSucceeded || state == JobState::kFailed ||
         state == JobState::kCancelled;
}

// ---- construction and migrations ---------------------------------------------------------

JobStore::JobStore(const std::string& db_path) {
  const int rc = sqlite3_open_v2(db_path.c_str(), &db_,
                                 SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_NOMUTEX,
                                 nullptr);
  if (rc != SQLITE_OK) {
    std::string message = "job store: cannot open '" + db_path + "': " + sqlite3_errstr(rc);
    if (db_ != nullptr) {
      message += std::string(" (") + sqlite3_errmsg(db_) + ")";
      sqlite3_close_v2(db_);
      db_ = nullptr;
    }
    throw StoreError(Code::kInternal, message);
  }
  try {
    sqlite3_extended_result_codes(db_, 1);
    sqlite3_busy_timeout(db_, kBusyTimeoutMs);
    std::string mode;
    {
      Stmt s(db_, prepare("PRAGMA journal_mode=WAL"));
      if (s.step()) mode = s.col_text(0);
    }
    if (mode != "wal" && db_path != ":memory:") {
      throw StoreError(Code::kInternal, "job store: cannot enable WAL on '" + db_path +
                                            "' (journal_mode is '" + mode + "')");
    }
    exec_sql(db_, "PRAGMA synchronous=FULL");
    exec_sql(db_, "PRAGMA foreign_keys=ON");
    migrate(db_path);
  } catch (...) {
    close();
    throw;
  }
}

JobStore::~JobStore() { close(); }

void JobStore::close() {
  for (auto& [sql, stmt] : stmts_) sqlite3_finalize(stmt);
  stmts_.clear();
  if (db_ != nullptr) sqlite3_close_v2(db_);
  db_ = nullptr;
}

int JobStore::schema_version() { return kLatestVersion; }

int JobStore::read_user_version() {
  Stmt s(db_, prepare("PRAGMA user_version"));
  return s.step() ? static_cast<int>(s.col_int(0)) : 0;
}

void JobStore::migrate(const std::string& db_path) {
  const auto too_new = [&](int version) {
    return StoreError(Code::kFailedPrecondition,
                      "job store '" + db_path + "' has schema version " +
                          std::to_string(version) + " but this systole only knows versions up to " +
                          std::to_string(kLatestVersion) +
                          "; it was written by a newer systole (upgrade, or use another file)");
  };
  for (const Migration& step : kMigrations) {
    // Cheap check outside a transaction first, so that opening an up-to-date store never
    // takes the write lock.
    const int seen = read_user_version();
    if (seen > kLatestVersion) throw too_new(seen);
    if (seen >= step.version) continue;

    Txn txn(db_, Txn::Kind::kWrite);
    // Re-read under the write lock: another process may have migrated in the meantime.
    const int version = read_user_version();
    if (version > kLatestVersion) throw too_new(version);
    if (version >= step.version) continue;
    if (version == 0) {
      Stmt s(db_, prepare("SELECT COUNT(*) FROM sqlite_schema"));
      if (s.step() && s.col_int(0) != 0) {
        throw StoreError(Code::kFailedPrecondition,
                         "'" + db_path + "' is a SQLite database but not a systole job store");
      }
    } else {
      Stmt s(db_, prepare("PRAGMA application_id"));
      if (s.step() && s.col_int(0) != kApplicationId) {
        throw StoreError(Code::kFailedPrecondition,
                         "'" + db_path + "' is a SQLite database but not a systole job store");
      }
    }
    if (version != step.version - 1) {
      throw StoreError(Code::kInternal, "job store '" + db_path + "': no migration from version " +
                                            std::to_string(version) + " to " +
                                            std::to_string(step.version));
    }
    exec_sql(db_, step.sql);
    // PRAGMAs take no bound parameters; the values are compile-time integers, not user input.
    const std::string set_version = "PRAGMA user_version = " + std::to_string(step.version);
    exec_sql(db_, set_version.c_str());
    if (step.version == 1) {
      const std::string set_app = "PRAGMA application_id = " + std::to_string(kApplicationId);
      exec_sql(db_, set_app.c_str());
    }
    txn.commit();
  }
}

// ---- internals (all require mu_) ---------------------------------------------------------

sqlite3_stmt* JobStore::prepare(const char* sql) {
  const auto it = stmts_.find(sql);
  if (it != stmts_.end()) return it->second;
  sqlite3_stmt* stmt = nullptr;
  const int rc = sqlite3_prepare_v3(db_, sql, -1, SQLITE_PREPARE_PERSISTENT, &stmt, nullptr);
  if (rc != SQLITE_OK) throw_sqlite(db_, rc, std::string("prepare '") + sql + "'");
  stmts_.emplace(sql, stmt);
  return stmt;
}

std::optional<JobRecord> JobStore::get_locked(const std::string& id) {
  Stmt s(db_, prepare("SELECT " SYSTOLE_JOB_COLUMNS " FROM jobs WHERE id = ?1"));
  s.bind_text(1, id);
  if (!s.step()) return std::nullopt;
  return read_job(s);
}

JobRecord JobStore::require_job(const std::string& id) {
  std::optional<JobRecord> job = get_locked(id);
  if (!job) throw_not_found(id);
  return std::move(*job);
}

JobRecord JobStore::require_owned_running(const std::string& job_id, const std::string& worker_id,
                                          std::string_view action) {
  JobRecord job = require_job(job_id);
  if (job.state != JobState::kRunning) {
    throw StoreError(Code::kFailedPrecondition,
                     "job " + job_id + " is " + state_text(job.state) + "; only a RUNNING job can " +
                         std::string(action));
  }
  if (job.worker_id != worker_id) {
    throw StoreError(Code::kFailedPrecondition,
                     "job " + job_id + " is leased by worker '" + job.worker_id + "', not '" +
                         worker_id + "'; only the lease owner can " + std::string(action));
  }
  return job;
}

void JobStore::append_event(const std::string& job_id, int64_t now_ms, std::string_view kind,
                            const std::string& payload_json) {
  // The next per-job sequence number comes from the (job_id, seq) primary key; we hold the
  // write lock, so nobody can take the same number.
  Stmt s(db_, prepare("INSERT INTO events (job_id, seq, time_ms, kind, payload_json) "
                      "SELECT ?1, COALESCE(MAX(seq), 0) + 1, ?2, ?3, ?4 "
                      "FROM events WHERE job_id = ?1"));
  s.bind_text(1, job_id).bind_int(2, now_ms).bind_text(3, kind).bind_text(4, payload_json);
  s.run();
}

void JobStore::requeue_locked(const JobRecord& job, int attempts, const std::string& reason,
                              int64_t now_ms) {
  {
    Stmt s(db_, prepare("UPDATE jobs SET state = 'QUEUED', worker_id = '', lease_expires_ms = 0, "
                        "lease_ms = 0, progress_json = '', attempts = ?2, updated_ms = ?3 "
                        "WHERE id = ?1"));
    s.bind_text(1, job.id).bind_int(2, attempts).bind_int(3, now_ms);
    s.run();
  }
  {
    // Artifacts belong to the attempt that completes; drop those of the abandoned attempt.
    Stmt s(db_, prepare("DELETE FROM artifacts WHERE job_id = ?1"));
    s.bind_text(1, job.id);
    s.run();
  }
  append_event(job.id, now_ms, "state", dump({{"state", "QUEUED"}, {"reason", reason}}));
}

void JobStore::finish_locked(const JobRecord& job, JobState state, const std::string& error,
                             const std::string& event_payload, int64_t now_ms) {
  {
    Stmt s(db_, prepare("UPDATE jobs SET state = ?2, error = ?3, finished_ms = ?4, "
                        "lease_expires_ms = 0, lease_ms = 0, updated_ms = ?4 WHERE id = ?1"));
    s.bind_text(1, job.id).bind_text(2, to_string(state)).bind_text(3, error).bind_int(4, now_ms);
    s.run();
  }
  append_event(job.id, now_ms, "state", event_payload);
}

std::string JobStore::new_job_id() {
  for (;;) {
    const uint64_t value = (static_cast<uint64_t>(random_()) << 32) ^ random_();
    std::array<char, kJobIdHexDigits + 1> hex{};
    std::snprintf(hex.data(), hex.size(), "%016llx", static_cast<unsigned long long>(value));
    std::string id = std::string(kJobIdPrefix) + std::string(hex.data(), kJobIdHexDigits);
    if (!get_locked(id)) return id;  // 64 random bits: a collision is astronomically rare
  }
}

// ---- public API --------------------------------------------------------------------------

SubmitOutcome JobStore::submit(const std::string& request_id, const std::string& scene,
                               const std::string& scenario_json, int priority, int max_attempts,
                               int64_t now_ms) {
  NewJob job;
  job.request_id = request_id;
  job.scene = scene;
  job.scenario_json = scenario_json;
  job.priority = priority;
  job.max_attempts = max_attempts;
  return submit_job(job, now_ms);
}

namespace {
void validate_new_job(const NewJob& job) {
  check_range("priority", job.priority, JobStore::kMinPriority, JobStore::kMaxPriority);
  check_range("max_attempts", job.max_attempts, JobStore::kMinMaxAttempts, JobStore::kMaxMaxAttempts);
  if (job.scene.empty()) throw StoreError(Code::kInvalidArgument, "scene must not be empty");
  (void)parse_json_arg(job.scenario_json, "scenario_json");
}
}  // namespace

SubmitOutcome JobStore::submit_job(const NewJob& new_job, int64_t now_ms) {
  validate_new_job(new_job);
  const json scenario = json::parse(new_job.scenario_json);
  const std::string& request_id = new_job.request_id;
  const std::string& scene = new_job.scene;
  const int priority = new_job.priority;

  std::lock_guard lock(mu_);
  Txn txn(db_, Txn::Kind::kWrite);
  if (!request_id.empty()) {
    std::optional<JobRecord> existing;
    {
      Stmt s(db_, prepare("SELECT " SYSTOLE_JOB_COLUMNS " FROM jobs WHERE request_id = ?1"));
      s.bind_text(1, request_id);
      if (s.step()) existing = read_job(s);
    }
    if (existing) {
      std::vector<std::string> differences;
      if (existing->scene != scene) {
        differences.push_back("scene ('" + existing->scene + "' vs '" + scene + "')");
      }
      if (existing->priority != priority) {
        differences.push_back("priority (" + std::to_string(existing->priority) + " vs " +
                              std::to_string(priority) + ")");
      }
      if (json::parse(existing->scenario_json) != scenario) differences.push_back("scenario");
      if (!differences.empty()) {
        std::string what;
        for (size_t i = 0; i < differences.size(); ++i) {
          if (i > 0) what += i + 1 == differences.size() ? " and " : ", ";
          what += differences[i];
        }
        throw StoreError(Code::kAlreadyExists, "request_id '" + request_id +
                                                   "' was already used for job " + existing->id +
                                                   " with a different " + what);
      }
      return SubmitOutcome{std::move(*existing), false};
    }
  }
  JobRecord job = insert_job_locked(new_job, "", now_ms);
  txn.commit();
  return SubmitOutcome{std::move(job), true};
}

JobRecord JobStore::insert_job_locked(const NewJob& new_job, const std::string& campaign_id,
                                      int64_t now_ms) {
  std::string cached_from;
  if (!new_job.cache_key.empty()) {
    Stmt s(db_, prepare("SELECT j.id FROM jobs j JOIN results r ON r.job_id = j.id "
                        "WHERE j.cache_key = ?1 AND j.state = 'SUCCEEDED' "
                        "ORDER BY j.finished_ms, j.id LIMIT 1"));
    s.bind_text(1, new_job.cache_key);
    if (s.step()) cached_from = s.col_text(0);
  }
  const std::string id = new_job_id();
  {
    Stmt s(db_, prepare("INSERT INTO jobs (id, request_id, scene, scenario_json, state, priority, "
                        "max_attempts, created_ms, updated_ms, cache_key, campaign_id) "
                        "VALUES (?1, ?2, ?3, ?4, 'QUEUED', ?5, ?6, ?7, ?7, ?8, ?9)"));
    s.bind_text(1, id);
    if (new_job.request_id.empty()) {
      s.bind_null(2);
    } else {
      s.bind_text(2, new_job.request_id);
    }
    s.bind_text(3, new_job.scene).bind_text(4, new_job.scenario_json).bind_int(5, new_job.priority);
    s.bind_int(6, new_job.max_attempts).bind_int(7, now_ms);
    s.bind_text(8, new_job.cache_key).bind_text(9, campaign_id);
    s.run();
  }
  append_event(id, now_ms, "state", dump({{"state", "QUEUED"}}));
  if (!cached_from.empty()) {
    // Reuse: the result row and the artifact index are copied (the files are shared and are
    // never deleted while indexed).
    {
      Stmt s(db_, prepare("INSERT INTO results (job_id, metrics_json, timeseries_json, created_ms) "
                          "SELECT ?1, metrics_json, timeseries_json, ?3 FROM results WHERE job_id = ?2"));
      s.bind_text(1, id).bind_text(2, cached_from).bind_int(3, now_ms);
      s.run();
    }
    {
      Stmt s(db_, prepare("INSERT INTO artifacts (job_id, name, path, sha256, size_bytes) "
                          "SELECT ?1, name, path, sha256, size_bytes FROM artifacts WHERE job_id = ?2"));
      s.bind_text(1, id).bind_text(2, cached_from);
      s.run();
    }
    {
      Stmt s(db_, prepare("UPDATE jobs SET state = 'SUCCEEDED', cached_from = ?2, started_ms = ?3, "
                          "finished_ms = ?3, updated_ms = ?3 WHERE id = ?1"));
      s.bind_text(1, id).bind_text(2, cached_from).bind_int(3, now_ms);
      s.run();
    }
    append_event(id, now_ms, "state",
                 dump({{"state", "SUCCEEDED"},
                       {"cached_from", cached_from},
                       {"reason", "result reused from job " + cached_from +
                                      " (same canonical scenario and solver version)"}}));
  }
  return require_job(id);
}

std::optional<JobRecord> JobStore::get(const std::string& id) {
  std::lock_guard lock(mu_);
  return get_locked(id);
}

ListPage JobStore::list(std::optional<JobState> state, int page_size,
                        const std::string& page_token) {
  if (page_size == 0) page_size = kDefaultPageSize;
  check_range("page_size", page_size, 1, kMaxPageSize);
  std::optional<PageCursor> cursor;
  if (!page_token.empty()) cursor = parse_page_token(page_token, state);

  // Four spellings so that each one can walk its index (no "?1 IS NULL OR ..." predicates).
  const char* sql = nullptr;
  if (state && cursor) {
    sql = "SELECT " SYSTOLE_JOB_COLUMNS " FROM jobs WHERE state = ?1 AND "
          "(created_ms < ?2 OR (created_ms = ?2 AND id > ?3)) "
          "ORDER BY created_ms DESC, id LIMIT ?4";
  } else if (state) {
    sql = "SELECT " SYSTOLE_JOB_COLUMNS " FROM jobs WHERE state = ?1 "
          "ORDER BY created_ms DESC, id LIMIT ?4";
  } else if (cursor) {
    sql = "SELECT " SYSTOLE_JOB_COLUMNS " FROM jobs WHERE "
          "(created_ms < ?2 OR (created_ms = ?2 AND id > ?3)) "
          "ORDER BY created_ms DESC, id LIMIT ?4";
  } else {
    sql = "SELECT " SYSTOLE_JOB_COLUMNS " FROM jobs ORDER BY created_ms DESC, id LIMIT ?4";
  }

  std::lock_guard lock(mu_);
  ListPage page;
  Stmt s(db_, prepare(sql));
  if (state) s.bind_text(1, to_string(*state));
  if (cursor) s.bind_int(2, cursor->created_ms).bind_text(3, cursor->id);
  s.bind_int(4, page_size + 1);  // one extra row tells whether there is a next page
  while (s.step()) page.jobs.push_back(read_job(s));
  if (page.jobs.size() > static_cast<size_t>(page_size)) {
    page.jobs.pop_back();
    page.next_page_token = make_page_token(state, page.jobs.back());
  }
  return page;
}

JobRecord JobStore::cancel(const std::string& id, int64_t now_ms) {
  std::lock_guard lock(mu_);
  Txn txn(db_, Txn::Kind::kWrite);
  JobRecord job = require_job(id);
  switch (job.state) {
    case JobState::kQueued:
      finish_locked(job, JobState::kCancelled, "", dump({{"state", "CANCELLED"}}), now_ms);
      break;
    case JobState::kRunning:
      if (job.cancel_requested) return job;  // already asked; nothing to write
      {
        Stmt s(db_, prepare("UPDATE jobs SET cancel_requested = 1, updated_ms = ?2 WHERE id = ?1"));
        s.bind_text(1, id).bind_int(2, now_ms);
        s.run();
      }
      append_event(id, now_ms, "cancel_requested", dump({{"worker", job.worker_id}}));
      break;
    case JobState::kSucceeded:
    case JobState::kFailed:
    case JobState::kCancelled:
      throw StoreError(Code::kFailedPrecondition,
                       "job " + id + " is " + state_text(job.state) +
                           "; only QUEUED or RUNNING jobs can be cancelled");
  }
  job = require_job(id);
  txn.commit();
  return job;
}

std::optional<Lease> JobStore::lease(const std::string& worker_id, int64_t lease_ms,
                                     int64_t now_ms) {
  if (worker_id.empty()) throw StoreError(Code::kInvalidArgument, "worker_id must not be empty");
  check_range("lease_ms", lease_ms, 1, JobStore::kMaxLeaseMs);

  std::lock_guard lock(mu_);
  Txn txn(db_, Txn::Kind::kWrite);
  std::string id;
  {
    Stmt s(db_, prepare("SELECT id FROM jobs WHERE state = 'QUEUED' "
                        "ORDER BY priority DESC, created_ms, id LIMIT 1"));
    if (!s.step()) return std::nullopt;  // rollback of an empty transaction
    id = s.col_text(0);
  }
  {
    Stmt s(db_, prepare("UPDATE jobs SET state = 'RUNNING', worker_id = ?2, "
                        "attempts = attempts + 1, "
                        "started_ms = CASE WHEN started_ms = 0 THEN ?3 ELSE started_ms END, "
                        "lease_expires_ms = ?3 + ?4, lease_ms = ?4, updated_ms = ?3 "
                        "WHERE id = ?1"));
    s.bind_text(1, id).bind_text(2, worker_id).bind_int(3, now_ms).bind_int(4, lease_ms);
    s.run();
  }
  JobRecord job = require_job(id);
  append_event(id, now_ms, "state",
               dump({{"state", "RUNNING"}, {"worker", worker_id}, {"attempt", job.attempts}}));
  txn.commit();
  return Lease{std::move(job)};
}

HeartbeatAnswer JobStore::heartbeat(const std::string& job_id, const std::string& worker_id,
                                    int64_t lease_ms, int64_t now_ms) {
  check_range("lease_ms", lease_ms, 1, JobStore::kMaxLeaseMs);
  std::lock_guard lock(mu_);
  Txn txn(db_, Txn::Kind::kWrite);
  const std::optional<JobRecord> job = get_locked(job_id);
  if (!job) return HeartbeatAnswer{false, false};
  if (job->state != JobState::kRunning || job->worker_id != worker_id) {
    return HeartbeatAnswer{false, job->cancel_requested || job->state == JobState::kCancelled};
  }
  {
    Stmt s(db_, prepare("UPDATE jobs SET lease_expires_ms = ?2 + ?3, lease_ms = ?3, "
                        "updated_ms = ?2 WHERE id = ?1"));
    s.bind_text(1, job_id).bind_int(2, now_ms).bind_int(3, lease_ms);
    s.run();
  }
  txn.commit();
  return HeartbeatAnswer{true, job->cancel_requested};
}

void JobStore::progress(const std::string& job_id, const std::string& worker_id,
                        const std::string& payload_json, int64_t now_ms) {
  parse_json_arg(payload_json, "progress payload_json");
  std::lock_guard lock(mu_);
  Txn txn(db_, Txn::Kind::kWrite);
  require_owned_running(job_id, worker_id, "report progress");
  {
    Stmt s(db_, prepare("UPDATE jobs SET progress_json = ?2, lease_expires_ms = ?3 + lease_ms, "
                        "updated_ms = ?3 WHERE id = ?1"));
    s.bind_text(1, job_id).bind_text(2, payload_json).bind_int(3, now_ms);
    s.run();
  }
  append_event(job_id, now_ms, "progress", payload_json);
  txn.commit();
}

void JobStore::add_artifact(const std::string& job_id, const std::string& worker_id,
                            const Artifact& artifact) {
  if (artifact.name.empty()) {
    throw StoreError(Code::kInvalidArgument, "artifact name must not be empty");
  }
  if (artifact.path.empty()) {
    throw StoreError(Code::kInvalidArgument,
                     "artifact '" + artifact.name + "' has an empty path");
  }
  check_range("artifact size_bytes", artifact.size_bytes, 0,
              std::numeric_limits<int64_t>::max());
  std::lock_guard lock(mu_);
  Txn txn(db_, Txn::Kind::kWrite);
  require_owned_running(job_id, worker_id, "add artifacts");
  {
    Stmt s(db_, prepare("INSERT INTO artifacts (job_id, name, path, sha256, size_bytes) "
                        "VALUES (?1, ?2, ?3, ?4, ?5) ON CONFLICT (job_id, name) DO UPDATE SET "
                        "path = excluded.path, sha256 = excluded.sha256, "
                        "size_bytes = excluded.size_bytes"));
    s.bind_text(1, job_id).bind_text(2, artifact.name).bind_text(3, artifact.path);
    s.bind_text(4, artifact.sha256).bind_int(5, artifact.size_bytes);
    s.run();
  }
  txn.commit();
}

JobRecord JobStore::complete(const std::string& job_id, const std::string& worker_id,
                             const std::string& metrics_json, const std::string& timeseries_json,
                             int64_t now_ms) {
  if (!metrics_json.empty()) parse_json_arg(metrics_json, "metrics_json");
  if (!timeseries_json.empty()) parse_json_arg(timeseries_json, "timeseries_json");
  std::lock_guard lock(mu_);
  Txn txn(db_, Txn::Kind::kWrite);
  const JobRecord job = require_owned_running(job_id, worker_id, "be completed");
  {
    Stmt s(db_, prepare("INSERT INTO results (job_id, metrics_json, timeseries_json, created_ms) "
                        "VALUES (?1, ?2, ?3, ?4)"));
    s.bind_text(1, job_id).bind_text(2, metrics_json).bind_text(3, timeseries_json);
    s.bind_int(4, now_ms);
    s.run();
  }
  finish_locked(job, JobState::kSucceeded, "", dump({{"state", "SUCCEEDED"}}), now_ms);
  JobRecord done = require_job(job_id);
  txn.commit();
  return done;
}

JobRecord JobStore::fail(const std::string& job_id, const std::string& worker_id,
                         const std::string& error, bool retryable, int64_t now_ms) {
  const std::string message = error.empty() ? "(the worker gave no error message)" : error;
  std::lock_guard lock(mu_);
  Txn txn(db_, Txn::Kind::kWrite);
  const JobRecord job = require_owned_running(job_id, worker_id, "fail");
  if (retryable && job.attempts < job.max_attempts) {
    if (job.cancel_requested) {
      finish_locked(job, JobState::kCancelled, "",
                    dump({{"state", "CANCELLED"}, {"reason", message}}), now_ms);
    } else {
      requeue_locked(job, job.attempts, message, now_ms);
    }
  } else {
    finish_locked(job, JobState::kFailed, message,
                  dump({{"state", "FAILED"}, {"error", message}, {"attempts", job.attempts}}),
                  now_ms);
  }
  JobRecord after = require_job(job_id);
  txn.commit();
  return after;
}

JobRecord JobStore::acknowledge_cancel(const std::string& job_id, const std::string& worker_id,
                                       int64_t now_ms) {
  std::lock_guard lock(mu_);
  Txn txn(db_, Txn::Kind::kWrite);
  const JobRecord job = require_owned_running(job_id, worker_id, "acknowledge a cancel");
  if (!job.cancel_requested) {
    throw StoreError(Code::kFailedPrecondition,
                     "job " + job_id + " is RUNNING with no cancel request to acknowledge");
  }
  finish_locked(job, JobState::kCancelled, "", dump({{"state", "CANCELLED"}}), now_ms);
  JobRecord after = require_job(job_id);
  txn.commit();
  return after;
}

JobRecord JobStore::release(const std::string& job_id, const std::string& worker_id,
                            int64_t now_ms) {
  std::lock_guard lock(mu_);
  Txn txn(db_, Txn::Kind::kWrite);
  const JobRecord job = require_owned_running(job_id, worker_id, "be released");
  const std::string reason = "released by worker " + worker_id;
  if (job.cancel_requested) {
    finish_locked(job, JobState::kCancelled, "", dump({{"state", "CANCELLED"}, {"reason", reason}}),
                  now_ms);
  } else {
    requeue_locked(job, job.attempts - 1, reason, now_ms);
  }
  JobRecord after = require_job(job_id);
  txn.commit();
  return after;
}

std::vector<std::string> JobStore::requeue_expired(int64_t now_ms) {
  std::lock_guard lock(mu_);
  Txn txn(db_, Txn::Kind::kWrite);
  std::vector<JobRecord> expired;
  {
    Stmt s(db_, prepare("SELECT " SYSTOLE_JOB_COLUMNS " FROM jobs "
                        "WHERE state = 'RUNNING' AND lease_expires_ms < ?1 ORDER BY id"));
    s.bind_int(1, now_ms);
    while (s.step()) expired.push_back(read_job(s));
  }
  std::vector<std::string> ids;
  ids.reserve(expired.size());
  for (const JobRecord& job : expired) {
    const std::string reason = "lease expired (worker " + job.worker_id + " lost)";
    if (job.cancel_requested) {
      finish_locked(job, JobState::kCancelled, "",
                    dump({{"state", "CANCELLED"}, {"reason", reason}}), now_ms);
    } else if (job.attempts < job.max_attempts) {
      requeue_locked(job, job.attempts, reason, now_ms);
    } else {
      const std::string error = "lease expired after " + std::to_string(job.attempts) +
                                (job.attempts == 1 ? " attempt" : " attempts");
      finish_locked(job, JobState::kFailed, error,
                    dump({{"state", "FAILED"}, {"error", error}, {"attempts", job.attempts}}),
                    now_ms);
    }
    ids.push_back(job.id);
  }
  txn.commit();
  return ids;
}

std::optional<ResultRecord> JobStore::result(const std::string& job_id) {
  std::lock_guard lock(mu_);
  Txn txn(db_, Txn::Kind::kRead);
  ResultRecord result;
  {
    Stmt s(db_, prepare("SELECT job_id, metrics_json, timeseries_json, created_ms FROM results "
                        "WHERE job_id = ?1"));
    s.bind_text(1, job_id);
    if (!s.step()) return std::nullopt;
    result.job_id = s.col_text(0);
    result.metrics_json = s.col_text(1);
    result.timeseries_json = s.col_text(2);
    result.created_ms = s.col_int(3);
  }
  {
    Stmt s(db_, prepare("SELECT name, path, sha256, size_bytes FROM artifacts "
                        "WHERE job_id = ?1 ORDER BY name"));
    s.bind_text(1, job_id);
    while (s.step()) {
      result.artifacts.push_back(Artifact{s.col_text(0), s.col_text(1), s.col_text(2),
                                          s.col_int(3)});
    }
  }
  txn.commit();
  return result;
}

std::vector<Event> JobStore::events(const std::string& job_id, int64_t after_seq, int limit) {
  if (limit == 0) limit = kDefaultPageSize;
  check_range("limit", limit, 1, kMaxPageSize);
  check_range("after_seq", after_seq, 0, std::numeric_limits<int64_t>::max());
  std::lock_guard lock(mu_);
  Txn txn(db_, Txn::Kind::kRead);
  require_job(job_id);
  std::vector<Event> out;
  {
    Stmt s(db_, prepare("SELECT seq, time_ms, kind, payload_json FROM events "
                        "WHERE job_id = ?1 AND seq > ?2 ORDER BY seq LIMIT ?3"));
    s.bind_text(1, job_id).bind_int(2, after_seq).bind_int(3, limit);
    while (s.step()) {
      out.push_back(Event{s.col_int(0), job_id, s.col_int(1), s.col_text(2), s.col_text(3)});
    }
  }
  txn.commit();
  return out;
}

// ---- campaigns ---------------------------------------------------------------------------

std::optional<CampaignRecord> JobStore::get_campaign_locked(const std::string& id) {
  CampaignRecord c;
  {
    Stmt s(db_, prepare("SELECT id, COALESCE(request_id, ''), spec_json, cancelled, created_ms "
                        "FROM campaigns WHERE id = ?1"));
    s.bind_text(1, id);
    if (!s.step()) return std::nullopt;
    c.id = s.col_text(0);
    c.request_id = s.col_text(1);
    c.spec_json = s.col_text(2);
    c.cancelled = s.col_int(3) != 0;
    c.created_ms = s.col_int(4);
  }
  {
    Stmt s(db_, prepare("SELECT j.state, COUNT(*), SUM(j.cached_from != '') FROM campaign_samples c "
                        "JOIN jobs j ON j.id = c.job_id WHERE c.campaign_id = ?1 GROUP BY j.state"));
    s.bind_text(1, id);
    while (s.step()) {
      const auto state = from_string(s.col_text(0));
      if (!state) continue;
      c.jobs_by_state.emplace_back(*state, s.col_int(1));
      c.jobs_total += s.col_int(1);
      c.jobs_cached += s.col_int(2);
    }
  }
  return c;
}

CampaignOutcome JobStore::create_campaign(const std::string& request_id, const std::string& spec_json,
                                          const std::vector<NewJob>& jobs,
                                          const std::vector<std::string>& inputs_json, int64_t now_ms) {
  const json spec = parse_json_arg(spec_json, "spec_json");
  if (jobs.empty()) throw StoreError(Code::kInvalidArgument, "a campaign needs at least one job");
  if (jobs.size() != inputs_json.size())
    throw StoreError(Code::kInvalidArgument, "jobs and inputs_json differ in length");
  for (const NewJob& job : jobs) validate_new_job(job);
  for (const auto& inputs : inputs_json) (void)parse_json_arg(inputs, "inputs_json");

  std::lock_guard lock(mu_);
  Txn txn(db_, Txn::Kind::kWrite);
  if (!request_id.empty()) {
    std::string existing_id, existing_spec;
    {
      Stmt s(db_, prepare("SELECT id, spec_json FROM campaigns WHERE request_id = ?1"));
      s.bind_text(1, request_id);
      if (s.step()) {
        existing_id = s.col_text(0);
        existing_spec = s.col_text(1);
      }
    }
    if (!existing_id.empty()) {
      if (json::parse(existing_spec) != spec)
        throw StoreError(Code::kAlreadyExists, "request_id '" + request_id +
                                                   "' was already used for campaign " + existing_id +
                                                   " with a different spec");
      return CampaignOutcome{*get_campaign_locked(existing_id), false};
    }
  }
  std::string id = "c" + new_job_id().substr(1);  // "c-" + 16 hex digits
  {
    Stmt s(db_, prepare("INSERT INTO campaigns (id, request_id, spec_json, created_ms, updated_ms) "
                        "VALUES (?1, ?2, ?3, ?4, ?4)"));
    s.bind_text(1, id);
    if (request_id.empty()) {
      s.bind_null(2);
    } else {
      s.bind_text(2, request_id);
    }
    s.bind_text(3, spec_json).bind_int(4, now_ms);
    s.run();
  }
  for (size_t i = 0; i < jobs.size(); ++i) {
    NewJob job = jobs[i];
    job.request_id.clear();
    const JobRecord inserted = insert_job_locked(job, id, now_ms);
    Stmt s(db_, prepare("INSERT INTO campaign_samples (campaign_id, sample_index, job_id, inputs_json) "
                        "VALUES (?1, ?2, ?3, ?4)"));
    s.bind_text(1, id).bind_int(2, static_cast<int64_t>(i)).bind_text(3, inserted.id).bind_text(4, inputs_json[i]);
    s.run();
  }
  CampaignRecord record = *get_campaign_locked(id);
  txn.commit();
  return CampaignOutcome{std::move(record), true};
}

std::optional<CampaignRecord> JobStore::get_campaign(const std::string& id) {
  std::lock_guard lock(mu_);
  Txn txn(db_, Txn::Kind::kRead);
  auto c = get_campaign_locked(id);
  txn.commit();
  return c;
}

CampaignPage JobStore::list_campaigns(int page_size, const std::string& page_token) {
  if (page_size == 0) page_size = kDefaultPageSize;
  check_range("page_size", page_size, 1, kMaxPageSize);
  int64_t offset = 0;
  if (!page_token.empty()) {
    const auto [ptr, ec] = std::from_chars(page_token.data(), page_token.data() + page_token.size(), offset);
    if (ec != std::errc() || ptr != page_token.data() + page_token.size() || offset < 0)
      throw StoreError(Code::kInvalidArgument, "page_token '" + page_token + "' is not a token from list_campaigns");
  }
  std::lock_guard lock(mu_);
  Txn txn(db_, Txn::Kind::kRead);
  std::vector<std::string> ids;
  {
    Stmt s(db_, prepare("SELECT id FROM campaigns ORDER BY created_ms DESC, id LIMIT ?1 OFFSET ?2"));
    s.bind_int(1, page_size + 1).bind_int(2, offset);
    while (s.step()) ids.push_back(s.col_text(0));
  }
  CampaignPage page;
  const bool more = ids.size() > static_cast<size_t>(page_size);
  if (more) ids.pop_back();
  for (const auto& id : ids) page.campaigns.push_back(*get_campaign_locked(id));
  if (more) page.next_page_token = std::to_string(offset + page_size);
  txn.commit();
  return page;
}

std::vector<CampaignSampleRow> JobStore::campaign_samples(const std::string& id) {
  std::lock_guard lock(mu_);
  Txn txn(db_, Txn::Kind::kRead);
  if (!get_campaign_locked(id)) throw StoreError(Code::kNotFound, "campaign " + id + " not found");
  std::vector<CampaignSampleRow> rows;
  {
    Stmt s(db_, prepare("SELECT c.sample_index, c.job_id, c.inputs_json, j.state, j.error, j.cached_from, "
                        "COALESCE(r.metrics_json, '') FROM campaign_samples c JOIN jobs j ON j.id = c.job_id "
                        "LEFT JOIN results r ON r.job_id = c.job_id WHERE c.campaign_id = ?1 "
                        "ORDER BY c.sample_index"));
    s.bind_text(1, id);
    while (s.step()) {
      CampaignSampleRow row;
      row.index = s.col_int(0);
      row.job_id = s.col_text(1);
      row.inputs_json = s.col_text(2);
      row.state = from_string(s.col_text(3)).value_or(JobState::kFailed);
      row.error = s.col_text(4);
      row.cached_from = s.col_text(5);
      row.metrics_json = s.col_text(6);
      rows.push_back(std::move(row));
    }
  }
  txn.commit();
  return rows;
}

CampaignRecord JobStore::cancel_campaign(const std::string& id, int64_t now_ms) {
  std::lock_guard lock(mu_);
  Txn txn(db_, Txn::Kind::kWrite);
  if (!get_campaign_locked(id)) throw StoreError(Code::kNotFound, "campaign " + id + " not found");
  std::vector<JobRecord> open;
  {
    Stmt s(db_, prepare("SELECT " SYSTOLE_JOB_COLUMNS " FROM jobs WHERE campaign_id = ?1 AND "
                        "state IN ('QUEUED', 'RUNNING')"));
    s.bind_text(1, id);
    while (s.step()) open.push_back(read_job(s));
  }
  for (const JobRecord& job : open) {
    if (job.state == JobState::kQueued) {
      finish_locked(job, JobState::kCancelled, "", dump({{"state", "CANCELLED"}, {"reason", "campaign cancelled"}}),
                    now_ms);
    } else if (!job.cancel_requested) {
      Stmt s(db_, prepare("UPDATE jobs SET cancel_requested = 1, updated_ms = ?2 WHERE id = ?1"));
      s.bind_text(1, job.id).bind_int(2, now_ms);
      s.run();
      append_event(job.id, now_ms, "cancel_requested", dump({{"worker", job.worker_id}, {"reason", "campaign cancelled"}}));
    }
  }
  {
    Stmt s(db_, prepare("UPDATE campaigns SET cancelled = 1, updated_ms = ?2 WHERE id = ?1"));
    s.bind_text(1, id).bind_int(2, now_ms);
    s.run();
  }
  CampaignRecord record = *get_campaign_locked(id);
  txn.commit();
  return record;
}

CampaignRecord JobStore::retry_failed(const std::string& id, int64_t now_ms) {
  std::lock_guard lock(mu_);
  Txn txn(db_, Txn::Kind::kWrite);
  if (!get_campaign_locked(id)) throw StoreError(Code::kNotFound, "campaign " + id + " not found");
  std::vector<std::string> ids;
  {
    Stmt s(db_, prepare("SELECT id FROM jobs WHERE campaign_id = ?1 AND state IN ('FAILED', 'CANCELLED')"));
    s.bind_text(1, id);
    while (s.step()) ids.push_back(s.col_text(0));
  }
  for (const auto& job_id : ids) {
    {
      Stmt s(db_, prepare("UPDATE jobs SET state = 'QUEUED', attempts = 0, error = '', cancel_requested = 0, "
                          "worker_id = '', finished_ms = 0, lease_expires_ms = 0, lease_ms = 0, progress_json = '', "
                          "updated_ms = ?2 WHERE id = ?1"));
      s.bind_text(1, job_id).bind_int(2, now_ms);
      s.run();
    }
    append_event(job_id, now_ms, "state", dump({{"state", "QUEUED"}, {"reason", "retry requested"}}));
  }
  {
    Stmt s(db_, prepare("UPDATE campaigns SET cancelled = 0, updated_ms = ?2 WHERE id = ?1"));
    s.bind_text(1, id).bind_int(2, now_ms);
    s.run();
  }
  CampaignRecord record = *get_campaign_locked(id);
  txn.commit();
  return record;
}

int64_t JobStore::count(std::optional<JobState> state) {
  std::lock_guard lock(mu_);
  if (state) {
    Stmt s(db_, prepare("SELECT COUNT(*) FROM jobs WHERE state = ?1"));
    s.bind_text(1, to_string(*state));
    return s.step() ? s.col_int(0) : 0;
  }
  Stmt s(db_, prepare("SELECT COUNT(*) FROM jobs"));
  return s.step() ? s.col_int(0) : 0;
}

}  // namespace systole::store

#undef SYSTOLE_JOB_COLUMNS
