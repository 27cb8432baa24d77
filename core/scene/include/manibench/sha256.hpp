// SHA-256 (FIPS 180-4): the digest an evaluation's certificate gives for
// every file and text a result depends on (docs/evaluation.md,
// "Certificate"), so that anyone can check them with `sha256sum`. Here in
// the scene layer, the lowest that reads object files, so that every layer
// above has it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace manibench {

class Sha256 {
 public:
  Sha256();
  Sha256& add(const void* data, std::size_t size);
  Sha256& add(const std::string& text) { return add(text.data(), text.size()); }
  // The digest as 64 lowercase hex digits; the object is spent after it.
  std::string finish();

 private:
  void compress(const unsigned char* block);
  uint32_t state_[8];
  unsigned char buffer_[64];
  std::size_t buffered_ = 0;
  uint64_t length_ = 0;  // bytes added
};

// The digest of `text`, as 64 hex digits.
std::string calcSha256(const std::string& text);
// The digest of a file's bytes; throws Error naming the file and the reason
// when it cannot be read. Files are read once per process for a given
// (path, size, modification time): a scene rebuilt for every object does
// not hash its robot's meshes again.
std::string calcFileSha256(const std::string& path);

}  // namespace manibench
