// SPDX-License-Identifier: AGPL-3.0-or-later
// Shared helpers of the fuzz targets: a check that aborts (so libFuzzer, or
// the replay driver under CTest, reports the input) and a little reader
// that takes parameters off the front of a fuzz input.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>

#include "hmc/status.hpp"

#define FUZZ_CHECK(cond, ...)                                                   \
  do {                                                                          \
    if (!(cond)) {                                                              \
      std::fprintf(stderr, "%s:%d: check failed: %s\n  ", __FILE__, __LINE__, #cond); \
      std::fprintf(stderr, __VA_ARGS__);                                        \
      std::fprintf(stderr, "\n");                                               \
      std::abort();                                                             \
    }                                                                           \
  } while (0)

namespace hmc_fuzz {

/// Takes bytes off the front of the input; past the end it yields zeros.
class Params {
 public:
  Params(const std::uint8_t* data, std::size_t size) : p_(data), n_(size) {}

  std::uint8_t u8() { return pos_ < n_ ? p_[pos_++] : 0; }
  std::uint32_t u16() { return u8() | (std::uint32_t{u8()} << 8); }
  std::uint32_t u24() { return u16() | (std::uint32_t{u8()} << 16); }
  std::uint32_t u32() { return u24() | (std::uint32_t{u8()} << 24); }

  const std::uint8_t* rest() const { return p_ + pos_; }
  std::size_t rest_size() const { return pos_ < n_ ? n_ - pos_ : 0; }

 private:
  const std::uint8_t* p_;
  std::size_t n_;
  std::size_t pos_ = 0;
};

/// The stream error classes of the spec (the statuses a decoder may return
/// for a bad stream).
inline bool is_stream_error(hmc::Status s) {
  switch (s) {
    case hmc::Status::bad_magic:
    case hmc::Status::unsupported_version:
    case hmc::Status::crc_mismatch:
    case hmc::Status::truncated:
    case hmc::Status::bad_chunk:
    case hmc::Status::bad_header:
    case hmc::Status::bad_huffman_table:
    case hmc::Status::bad_layer:
    case hmc::Status::limit_exceeded: return true;
    default: return false;
  }
}

}  // namespace hmc_fuzz
