// systole: the command-line client of systole-server.
//   systole submit SCENARIO.json [--set path=value ...]   → prints the job id
//   systole status ID | list | watch ID | cancel ID | results ID [--json|--csv]
//   systole download ID [--name NAME] [--out DIR]
//   systole run SCENARIO.json [--set ...] [--out DIR]      submit + watch + download
//   systole campaign submit|watch|status|results|retry|cancel|list   (client/campaign_cli.h)
// The server address comes from --server or $SYSTOLE_SERVER (default 127.0.0.1:50051).
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <thread>

#include <CLI/CLI.hpp>
#include <google/protobuf/util/json_util.h>
#include <grpcpp/grpcpp.h>

#include "client/campaign_cli.h"
#include "client/rpc.h"
#include "proto/bridge/scenario_bridge.h"
#include "service/server/sha256.h"
#include "solver/core/errors.h"
#include "systole/v1/service.grpc.pb.h"

namespace fs = std::filesystem;
using namespace systole;

namespace {

using client::CliError;

class Client {
 public:
  explicit Client(std::string address) : address_(std::move(address)) {
    grpc::ChannelArguments args;
    args.SetMaxReceiveMessageSize(256 << 20);
    stub_ = v1::Simulation::NewStub(grpc::CreateCustomChannel(address_, grpc::InsecureChannelCredentials(), args));
  }
  v1::Simulation::Stub& stub() { return *stub_; }
  std::unique_ptr<grpc::ClientContext> context(int timeout_s = 30) const { return client::make_context(timeout_s); }
  void check(const grpc::Status& status) const { client::check_status(status, address_); }

 private:
  std::string address_;
  std::unique_ptr<v1::Simulation::Stub> stub_;
};

std::string to_json(const google::protobuf::Message& m) {
  google::protobuf::util::JsonPrintOptions options;
  options.preserve_proto_field_names = true;
  options.add_whitespace = true;
  std::string text;
  (void)google::protobuf::util::MessageToJsonString(m, &text, options);
  return text;
}

using client::format_time;

void print_job(const v1::Job& job) {
  std::cout << "job        " << job.id() << "\n"
            << "state      " << v1::JobState_Name(job.state()) << (job.cancel_requested() ? " (cancel requested)" : "")
            << "\n"
            << "scene      " << job.scene() << "\n"
            << "priority   " << job.priority() << "\n"
            << "attempts   " << job.attempts() << " of " << job.max_attempts() << "\n"
            << "created    " << format_time(job.created_ms()) << "\n"
            << "started    " << format_time(job.started_ms()) << "\n"
            << "finished   " << format_time(job.finished_ms()) << "\n";
  if (!job.request_id().empty()) std::cout << "request_id " << job.request_id() << "\n";
  if (job.has_progress())
    std::cout << "progress   beat " << job.progress().beat() << "/" << job.progress().beats_total() << ", t = "
              << job.progress().simulated_time_s() << " s\n";
  if (!job.error().empty()) std::cout << "error      " << job.error() << "\n";
}

bool is_terminal(v1::JobState s) { return s == v1::SUCCEEDED || s == v1::FAILED || s == v1::CANCELLED; }

std::string metric_line(const google::protobuf::Map<std::string, double>& m) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(1);
  auto get = [&](const char* k) { auto it = m.find(k); return it == m.end() ? std::nan("") : it->second; };
  out << "EF " << get("ejection_fraction_percent") << " %  EDV " << get("edv_ml") << " ml  CO " << std::setprecision(2)
      << get("cardiac_output_l_min") << " l/min  LVP " << std::setprecision(0) << get("lv_peak_pressure_mmhg")
      << " mmHg  AoP " << get("aortic_pressure_max_mmhg") << "/" << get("aortic_pressure_min_mmhg") << " mmHg";
  return out.str();
}

// Streams events until the job is terminal; a live bar on a terminal, lines otherwise.
v1::JobState watch(Client& client, const std::string& id, bool quiet) {
  const bool tty = ::isatty(1);
  int64_t after = 0;
  v1::JobState state = v1::JOB_STATE_UNSPECIFIED;
  int last_beat_printed = 0;
  for (int reconnects = 0; reconnects < 20; ++reconnects) {
    auto context = client.context(0);
    v1::WatchJobRequest request;
    request.set_id(id);
    request.set_after_sequence(after);
    auto reader = client.stub().WatchJob(context.get(), request);
    v1::JobEvent event;
    while (reader->Read(&event)) {
      if (event.kind() != "snapshot") after = event.sequence();
      if (event.state() != v1::JOB_STATE_UNSPECIFIED) state = event.state();
      if (quiet || event.kind() == "snapshot") continue;
      if (event.kind() == "progress") {
        const auto& p = event.progress();
        if (tty) {
          const int width = 30;
          const int filled = static_cast<int>(std::clamp(p.fraction(), 0.0, 1.0) * width);
          std::cout << "\r[" << std::string(filled, '#') << std::string(width - filled, '.') << "] beat " << p.beat()
                    << "/" << p.beats_total() << "  t = " << std::fixed << std::setprecision(2) << p.simulated_time_s()
                    << " s  " << metric_line(p.latest_beat_metrics()) << std::flush;
        } else if (p.beat() != last_beat_printed) {
          std::cout << "beat " << p.beat() << "/" << p.beats_total() << "  t = " << std::fixed << std::setprecision(2)
                    << p.simulated_time_s() << " s  " << metric_line(p.latest_beat_metrics()) << "\n";
        }
        last_beat_printed = p.beat();
      } else {
        if (tty && last_beat_printed) std::cout << "\n";
        std::cout << "[" << event.kind() << "] " << v1::JobState_Name(event.state())
                  << (event.message().empty() ? "" : ": " + event.message()) << std::endl;
      }
    }
    const auto status = reader->Finish();
    if (status.ok() && is_terminal(state)) return state;
    if (!status.ok() && status.error_code() != grpc::StatusCode::UNAVAILABLE) client.check(status);
    std::this_thread::sleep_for(std::chrono::seconds(1));  // server restarting: resume where we were
  }
  throw CliError("lost the connection to the server while watching " + id, 3);
}

std::vector<std::string> download(Client& client, const std::string& id, const std::string& only, const fs::path& out) {
  auto context = client.context(60);
  v1::GetResultRequest request;
  request.set_id(id);
  v1::Result result;
  client.check(client.stub().GetResult(context.get(), request, &result));
  fs::create_directories(out);
  std::vector<std::string> written;
  for (const auto& artifact : result.artifacts()) {
    if (!only.empty() && artifact.name() != only) continue;
    auto ctx = client.context(600);
    v1::DownloadArtifactRequest dl;
    dl.set_id(id);
    dl.set_name(artifact.name());
    auto reader = client.stub().DownloadArtifact(ctx.get(), dl);
    const fs::path file = out / artifact.name();
    const fs::path tmp = file.string() + ".part";
    std::ofstream stream(tmp, std::ios::binary);
    service::Sha256 hash;
    v1::ArtifactChunk chunk;
    while (reader->Read(&chunk)) {
      stream.write(chunk.data().data(), static_cast<std::streamsize>(chunk.data().size()));
      hash.update(chunk.data());
    }
    client.check(reader->Finish());
    stream.close();
    const std::string sha = hash.hex_digest();
    if (sha != artifact.sha256()) {
      fs::remove(tmp);
      throw CliError("download of " + artifact.name() + " is corrupt (sha256 " + sha + " != " + artifact.sha256() + ")", 4);
    }
    fs::rename(tmp, file);
    written.push_back(file.string());
  }
  if (!only.empty() && written.empty()) throw CliError("job " + id + " has no artifact '" + only + "'", 2);
  return written;
}

std::string submit(Client& client, const std::string& file, const std::vector<std::string>& sets, int priority,
                   const std::string& request_id, int max_attempts) {
  v1::SubmitJobRequest request;
  *request.mutable_scenario() = bridge::load_scenario_file(file, sets);
  (void)bridge::validate(request.scenario());  // the same checks as the server, before sending
  request.set_priority(priority);
  request.set_request_id(request_id);
  request.set_max_attempts(max_attempts);
  v1::SubmitJobResponse response;
  auto context = client.context();
  client.check(client.stub().SubmitJob(context.get(), request, &response));
  return response.job().id();
}

void print_results(const v1::Result& result, bool json, bool csv) {
  if (json) {
    std::cout << to_json(result) << "\n";
    return;
  }
  if (csv) {
    const auto& series = result.time_series();
    for (int i = 0; i < series.size(); ++i) std::cout << (i ? "," : "") << series[i].name();
    std::cout << "\n" << std::setprecision(10);
    const int n = series.empty() ? 0 : series[0].values_size();
    for (int r = 0; r < n; ++r) {
      for (int i = 0; i < series.size(); ++i) std::cout << (i ? "," : "") << series[i].values(r);
      std::cout << "\n";
    }
    return;
  }
  std::map<std::string, double> sorted(result.metrics().begin(), result.metrics().end());
  std::cout << "metric                                   value\n";
  for (const auto& [k, v] : sorted) std::cout << std::left << std::setw(36) << k << std::right << std::setw(12) << v << "\n";
  std::cout << "\nartifacts:\n";
  for (const auto& a : result.artifacts())
    std::cout << "  " << std::left << std::setw(14) << a.name() << std::right << std::setw(10) << a.size_bytes()
              << " bytes  sha256 " << a.sha256() << "\n";
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"systole: client of the systole left-heart simulation service"};
  app.require_subcommand(1);
  const char* env_server = std::getenv("SYSTOLE_SERVER");
  std::string server = env_server ? env_server : "127.0.0.1:50051";
  app.add_option("--server", server, "systole-server gRPC address (or $SYSTOLE_SERVER)")->capture_default_str();

  std::string file, id, request_id, state_name, name, out_dir = ".", page_token;
  std::vector<std::string> sets;
  int priority = 0, max_attempts = 0, page_size = 50;
  bool json = false, csv = false, quiet = false;
  auto add_submit_options = [&](CLI::App* c) {
    c->add_option("scenario", file, "scenario JSON file (proto3 JSON)")->required()->check(CLI::ExistingFile);
    c->add_option("--set", sets, "override a field: path.to.field=value (repeatable)");
    c->add_option("--priority", priority, "higher runs first [-1000, 1000]");
    c->add_option("--request-id", request_id, "idempotency key");
    c->add_option("--max-attempts", max_attempts, "attempts before FAILED (default 3)");
  };
  auto* submit_cmd = app.add_subcommand("submit", "submit a scenario; prints the job id");
  add_submit_options(submit_cmd);
  auto* status_cmd = app.add_subcommand("status", "show a job");
  status_cmd->add_option("id", id)->required();
  status_cmd->add_flag("--json", json, "as JSON");
  auto* list_cmd = app.add_subcommand("list", "list jobs, newest first");
  list_cmd->add_option("--state", state_name, "QUEUED, RUNNING, SUCCEEDED, FAILED or CANCELLED");
  list_cmd->add_option("--page-size", page_size, "jobs per page")->capture_default_str();
  list_cmd->add_option("--page-token", page_token, "continue a listing");
  auto* watch_cmd = app.add_subcommand("watch", "stream a job's progress until it ends");
  watch_cmd->add_option("id", id)->required();
  auto* cancel_cmd = app.add_subcommand("cancel", "cancel a job");
  cancel_cmd->add_option("id", id)->required();
  auto* results_cmd = app.add_subcommand("results", "metrics of a finished job");
  results_cmd->add_option("id", id)->required();
  results_cmd->add_flag("--json", json, "the whole result as JSON");
  results_cmd->add_flag("--csv", csv, "the time series as CSV");
  auto* download_cmd = app.add_subcommand("download", "download a job's artifacts (sha256-checked)");
  download_cmd->add_option("id", id)->required();
  download_cmd->add_option("--name", name, "only this artifact (result.h5, metrics.json, pv_loop.csv)");
  download_cmd->add_option("--out", out_dir, "directory")->capture_default_str();
  auto* run_cmd = app.add_subcommand("run", "submit, watch and download");
  add_submit_options(run_cmd);
  run_cmd->add_option("--out", out_dir, "directory for the artifacts (default results/<job id>)");
  run_cmd->add_flag("--quiet", quiet, "no progress output");
  auto campaign = cli::add_campaign_commands(app);  // `systole campaign ...`: client/campaign_cli.cc
  CLI11_PARSE(app, argc, argv);
  if (campaign->selected()) return campaign->run(server);

  try {
    Client client(server);
    if (*submit_cmd) {
      std::cout << submit(client, file, sets, priority, request_id, max_attempts) << "\n";
    } else if (*status_cmd) {
      auto context = client.context();
      v1::GetJobRequest request;
      request.set_id(id);
      v1::Job job;
      client.check(client.stub().GetJob(context.get(), request, &job));
      if (json) std::cout << to_json(job) << "\n"; else print_job(job);
    } else if (*list_cmd) {
      v1::ListJobsRequest request;
      if (!state_name.empty()) {
        v1::JobState s;
        if (!v1::JobState_Parse(state_name, &s) || s == v1::JOB_STATE_UNSPECIFIED)
          throw CliError("--state '" + state_name + "' is not one of QUEUED, RUNNING, SUCCEEDED, FAILED, CANCELLED", 2);
        request.set_state(s);
      }
      request.set_page_size(page_size);
      request.set_page_token(page_token);
      auto context = client.context();
      v1::ListJobsResponse response;
      client.check(client.stub().ListJobs(context.get(), request, &response));
      std::cout << std::left << std::setw(20) << "ID" << std::setw(11) << "STATE" << std::setw(10) << "SCENE"
                << std::setw(9) << "ATTEMPTS" << "CREATED\n";
      for (const auto& job : response.jobs())
        std::cout << std::setw(20) << job.id() << std::setw(11) << v1::JobState_Name(job.state()) << std::setw(10)
                  << job.scene() << std::setw(9) << (std::to_string(job.attempts()) + "/" + std::to_string(job.max_attempts()))
                  << format_time(job.created_ms()) << "\n";
      if (!response.next_page_token().empty())
        std::cout << "more: systole list --page-token " << response.next_page_token() << "\n";
    } else if (*watch_cmd) {
      const auto state = watch(client, id, false);
      return state == v1::SUCCEEDED ? 0 : 1;
    } else if (*cancel_cmd) {
      auto context = client.context();
      v1::CancelJobRequest request;
      request.set_id(id);
      v1::Job job;
      client.check(client.stub().CancelJob(context.get(), request, &job));
      std::cout << job.id() << " " << v1::JobState_Name(job.state())
                << (job.cancel_requested() && job.state() == v1::RUNNING ? " (cancel requested; the worker stops shortly)" : "")
                << "\n";
    } else if (*results_cmd) {
      auto context = client.context(60);
      v1::GetResultRequest request;
      request.set_id(id);
      v1::Result result;
      client.check(client.stub().GetResult(context.get(), request, &result));
      print_results(result, json, csv);
    } else if (*download_cmd) {
      for (const auto& f : download(client, id, name, out_dir)) std::cout << f << "\n";
    } else if (*run_cmd) {
      const std::string job_id = submit(client, file, sets, priority, request_id, max_attempts);
      std::cout << "submitted " << job_id << std::endl;
      const auto state = watch(client, job_id, quiet);
      if (state != v1::SUCCEEDED) {
        auto context = client.context();
        v1::GetJobRequest request;
        request.set_id(job_id);
        v1::Job job;
        client.check(client.stub().GetJob(context.get(), request, &job));
        throw CliError("job " + job_id + " ended " + v1::JobState_Name(state) + (job.error().empty() ? "" : ": " + job.error()), 1);
      }
      const fs::path out = out_dir == "." ? fs::path("results") / job_id : fs::path(out_dir);
      const auto files = download(client, job_id, "", out);
      auto context = client.context();
      v1::GetResultRequest request;
      request.set_id(job_id);
      v1::Result result;
      client.check(client.stub().GetResult(context.get(), request, &result));
      const auto& m = result.metrics();
      auto get = [&](const char* k) { auto it = m.find(k); return it == m.end() ? std::nan("") : it->second; };
      if (m.contains("ejection_fraction_percent")) {
        std::cout << std::fixed << std::setprecision(1) << "\nejection fraction  " << get("ejection_fraction_percent")
                  << " %\n" << std::setprecision(2) << "cardiac output     " << get("cardiac_output_l_min") << " l/min\n"
                  << std::setprecision(1) << "EDV / ESV          " << get("edv_ml") << " / " << get("esv_ml") << " ml\n"
                  << std::setprecision(0) << "LV peak pressure   " << get("lv_peak_pressure_mmhg") << " mmHg\n"
                  << "aortic pressure    " << get("aortic_pressure_max_mmhg") << "/" << get("aortic_pressure_min_mmhg")
                  << " mmHg\n" << "beats simulated    " << get("beats_simulated") << "\n";
      } else {  // scenes without a heart (fluid, analytic): every metric
        std::cout << "\n";
        print_results(result, false, false);
      }
      for (const auto& f : files) std::cout << "wrote " << fs::absolute(f).string() << "\n";
    }
    return 0;
  } catch (const CliError& e) {
    std::cerr << "systole: " << e.what() << "\n";
    return e.exit_code;
  } catch (const InputError& e) {
    std::cerr << "systole: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "systole: " << e.what() << "\n";
    return 1;
  }
}
