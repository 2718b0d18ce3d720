#include "service/server/grpc_services.h"

#include <fstream>

namespace systole::service {

grpc::Status SimulationService::SubmitJob(grpc::ServerContext*, const v1::SubmitJobRequest* request,
                                          v1::SubmitJobResponse* response) {
  return guarded([&] { *response = jobs_.submit(*request); });
}
grpc::Status SimulationService::GetJob(grpc::ServerContext*, const v1::GetJobRequest* request, v1::Job* response) {
  return guarded([&] { *response = jobs_.get(request->id()); });
}
grpc::Status SimulationService::ListJobs(grpc::ServerContext*, const v1::ListJobsRequest* request,
                                         v1::ListJobsResponse* response) {
  return guarded([&] { *response = jobs_.list(*request); });
}
grpc::Status SimulationService::CancelJob(grpc::ServerContext*, const v1::CancelJobRequest* request, v1::Job* response) {
  return guarded([&] { *response = jobs_.cancel(request->id()); });
}
grpc::Status SimulationService::WatchJob(grpc::ServerContext* context, const v1::WatchJobRequest* request,
                                         grpc::ServerWriter<v1::JobEvent>* writer) {
  return guarded([&] {
    jobs_.watch(
        *request, [&](const v1::JobEvent& event) { return writer->Write(event); },
        [&] { return !context->IsCancelled(); });
  });
}
grpc::Status SimulationService::GetResult(grpc::ServerContext*, const v1::GetResultRequest* request, v1::Result* response) {
  return guarded([&] { *response = jobs_.result(request->id()); });
}
grpc::Status SimulationService::DownloadArtifact(grpc::ServerContext* context, const v1::DownloadArtifactRequest* request,
                                                 grpc::ServerWriter<v1::ArtifactChunk>* writer) {
  return guarded([&] {
    const store::Artifact artifact = jobs_.artifact(request->id(), request->name());
    std::ifstream in(artifact.path, std::ios::binary);
    if (!in) throw ServiceError(grpc::StatusCode::DATA_LOSS, "cannot open artifact '" + artifact.name + "'");
    std::string buffer(1 << 20, '\0');
    int64_t offset = 0;
    do {
      in.read(buffer.data(), static_cast<std::streamsize>(buffer.size()));
      v1::ArtifactChunk chunk;
      chunk.set_data(buffer.data(), static_cast<size_t>(in.gcount()));
      chunk.set_offset(offset);
      chunk.set_total_size_bytes(artifact.size_bytes);
      chunk.set_sha256(artifact.sha256);
      offset += in.gcount();
      if (context->IsCancelled() || !writer->Write(chunk)) return;
    } while (in);
  });
}

grpc::Status WorkerService::LeaseJob(grpc::ServerContext* context, const v1::LeaseJobRequest* request,
                                     v1::LeaseJobResponse* response) {
  return guarded([&] {
    if (request->wait_ms() < 0 || request->wait_ms() > 30000)
      throw ServiceError(grpc::StatusCode::INVALID_ARGUMENT,
                         "wait_ms = " + std::to_string(request->wait_ms()) + " is out of range [0, 30000]");
    *response = jobs_.lease(*request, std::chrono::milliseconds(request->wait_ms()));
    if (context->IsCancelled() && response->has_job()) {
      // The worker is gone before it saw its lease: give the job back at once.
      v1::ReleaseJobRequest release;
      release.set_worker_id(request->worker_id());
      release.set_job_id(response->job_id());
      jobs_.release(release);
    }
  });
}
grpc::Status WorkerService::Heartbeat(grpc::ServerContext*, const v1::HeartbeatRequest* request,
                                      v1::HeartbeatResponse* response) {
  return guarded([&] { *response = jobs_.heartbeat(*request); });
}
grpc::Status WorkerService::ReportProgress(grpc::ServerContext*, const v1::ReportProgressRequest* request,
                                           v1::HeartbeatResponse* response) {
  return guarded([&] { *response = jobs_.report_progress(*request); });
}
grpc::Status WorkerService::CompleteJob(grpc::ServerContext*, const v1::CompleteJobRequest* request, v1::WorkerAck* response) {
  return guarded([&] { *response = jobs_.complete(*request); });
}
grpc::Status WorkerService::FailJob(grpc::ServerContext*, const v1::FailJobRequest* request, v1::WorkerAck* response) {
  return guarded([&] { *response = jobs_.fail(*request); });
}
grpc::Status WorkerService::ReleaseJob(grpc::ServerContext*, const v1::ReleaseJobRequest* request, v1::WorkerAck* response) {
  return guarded([&] { *response = jobs_.release(*request); });
}
grpc::Status WorkerService::UploadArtifact(grpc::ServerContext*, grpc::ServerReader<v1::UploadArtifactRequest>* reader,
                                           v1::UploadArtifactResponse* response) {
  return guarded([&] {
    v1::UploadArtifactRequest first;
    if (!reader->Read(&first)) throw ServiceError(grpc::StatusCode::INVALID_ARGUMENT, "empty upload");
    *response = jobs_.upload(first, [&](v1::UploadArtifactRequest& next) { return reader->Read(&next); });
  });
}

grpc::Status CampaignsGrpcService::SubmitCampaign(grpc::ServerContext*, const v1::SubmitCampaignRequest* request,
                                                  v1::SubmitCampaignResponse* response) {
  return guarded([&] { *response = campaigns_.submit(*request); });
}
grpc::Status CampaignsGrpcService::GetCampaign(grpc::ServerContext*, const v1::GetCampaignRequest* request,
                                               v1::GetCampaignResponse* response) {
  return guarded([&] { *response = campaigns_.get(request->id()); });
}
grpc::Status CampaignsGrpcService::WatchCampaign(grpc::ServerContext* context, const v1::WatchCampaignRequest* request,
                                                 grpc::ServerWriter<v1::GetCampaignResponse>* writer) {
  return guarded([&] {
    campaigns_.watch(
        request->id(), [&](const v1::GetCampaignResponse& r) { return writer->Write(r); },
        [&] { return !context->IsCancelled(); });
  });
}
grpc::Status CampaignsGrpcService::CancelCampaign(grpc::ServerContext*, const v1::CancelCampaignRequest* request,
                                                  v1::Campaign* response) {
  return guarded([&] { *response = campaigns_.cancel(request->id()); });
}
grpc::Status CampaignsGrpcService::RetryFailed(grpc::ServerContext*, const v1::RetryFailedRequest* request,
                                               v1::Campaign* response) {
  return guarded([&] { *response = campaigns_.retry_failed(request->id()); });
}
grpc::Status CampaignsGrpcService::ListCampaigns(grpc::ServerContext*, const v1::ListCampaignsRequest* request,
                                                 v1::ListCampaignsResponse* response) {
  return guarded([&] { *response = campaigns_.list(*request); });
}
grpc::Status CampaignsGrpcService::GetCampaignSamples(grpc::ServerContext*, const v1::GetCampaignSamplesRequest* request,
                                                      v1::GetCampaignSamplesResponse* response) {
  return guarded([&] { *response = campaigns_.samples(request->id()); });
}

}  // namespace systole::service
