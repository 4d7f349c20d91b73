// SPDX-License-Identifier: AGPL-3.0-or-later
//
// hmc/status.hpp — status codes and the Result type used at every public
// entry point of libhmc.
//
// libhmc never lets an exception cross its public API. Every operation that
// can fail returns either a `Status` or a `Result<T>`, which holds a value or
// an `Error` (a status code plus a human-readable message that says what was
// wrong and where).
//
// The stream error classes (`bad_magic` … `limit_exceeded`) are the error
// classes named in the HMC specification (spec/hmc.md, section "Errors"); a
// conforming decoder reports one of them for every invalid stream. Their
// names, as returned by `status_name`, are stable and are what the
// conformance runner compares.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <variant>

namespace hmc {

/// Outcome of a libhmc operation. Values are stable across releases.
enum class Status : int {
  ok = 0,

  // --- stream error classes (normative; spec section "Errors") ---
  bad_magic = 1,            ///< the first 8 bytes are not the HMC signature
  unsupported_version = 2,  ///< the major version is not one this decoder knows
  crc_mismatch = 3,         ///< a chunk's CRC-32 does not match its contents
  truncated = 4,            ///< the stream ends before a complete level
  bad_chunk = 5,            ///< chunk length, order, count or type is invalid
  bad_header = 6,           ///< a header or quantizer field is out of range
  bad_huffman_table = 7,    ///< a Huffman code-length table is invalid
  bad_layer = 8,            ///< a vertex layer or side-information payload is malformed
  limit_exceeded = 9,       ///< the stream needs more than the caller's limits allow

  // --- caller and environment errors ---
  invalid_argument = 20,    ///< an argument or option is out of range
  io_error = 21,            ///< a file could not be read or written
  parse_error = 22,         ///< an input mesh or point file is malformed
  unsupported_format = 23,  ///< the file format is not recognised or not supported
  out_of_memory = 24,       ///< an allocation failed
  internal_error = 25,      ///< a bug in libhmc; please report it
};

/// Stable lower-case identifier of a status, e.g. "crc_mismatch".
const char* status_name(Status s) noexcept;

/// One-sentence English description of a status.
const char* status_description(Status s) noexcept;

/// A failed outcome: the status and a message naming what was wrong and where
/// (file, line, byte offset, chunk or field, as applicable).
struct Error {
  Status status = Status::internal_error;
  std::string message;

  /// "status_name: message".
  std::string to_string() const;
};

/// Either a value of type T or an Error. Check `ok()` before `value()`.
template <class T>
class Result {
 public:
  Result(T value) : v_(std::move(value)) {}          // NOLINT(implicit)
  Result(Error error) : v_(std::move(error)) {}      // NOLINT(implicit)
  Result(Status s, std::string message) : v_(Error{s, std::move(message)}) {}

  bool ok() const noexcept { return v_.index() == 0; }
  explicit operator bool() const noexcept { return ok(); }

  /// The value; only valid when ok().
  T& value() & { return std::get<0>(v_); }
  const T& value() const& { return std::get<0>(v_); }
  T&& value() && { return std::get<0>(std::move(v_)); }

  /// The error; only valid when !ok().
  const Error& error() const& { return std::get<1>(v_); }

  /// Status::ok, or the error's status.
  Status status() const noexcept { return ok() ? Status::ok : std::get<1>(v_).status; }

 private:
  std::variant<T, Error> v_;
};

/// Value of a Result that carries no data: `Result<Done>` is ok or an Error.
struct Done {};

}  // namespace hmc
