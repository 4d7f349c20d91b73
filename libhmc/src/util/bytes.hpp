// SPDX-License-Identifier: AGPL-3.0-or-later
// Byte-level writing and bounds-checked reading of the stream's integer
// encodings (spec "Conventions"): little-endian fixed-width integers,
// binary64, and LEB128 varints in their shortest form.
#pragma once

#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "util/error.hpp"

namespace hmc::detail {

class ByteWriter {
 public:
  void u8(std::uint8_t v) { buf_.push_back(v); }
  void u16(std::uint16_t v) { fixed(v, 2); }
  void u32(std::uint32_t v) { fixed(v, 4); }
  void u64(std::uint64_t v) { fixed(v, 8); }
  void f64(double v) {
    std::uint64_t b;
    std::memcpy(&b, &v, 8);
    u64(b);
  }
  void varint(std::uint64_t v) {
    while (v >= 0x80) {
      buf_.push_back(static_cast<std::uint8_t>(v | 0x80));
      v >>= 7;
    }
    buf_.push_back(static_cast<std::uint8_t>(v));
  }
  void bytes(const std::uint8_t* p, std::size_t n) { buf_.insert(buf_.end(), p, p + n); }
  void bytes(const std::vector<std::uint8_t>& v) { bytes(v.data(), v.size()); }

  std::vector<std::uint8_t>& data() { return buf_; }
  std::size_t size() const { return buf_.size(); }

 private:
  void fixed(std::uint64_t v, int n) {
    for (int i = 0; i < n; ++i) buf_.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
  }
  std::vector<std::uint8_t> buf_;
};

/// Reads from a bounded span; every overrun raises `fail` with the status
/// given at construction (bad_layer inside a chunk payload, truncated for
/// the file itself).
class ByteReader {
 public:
  ByteReader(const std::uint8_t* p, std::size_t n, Status overrun, std::string what)
      : p_(p), n_(n), overrun_(overrun), what_(std::move(what)) {}

  std::size_t pos() const { return pos_; }
  std::size_t remaining() const { return n_ - pos_; }
  bool at_end() const { return pos_ == n_; }
  const std::uint8_t* here() const { return p_ + pos_; }

  std::uint8_t u8() {
    need(1);
    return p_[pos_++];
  }
  std::uint16_t u16() { return static_cast<std::uint16_t>(fixed(2)); }
  std::uint32_t u32() { return static_cast<std::uint32_t>(fixed(4)); }
  std::uint64_t u64() { return fixed(8); }
  double f64() {
    std::uint64_t b = u64();
    double v;
    std::memcpy(&v, &b, 8);
    return v;
  }
  std::uint64_t varint() {
    std::uint64_t v = 0;
    for (int shift = 0;; shift += 7) {
      std::uint8_t b = u8();
      if (shift == 63 && b > 1) fail(overrun_, what_ + ": varint overflows 64 bits");
      v |= static_cast<std::uint64_t>(b & 0x7f) << shift;
      if (!(b & 0x80)) {
        if (b == 0 && shift != 0) fail(overrun_, what_ + ": varint is not in its shortest form");
        return v;
      }
    }
  }
  void skip(std::size_t n) {
    need(n);
    pos_ += n;
  }
  void need(std::size_t n) const {
    if (n > n_ - pos_)
      fail(overrun_, what_ + ": needs " + std::to_string(n) + " more byte(s) at offset " +
                         std::to_string(pos_) + ", only " + std::to_string(n_ - pos_) + " left");
  }

 private:
  std::uint64_t fixed(int n) {
    need(static_cast<std::size_t>(n));
    std::uint64_t v = 0;
    for (int i = 0; i < n; ++i) v |= static_cast<std::uint64_t>(p_[pos_ + i]) << (8 * i);
    pos_ += static_cast<std::size_t>(n);
    return v;
  }
  const std::uint8_t* p_;
  std::size_t n_;
  std::size_t pos_ = 0;
  Status overrun_;
  std::string what_;
};

}  // namespace hmc::detail
