// SPDX-License-Identifier: AGPL-3.0-or-later
// Bit packing (spec "Conventions: bit order"): bits fill each byte from its
// most significant bit down; a field of n bits is written most significant
// bit first. A bit stream ends with zero bits up to the next byte boundary.
#pragma once

#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "util/error.hpp"

namespace hmc::detail {

class BitWriter {
 public:
  /// Append the low `n` bits of `v` (n <= 32), most significant first.
  void put(std::uint32_t v, int n) {
    for (int i = n - 1; i >= 0; --i) {
      acc_ = static_cast<std::uint8_t>((acc_ << 1) | ((v >> i) & 1u));
      if (++nacc_ == 8) {
        out_.push_back(acc_);
        acc_ = 0;
        nacc_ = 0;
      }
    }
  }
  /// Order-0 exponential-Golomb code of v (v < 2^31).
  void exp_golomb(std::uint32_t v) {
    std::uint32_t x = v + 1;
    int bits = 0;
    while ((x >> bits) > 1) ++bits;
    put(0, bits);
    put(x, bits + 1);
  }
  /// Pad with zero bits to a byte boundary and return the bytes.
  std::vector<std::uint8_t> finish() {
    if (nacc_) put(0, 8 - nacc_);
    return std::move(out_);
  }
  std::uint64_t bit_count() const { return out_.size() * 8 + static_cast<std::uint64_t>(nacc_); }

 private:
  std::vector<std::uint8_t> out_;
  std::uint8_t acc_ = 0;
  int nacc_ = 0;
};

/// Reads bits from a bounded buffer. Reading past the end raises bad_layer.
class BitReader {
 public:
  BitReader(const std::uint8_t* p, std::size_t n, std::string what)
      : p_(p), nbytes_(n), nbits_(std::uint64_t{n} * 8), what_(std::move(what)) {}

  /// The next n bits (n <= 32).
  std::uint32_t get(int n) {
    if (static_cast<std::uint64_t>(n) > nbits_ - pos_) overrun();
    const std::uint32_t v = peek(n);
    pos_ += static_cast<std::uint64_t>(n);
    return v;
  }
  /// The next `n` bits (n <= 32) without consuming them; zeros past the end.
  std::uint32_t peek(int n) const {
    return n == 0 ? 0 : static_cast<std::uint32_t>(window() >> (64 - n));
  }
  void consume(int n) {
    if (static_cast<std::uint64_t>(n) > nbits_ - pos_) overrun();
    pos_ += static_cast<std::uint64_t>(n);
  }
  std::uint32_t exp_golomb() {
    int zeros = 0;
    while (get(1) == 0)
      if (++zeros > 31) fail(Status::bad_layer, what_ + ": exp-Golomb prefix longer than 31 bits");
    std::uint64_t x = (std::uint64_t{1} << zeros) | get(zeros);
    return static_cast<std::uint32_t>(x - 1);
  }
  /// Require that only zero padding to the next byte boundary remains and
  /// that it is the end of the buffer.
  void expect_end() {
    std::uint64_t pad = (8 - (pos_ & 7)) & 7;
    if (pad > nbits_ - pos_ || get(static_cast<int>(pad)) != 0)
      fail(Status::bad_layer, what_ + ": non-zero padding bits");
    if (pos_ != nbits_)
      fail(Status::bad_layer, what_ + ": " + std::to_string((nbits_ - pos_) / 8) + " unused byte(s) after the bit stream");
  }
  std::uint64_t bits_left() const { return nbits_ - pos_; }
  /// Skip the zero padding to the next byte boundary and return the number
  /// of bytes consumed so far (for bit streams followed by byte fields).
  std::size_t align() {
    const std::uint64_t pad = (8 - (pos_ & 7)) & 7;
    if (pad > nbits_ - pos_ || get(static_cast<int>(pad)) != 0)
      fail(Status::bad_layer, what_ + ": non-zero padding bits");
    return static_cast<std::size_t>(pos_ / 8);
  }

 private:
  // 64 bits starting at the current position, at least 57 of them real
  // (zeros beyond the end of the buffer).
  std::uint64_t window() const {
    const std::size_t byte = static_cast<std::size_t>(pos_ >> 3);
    std::uint64_t w = 0;
    if (byte + 8 <= nbytes_) {
#if defined(__GNUC__) && defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
      std::memcpy(&w, p_ + byte, 8);  // one load: the loop below is not fused by the compiler
      w = __builtin_bswap64(w);
#else
      for (int i = 0; i < 8; ++i) w = (w << 8) | p_[byte + static_cast<std::size_t>(i)];
#endif
    } else {
      for (std::size_t i = 0; i < 8; ++i) w = (w << 8) | (byte + i < nbytes_ ? p_[byte + i] : 0u);
    }
    return w << (pos_ & 7);
  }
  [[noreturn]] void overrun() const {
    fail(Status::bad_layer, what_ + ": bit stream ends early (at bit " + std::to_string(pos_) + " of " +
                                std::to_string(nbits_) + ")");
  }
  const std::uint8_t* p_;
  std::size_t nbytes_;
  std::uint64_t nbits_;
  std::uint64_t pos_ = 0;
  std::string what_;
};

}  // namespace hmc::detail
