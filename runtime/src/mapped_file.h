// Read-only POSIX memory mapping of a whole file, unmapped on destruction.
#pragma once
#include <cstdint>
#include <span>
#include <string>

#include "octbake/result.h"

namespace octbake::detail {

class MappedFile {
 public:
  MappedFile() = default;
  // not_found when the file does not exist, io_error when it cannot be opened
  // or mapped. An empty file maps to an empty span (nothing to mmap).
  static Result<MappedFile> open(const std::string& path);

  MappedFile(MappedFile&& o) noexcept;
  MappedFile& operator=(MappedFile&& o) noexcept;
  MappedFile(const MappedFile&) = delete;
  MappedFile& operator=(const MappedFile&) = delete;
  ~MappedFile();

  std::span<const uint8_t> bytes() const { return {data_, size_}; }

 private:
  const uint8_t* data_ = nullptr;
  size_t size_ = 0;
  void release();
};

}  // namespace octbake::detail
