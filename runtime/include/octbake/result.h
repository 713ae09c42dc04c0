// Result<T>: a value or a typed Error. No exceptions cross the runtime API.
#pragma once
#include <string>
#include <utility>
#include <variant>
#include "octbake/export.h"

namespace octbake {

enum class ErrorCode {
  not_found,            // file or tree missing
  io_error,             // could not open / map / read
  truncated,            // shorter than its header says
  bad_identifier,       // not an octbake file
  unsupported_version,  // newer format than this build reads
  corrupt,              // fails verification (sizes, offsets, counts)
  decompress_failed,    // zstd frame broken or lies about its size
  invalid_argument,
};

OCTBAKE_API const char* to_string(ErrorCode code);

struct Error {
  ErrorCode code;
  std::string message;  // names the file and the reason
};

template <class T>
class [[nodiscard]] Result {
 public:
  Result(T value) : v_(std::move(value)) {}
  Result(Error error) : v_(std::move(error)) {}
  bool ok() const { return v_.index() == 0; }
  explicit operator bool() const { return ok(); }
  T& value() & { return std::get<0>(v_); }
  const T& value() const& { return std::get<0>(v_); }
  T&& value() && { return std::get<0>(std::move(v_)); }
  T* operator->() { return &value(); }
  const T* operator->() const { return &value(); }
  T& operator*() & { return value(); }
  const T& operator*() const& { return value(); }
  const Error& error() const { return std::get<1>(v_); }

 private:
  std::variant<T, Error> v_;
};

}  // namespace octbake
