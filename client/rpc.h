#pragma once
// What every `systole` subcommand shares: the error type whose exit code tells the kind of
// failure, and the mapping of a gRPC status onto it.
//   exit 1: the job/campaign failed, or the server had an internal fault
//   exit 2: bad input or a request the server rejected
//   exit 3: the server is unreachable
//   exit 4: a corrupt download
#include <chrono>
#include <cstdint>
#include <ctime>
#include <memory>
#include <stdexcept>
#include <string>

#include <grpcpp/grpcpp.h>

namespace systole::client {

struct CliError : std::runtime_error {
  CliError(const std::string& message, int code) : std::runtime_error(message), exit_code(code) {}
  int exit_code;
};

inline std::unique_ptr<grpc::ClientContext> make_context(int timeout_s) {
  auto c = std::make_unique<grpc::ClientContext>();
  if (timeout_s > 0) c->set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(timeout_s));
  return c;
}

inline std::string status_code_name(grpc::StatusCode code) {
  static const char* names[] = {"OK", "CANCELLED", "UNKNOWN", "INVALID_ARGUMENT", "DEADLINE_EXCEEDED",
                                "NOT_FOUND", "ALREADY_EXISTS", "PERMISSION_DENIED", "RESOURCE_EXHAUSTED",
                                "FAILED_PRECONDITION", "ABORTED", "OUT_OF_RANGE", "UNIMPLEMENTED", "INTERNAL",
                                "UNAVAILABLE", "DATA_LOSS", "UNAUTHENTICATED"};
  const int i = static_cast<int>(code);
  return i >= 0 && i < 17 ? names[i] : std::to_string(i);
}

// Throws the CliError for a failed call to the server at `address`.
inline void check_status(const grpc::Status& status, const std::string& address) {
  if (status.ok()) return;
  if (status.error_code() == grpc::StatusCode::UNAVAILABLE || status.error_code() == grpc::StatusCode::DEADLINE_EXCEEDED)
    throw CliError("cannot reach systole-server at " + address + ": " + status.error_message() +
                       "\n  is it running? start one with: build/bin/systole-server --local-workers 2"
                       "\n  or point to another with --server HOST:PORT or SYSTOLE_SERVER",
                   3);
  if (status.error_code() == grpc::StatusCode::INTERNAL || status.error_code() == grpc::StatusCode::UNKNOWN)
    throw CliError("server error: " + status.error_message(), 1);
  throw CliError("error (" + status_code_name(status.error_code()) + "): " + status.error_message(), 2);
}

// Local date and time of a millisecond epoch timestamp; "-" for 0 (never).
inline std::string format_time(int64_t ms) {
  if (ms == 0) return "-";
  const std::time_t t = static_cast<std::time_t>(ms / 1000);
  char buffer[32];
  std::strftime(buffer, sizeof buffer, "%Y-%m-%d %H:%M:%S", std::localtime(&t));
  return buffer;
}

}  // namespace systole::client
