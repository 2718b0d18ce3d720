// Campaign throughput through the real service: a 1000-sample 0-D campaign (issue 10's
// example: LV Emax, heart rate, systemic resistance; SALTELLI 200 x 5) with 1 and 2 local
// workers, then the same campaign again (result cache hit rate). Prints a Markdown table.
//   campaign_bench [--samples 200] [--workers 1,2]
#include <cstdio>
#include <iostream>

#include "systole/v1/campaign.grpc.pb.h"
#include "tests/e2e/harness.h"

using namespace systole;
using namespace systole::e2e;

namespace {

v1::CampaignSpec spec(int samples) {
  const nlohmann::json j = {
      {"base_scenario", {{"scene", "lumped"}, {"outputs", {{"time_series", false}}}}},
      {"parameters",
       {{{"path", "lumped.lv.emax_mmhg_per_ml"}, {"uniform", {{"min", 2.0}, {"max", 3.5}}}},
        {{"path", "heart_rate_bpm"}, {"uniform", {{"min", 60}, {"max", 90}}}},
        {{"path", "lumped.systemic_resistance_mmhg_s_per_ml"}, {"uniform", {{"min", 0.8}, {"max", 1.3}}}}}},
      {"design", "SALTELLI"}, {"samples", samples}, {"seed", 1},
      {"quantities_of_interest", {"ejection_fraction_percent", "cardiac_output_l_min"}}};
  v1::CampaignSpec out;
  (void)google::protobuf::util::JsonStringToMessage(j.dump(), &out);
  return out;
}

struct Run {
  double seconds = 0;
  int jobs = 0, cached = 0, succeeded = 0;
  v1::GetCampaignResponse final;
};

Run run_campaign(ServerProcess& server, int samples, const std::string& request_id) {
  auto stub = v1::Campaigns::NewStub(server.channel());
  v1::SubmitCampaignRequest request;
  *request.mutable_spec() = spec(samples);
  request.set_request_id(request_id);
  v1::SubmitCampaignResponse submitted;
  const auto start = std::chrono::steady_clock::now();
  auto ctx = deadline_context(120);
  const auto status = stub->SubmitCampaign(ctx.get(), request, &submitted);
  if (!status.ok()) throw std::runtime_error(status.error_message());
  // WatchCampaign ends when the campaign is finished; its last message has the statistics.
  v1::WatchCampaignRequest watch;
  watch.set_id(submitted.campaign().id());
  auto wctx = deadline_context(1200);
  auto reader = stub->WatchCampaign(wctx.get(), watch);
  Run run;
  v1::GetCampaignResponse message;
  while (reader->Read(&message)) run.final = message;
  if (!reader->Finish().ok()) throw std::runtime_error("watch failed");
  run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  run.jobs = run.final.campaign().jobs_total();
  run.cached = run.final.campaign().jobs_cached();
  run.succeeded = run.final.statistics().samples_succeeded();
  return run;
}

}  // namespace

int main(int argc, char** argv) {
  int samples = 200;
  std::vector<int> workers{1, 2};
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    if (flag == "--samples") samples = std::stoi(argv[i + 1]);
    if (flag == "--workers") {
      workers.clear();
      std::stringstream list(argv[i + 1]);
      std::string item;
      while (std::getline(list, item, ',')) workers.push_back(std::stoi(item));
    }
  }
  std::cout << "| local workers (1 rank each) | campaign | jobs | cached | succeeded | wall (s) | samples/s |\n"
            << "|---|---|---:|---:|---:|---:|---:|\n";
  for (int w : workers) {
    const fs::path dir = make_temp_dir("campaign-bench");
    {
      ServerProcess server(dir, w, 1, 15000);
      const Run first = run_campaign(server, samples, "bench-first");
      const Run again = run_campaign(server, samples, "bench-again");
      for (const auto& [name, r] : {std::pair{"first", first}, std::pair{"repeat (cache)", again}}) {
        char line[256];
        std::snprintf(line, sizeof line, "| %d | %s | %d | %d (%.0f %%) | %d | %.2f | %.1f |\n", w, name, r.jobs,
                      r.cached, 100.0 * r.cached / std::max(1, r.jobs), r.succeeded, r.seconds, r.jobs / r.seconds);
        std::cout << line << std::flush;
      }
      if (w == workers.back()) {
        const auto& q = first.final.statistics().qoi(0);
        std::cout << "\nEF: mean " << q.mean() << " %, std " << q.std() << "; Sobol first/total:";
        for (const auto& s : q.sensitivities())
          std::cout << " " << s.path() << " " << s.sobol_first().estimate() << "/" << s.sobol_total().estimate();
        const auto& c = first.final.statistics().qoi(1);
        std::cout << "\nCO: mean " << c.mean() << " l/min, std " << c.std() << "; Sobol first/total:";
        for (const auto& s : c.sensitivities())
          std::cout << " " << s.path() << " " << s.sobol_first().estimate() << "/" << s.sobol_total().estimate();
        std::cout << "\n";
      }
    }
    fs::remove_all(dir);
  }
  return 0;
}
