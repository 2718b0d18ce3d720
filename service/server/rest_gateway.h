#pragma once
// REST/JSON gateway: the public RPCs of systole.v1.Simulation on plain HTTP, bodies in
// protobuf's JSON mapping, errors as gRPC-style bodies {"code": <grpc code>, "message": ...,
// "details": []}. Routes (docs/api.md):
//   POST /v1/jobs                          SubmitJob      (201 created, 200 idempotent repeat)
//   GET  /v1/jobs?state=&page_size=&page_token=   ListJobs
//   GET  /v1/jobs/{id}                     GetJob
//   POST /v1/jobs/{id}:cancel              CancelJob
//   GET  /v1/jobs/{id}:watch?after_sequence=N     WatchJob as NDJSON, or SSE with
//                                                 Accept: text/event-stream
//   GET  /v1/jobs/{id}/result              GetResult
//   GET  /v1/jobs/{id}/artifacts/{name}    DownloadArtifact (raw bytes, X-Sha256 header)
//   POST /v1/campaigns                     SubmitCampaign (201 / 200)
//   GET  /v1/campaigns                     ListCampaigns
//   GET  /v1/campaigns/{id}                GetCampaign (with statistics)
//   GET  /v1/campaigns/{id}/samples        GetCampaignSamples
//   POST /v1/campaigns/{id}:cancel | :retry
//   GET  /v1/campaigns/{id}:watch          WatchCampaign as NDJSON (or SSE)
//   GET  /healthz                          200 "SERVING"
#include <atomic>
#include <memory>
#include <string>
#include <thread>

#include "service/server/campaign_service.h"
#include "service/server/job_service.h"

namespace httplib {
class Server;
}

namespace systole::service {

class RestGateway {
 public:
  // Binds host:port (port 0 picks a free one) and starts serving on a background thread.
  RestGateway(JobService& jobs, CampaignService& campaigns, const std::string& host, int port,
              size_t max_body_bytes);
  ~RestGateway();  // stops and joins
  RestGateway(const RestGateway&) = delete;
  RestGateway& operator=(const RestGateway&) = delete;
  int port() const { return port_; }

 private:
  JobService& jobs_;
  CampaignService& campaigns_;
  std::unique_ptr<httplib::Server> server_;
  int port_ = 0;
  std::atomic<bool> listen_returned_{false};
  std::thread thread_;
};

int http_status_for(grpc::StatusCode code);

}  // namespace systole::service
