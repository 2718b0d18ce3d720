#pragma once
// gRPC front ends of JobService: systole.v1.Simulation (public) and systole.v1.WorkerApi.
// Each RPC is a one-line call into JobService wrapped by guarded(), which maps errors to status.
#include "service/server/campaign_service.h"
#include "service/server/job_service.h"
#include "systole/v1/campaign.grpc.pb.h"
#include "systole/v1/service.grpc.pb.h"
#include "systole/v1/worker.grpc.pb.h"

namespace systole::service {

class SimulationService final : public v1::Simulation::Service {
 public:
  explicit SimulationService(JobService& jobs) : jobs_(jobs) {}
  grpc::Status SubmitJob(grpc::ServerContext*, const v1::SubmitJobRequest*, v1::SubmitJobResponse*) override;
  grpc::Status GetJob(grpc::ServerContext*, const v1::GetJobRequest*, v1::Job*) override;
  grpc::Status ListJobs(grpc::ServerContext*, const v1::ListJobsRequest*, v1::ListJobsResponse*) override;
  grpc::Status CancelJob(grpc::ServerContext*, const v1::CancelJobRequest*, v1::Job*) override;
  grpc::Status WatchJob(grpc::ServerContext*, const v1::WatchJobRequest*, grpc::ServerWriter<v1::JobEvent>*) override;
  grpc::Status GetResult(grpc::ServerContext*, const v1::GetResultRequest*, v1::Result*) override;
  grpc::Status DownloadArtifact(grpc::ServerContext*, const v1::DownloadArtifactRequest*,
                                grpc::ServerWriter<v1::ArtifactChunk>*) override;

 private:
  JobService& jobs_;
};

class WorkerService final : public v1::WorkerApi::Service {
 public:
  explicit WorkerService(JobService& jobs) : jobs_(jobs) {}
  grpc::Status LeaseJob(grpc::ServerContext*, const v1::LeaseJobRequest*, v1::LeaseJobResponse*) override;
  grpc::Status Heartbeat(grpc::ServerContext*, const v1::HeartbeatRequest*, v1::HeartbeatResponse*) override;
  grpc::Status ReportProgress(grpc::ServerContext*, const v1::ReportProgressRequest*, v1::HeartbeatResponse*) override;
  grpc::Status CompleteJob(grpc::ServerContext*, const v1::CompleteJobRequest*, v1::WorkerAck*) override;
  grpc::Status FailJob(grpc::ServerContext*, const v1::FailJobRequest*, v1::WorkerAck*) override;
  grpc::Status ReleaseJob(grpc::ServerContext*, const v1::ReleaseJobRequest*, v1::WorkerAck*) override;
  grpc::Status UploadArtifact(grpc::ServerContext*, grpc::ServerReader<v1::UploadArtifactRequest>*,
                              v1::UploadArtifactResponse*) override;

 private:
  JobService& jobs_;
};

class CampaignsGrpcService final : public v1::Campaigns::Service {
 public:
  explicit CampaignsGrpcService(CampaignService& campaigns) : campaigns_(campaigns) {}
  grpc::Status SubmitCampaign(grpc::ServerContext*, const v1::SubmitCampaignRequest*, v1::SubmitCampaignResponse*) override;
  grpc::Status GetCampaign(grpc::ServerContext*, const v1::GetCampaignRequest*, v1::GetCampaignResponse*) override;
  grpc::Status WatchCampaign(grpc::ServerContext*, const v1::WatchCampaignRequest*,
                             grpc::ServerWriter<v1::GetCampaignResponse>*) override;
  grpc::Status CancelCampaign(grpc::ServerContext*, const v1::CancelCampaignRequest*, v1::Campaign*) override;
  grpc::Status RetryFailed(grpc::ServerContext*, const v1::RetryFailedRequest*, v1::Campaign*) override;
  grpc::Status ListCampaigns(grpc::ServerContext*, const v1::ListCampaignsRequest*, v1::ListCampaignsResponse*) override;
  grpc::Status GetCampaignSamples(grpc::ServerContext*, const v1::GetCampaignSamplesRequest*,
                                  v1::GetCampaignSamplesResponse*) override;

 private:
  CampaignService& campaigns_;
};

}  // namespace systole::service
