#pragma once
// Streaming SHA-256 (OpenSSL EVP), hex-encoded: artifact integrity end to end.
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>

namespace systole::service {

class Sha256 {
 public:
  Sha256();
  ~Sha256();
  Sha256(const Sha256&) = delete;
  Sha256& operator=(const Sha256&) = delete;
  void update(std::string_view bytes);
  std::string hex_digest();  // finishes the hash

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

std::string sha256_of_file(const std::filesystem::path& file);

}  // namespace systole::service
