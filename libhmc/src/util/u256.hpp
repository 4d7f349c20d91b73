// SPDX-License-Identifier: AGPL-3.0-or-later
// Unsigned 256-bit integers, just enough for exact comparisons of products
// of squared lengths (reconstruction rules compare ratios whose cross
// products reach about 2^221 for coordinates below 2^21).
#pragma once

#include <cstdint>

namespace hmc::detail {

struct U256 {
  std::uint64_t w[4] = {0, 0, 0, 0};  // little-endian limbs

  static U256 from(std::uint64_t v) {
    U256 r;
    r.w[0] = v;
    return r;
  }
  /// Product with a 64-bit factor; the caller guarantees no overflow.
  U256 mul(std::uint64_t m) const {
    __extension__ typedef unsigned __int128 U128;
    U256 r;
    U128 carry = 0;
    for (int i = 0; i < 4; ++i) {
      const U128 p = static_cast<U128>(w[i]) * m + carry;
      r.w[i] = static_cast<std::uint64_t>(p);
      carry = p >> 64;
    }
    return r;
  }
  /// Product with a 128-bit factor given as (hi, lo); no overflow allowed.
  U256 mul(std::uint64_t hi, std::uint64_t lo) const {
    U256 a = mul(lo), b = mul(hi);
    // a + (b << 64)
    __extension__ typedef unsigned __int128 U128;
    U256 r;
    U128 carry = 0;
    for (int i = 0; i < 4; ++i) {
      const U128 s = static_cast<U128>(a.w[i]) + (i ? b.w[i - 1] : 0) + carry;
      r.w[i] = static_cast<std::uint64_t>(s);
      carry = s >> 64;
    }
    return r;
  }
  friend int compare(const U256& a, const U256& b) {
    for (int i = 3; i >= 0; --i)
      if (a.w[i] != b.w[i]) return a.w[i] < b.w[i] ? -1 : 1;
    return 0;
  }
  bool is_zero() const { return (w[0] | w[1] | w[2] | w[3]) == 0; }
};

}  // namespace hmc::detail
