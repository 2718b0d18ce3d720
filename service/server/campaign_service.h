#pragma once
// Uncertainty-quantification campaigns (systole.v1.Campaigns): validates a campaign spec,
// draws its samples (uq/), inserts one job per sample in one transaction, and computes
// statistics and Sobol indices over the finished samples. Transport-free like JobService:
// the gRPC service and the REST gateway call it.
#include <functional>
#include <string>
#include <vector>

#include "service/server/job_service.h"
#include "systole/v1/campaign.pb.h"

namespace systole::service {

struct CampaignLimits {
  int max_samples = 100000;   // base sample count N
  int max_jobs = 200000;      // N, or N (d + 2) with SALTELLI
  int default_bootstrap = 200;
};

class CampaignService {
 public:
  CampaignService(store::JobStore& store, ChangeNotifier& notifier, ServiceOptions options,
                  CampaignLimits limits = {});

  // INVALID_ARGUMENT (every problem listed, each naming the offending field) or the campaign.
  v1::SubmitCampaignResponse submit(const v1::SubmitCampaignRequest& request);
  // What submit() would refuse, one message per problem (empty: valid); stores nothing. For a
  // front end that reports them with its own (the REST gateway's unknown JSON keys).
  std::vector<std::string> problems(const v1::SubmitCampaignRequest& request) const;
  v1::GetCampaignResponse get(const std::string& id);
  // Sends the campaign now and whenever its job counts change (at most every 500 ms), the
  // last message with full statistics, until it is finished or keep_going() is false.
  void watch(const std::string& id, const std::function<bool(const v1::GetCampaignResponse&)>& send,
             const std::function<bool()>& keep_going);
  v1::Campaign cancel(const std::string& id);
  v1::Campaign retry_failed(const std::string& id);
  v1::ListCampaignsResponse list(const v1::ListCampaignsRequest& request);
  v1::GetCampaignSamplesResponse samples(const std::string& id);

 private:
  v1::Campaign campaign_proto(const store::CampaignRecord& record) const;
  v1::CampaignStatistics statistics(const v1::CampaignSpec& spec,
                                    const std::vector<store::CampaignSampleRow>& rows) const;
  store::CampaignRecord require(const std::string& id);

  store::JobStore& store_;
  ChangeNotifier& notifier_;
  ServiceOptions options_;
  CampaignLimits limits_;
};

}  // namespace systole::service
