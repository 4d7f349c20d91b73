// SPDX-License-Identifier: AGPL-3.0-or-later
// Shared helpers of the fuzz targets: a check that aborts (so libFuzzer, or
// the replay driver under CTest, reports the input) and a little reader
// that takes parameters off the front of a fuzz input.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <type_traits>
#include <utility>
#include <vector>

#include "hmc/codec.hpp"
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

/// A coarser level from the input, as the layer targets read it: u8 q
/// (mapped to 1..21), u8 count c (1..64), then c points of 3 x u24 masked to
/// the 2^q grid; returned distinct and in canonical order, with q.
inline std::vector<hmc::GridPoint> read_coarse_level(Params& params, int& q) {
  q = 1 + params.u8() % 21;
  const std::uint32_t mask = (std::uint32_t{1} << q) - 1;
  const int c = 1 + params.u8() % 64;
  std::vector<hmc::GridPoint> coarse;
  for (int i = 0; i < c; ++i) coarse.push_back({params.u24() & mask, params.u24() & mask, params.u24() & mask});
  std::sort(coarse.begin(), coarse.end());
  coarse.erase(std::unique(coarse.begin(), coarse.end()), coarse.end());
  return coarse;
}

/// The properties every decoded refinement layer has, whatever its coder:
/// exactly `n` distinct points on the 2^q grid, in canonical order, none of
/// them a point of the coarser level.
inline void check_added_layer(const std::vector<hmc::GridPoint>& added, const std::vector<hmc::GridPoint>& coarse,
                              std::uint64_t n, int q) {
  const std::uint32_t mask = (std::uint32_t{1} << q) - 1;
  FUZZ_CHECK(added.size() == n, "%zu points decoded, %llu asked for", added.size(), static_cast<unsigned long long>(n));
  FUZZ_CHECK(std::is_sorted(added.begin(), added.end()), "added points not in canonical order");
  FUZZ_CHECK(std::adjacent_find(added.begin(), added.end()) == added.end(), "duplicate added points");
  for (const auto& p : added) {
    for (auto x : p) FUZZ_CHECK(x <= mask, "coordinate %u outside the 2^%d grid", x, q);
    FUZZ_CHECK(!std::binary_search(coarse.begin(), coarse.end(), p), "an added point repeats a coarser one");
  }
}

// The codec's reconstruction (DecodeOptions::reconstruct, triangles and
// tetrahedra in DecodedLevel and Encoded) is used when the library has it;
// these let the targets compile against the library with or without it.
template <class T, class = void>
struct has_reconstruct_option : std::false_type {};
template <class T>
struct has_reconstruct_option<T, std::void_t<decltype(std::declval<T&>().reconstruct)>> : std::true_type {};

template <class T, class = void>
struct has_connectivity : std::false_type {};
template <class T>
struct has_connectivity<T, std::void_t<decltype(std::declval<T&>().triangles.size()),
                                       decltype(std::declval<T&>().tetrahedra.size())>> : std::true_type {};

/// Turns reconstruction on or off; false if the library cannot reconstruct.
template <class Options>
bool set_reconstruct(Options& o, bool on) {
  if constexpr (has_reconstruct_option<Options>::value) {
    o.reconstruct = on;
    return true;
  } else {
    (void)o;
    (void)on;
    return false;
  }
}

/// Number of triangles plus tetrahedra of a decoded level or an encoding,
/// after checking that every index is below `points` and that no element
/// repeats a vertex. Zero when the library has no connectivity.
template <class T>
std::size_t check_connectivity(const T& x, std::size_t points) {
  if constexpr (has_connectivity<T>::value) {
    for (const auto& t : x.triangles) {
      for (auto v : t) FUZZ_CHECK(v < points, "triangle vertex %u of %zu points", unsigned(v), points);
      FUZZ_CHECK(t[0] != t[1] && t[1] != t[2] && t[0] != t[2], "degenerate triangle");
    }
    for (const auto& t : x.tetrahedra) {
      for (auto v : t) FUZZ_CHECK(v < points, "tetrahedron vertex %u of %zu points", unsigned(v), points);
      FUZZ_CHECK(t[0] != t[1] && t[0] != t[2] && t[0] != t[3] && t[1] != t[2] && t[1] != t[3] && t[2] != t[3],
                 "degenerate tetrahedron");
    }
    return x.triangles.size() + x.tetrahedra.size();
  } else {
    (void)x;
    (void)points;
    return 0;
  }
}

/// True when both have the same connectivity (or the library has none).
template <class A, class B>
bool same_connectivity(const A& a, const B& b) {
  if constexpr (has_connectivity<A>::value && has_connectivity<B>::value)
    return a.triangles == b.triangles && a.tetrahedra == b.tetrahedra;
  else {
    (void)a;
    (void)b;
    return true;
  }
}

}  // namespace hmc_fuzz
