#pragma once
// `systole campaign ...`: the command-line side of systole.v1.Campaigns (UQ campaigns).
//   systole campaign submit SPEC.json [--set key=value ...] [--request-id ID]  → campaign id
//   systole campaign watch ID      progress until it finishes, then the summary (exit 1 if any
//                                  sample failed or was cancelled, and they are listed)
//   systole campaign status ID     the same summary, over the samples finished so far
//   systole campaign results ID --out DIR   campaign.csv, campaign.h5, statistics.json
//   systole campaign retry ID | cancel ID | list
// Exit codes as the rest of the CLI: 0 ok, 1 failed samples/other, 2 bad input or rejected
// request, 3 server unreachable.
#include <memory>
#include <string>

namespace CLI {
class App;
}

namespace systole::cli {

class CampaignCommands {
 public:
  virtual ~CampaignCommands() = default;
  // True when the parsed command line selected `campaign <subcommand>`.
  virtual bool selected() const = 0;
  // Runs the selected subcommand against the gRPC address `server`; prints errors to stderr
  // ("systole: ...") and returns the process exit code.
  virtual int run(const std::string& server) = 0;
};

// Registers the `campaign` subcommand group on `app` (before parsing). Keep the returned
// object alive until run().
std::unique_ptr<CampaignCommands> add_campaign_commands(CLI::App& app);

}  // namespace systole::cli
