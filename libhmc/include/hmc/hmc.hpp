// SPDX-License-Identifier: AGPL-3.0-or-later
/**
 * @file hmc.hpp
 * @brief A thin C++17 layer over the C API (`<hmc/hmc.h>`): RAII handles and
 *        results instead of status codes.
 *
 * Header only; it calls nothing but the C functions, so a program built
 * against it depends only on the C ABI of libhmc. Handles are
 * `std::unique_ptr`s with deleters that call the C destroy functions, and
 * buffers the C API returns are owned by Buffer, which frees them with the
 * allocator that made them. No function here throws, except that the
 * standard library may throw `std::bad_alloc` when building a std::string.
 *
 * @code
 * auto dec = hmc::capi::Decoder::create();
 * if (!dec) return 1;
 * for (;;) {                                   // bytes arrive
 *   auto n = dec.value().feed(piece, piece_size);   // levels complete so far
 *   if (!n) { std::cerr << n.error().to_string() << "\n"; break; }
 *   ...
 * }
 * auto end = dec.value().finish();             // HMC_OK, or HMC_INCOMPLETE for a cut stream
 * auto pts = dec.value().positions(dec.value().level_count() - 1);
 * @endcode
 */
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <variant>

#include "hmc/hmc.h"

namespace hmc::capi {

/// A failed call: the status and the handle's message.
struct Error {
  hmc_status status = HMC_INTERNAL_ERROR;  ///< what failed
  std::string message;                     ///< the handle's message: what was wrong and where

  /// "status_name: message".
  std::string to_string() const {
    std::string s = hmc_status_string(status);
    if (!message.empty()) s += ": " + message;
    return s;
  }
};

/// Either a value of type T or an Error. Check ok() before value().
template <class T>
class Result {
 public:
  /// A success holding `value`.
  Result(T value) : v_(std::move(value)) {}  // NOLINT(implicit)
  /// A failure.
  Result(Error error) : v_(std::move(error)) {}  // NOLINT(implicit)

  /// True when it holds a value.
  bool ok() const noexcept { return v_.index() == 0; }
  /// ok().
  explicit operator bool() const noexcept { return ok(); }
  /// The value; only when ok().
  T& value() & { return std::get<0>(v_); }
  /// The value; only when ok().
  const T& value() const& { return std::get<0>(v_); }
  /// The value, moved out; only when ok().
  T&& value() && { return std::get<0>(std::move(v_)); }
  /// The error; only when !ok().
  const Error& error() const& { return std::get<1>(v_); }
  /// HMC_OK, or the error's status.
  hmc_status status() const noexcept { return ok() ? HMC_OK : std::get<1>(v_).status; }

 private:
  std::variant<T, Error> v_;
};

/// Value of a Result that carries nothing.
struct Done {};

/// Deleters for the C handles.
struct Deleter {
  /// hmc_encoder_destroy().
  void operator()(hmc_encoder* e) const noexcept { hmc_encoder_destroy(e); }
  /// hmc_decoder_destroy().
  void operator()(hmc_decoder* d) const noexcept { hmc_decoder_destroy(d); }
};
/// An owned hmc_encoder.
using EncoderHandle = std::unique_ptr<hmc_encoder, Deleter>;
/// An owned hmc_decoder.
using DecoderHandle = std::unique_ptr<hmc_decoder, Deleter>;

/// A buffer returned by the C API: `size()` values of type T, freed with the
/// allocator of the handle that returned it.
template <class T>
class Buffer {
 public:
  Buffer() = default;
  /// Take ownership of `data` (may be null when `size` is 0).
  Buffer(T* data, std::size_t size, const hmc_allocator* allocator) noexcept
      : p_(data, Free{allocator ? *allocator : hmc_allocator{}, allocator != nullptr}), n_(size) {}

  /// The values (null when empty).
  T* data() noexcept { return p_.get(); }
  /// The values (null when empty).
  const T* data() const noexcept { return p_.get(); }
  /// Number of values (for points: 3 per point).
  std::size_t size() const noexcept { return n_; }
  /// True when there are no values.
  bool empty() const noexcept { return n_ == 0; }
  /// Value `i`.
  T& operator[](std::size_t i) noexcept { return p_.get()[i]; }
  /// Value `i`.
  const T& operator[](std::size_t i) const noexcept { return p_.get()[i]; }
  /// Iteration over the values.
  T* begin() noexcept { return p_.get(); }
  /// Iteration over the values.
  T* end() noexcept { return p_.get() + n_; }
  /// Iteration over the values.
  const T* begin() const noexcept { return p_.get(); }
  /// Iteration over the values.
  const T* end() const noexcept { return p_.get() + n_; }

 private:
  struct Free {
    hmc_allocator alloc{};
    bool custom = false;
    void operator()(T* p) const noexcept { hmc_free(custom ? &alloc : nullptr, p); }
  };
  std::unique_ptr<T, Free> p_{nullptr, Free{}};
  std::size_t n_ = 0;
};

/// An encoder (hmc_encoder).
class Encoder {
 public:
  /// A new encoder with default settings; `allocator` (copied) as in hmc_encoder_create().
  static Result<Encoder> create(const hmc_allocator* allocator = nullptr) {
    EncoderHandle h(hmc_encoder_create(allocator));
    if (!h) return Error{allocator ? HMC_INVALID_ARGUMENT : HMC_OUT_OF_MEMORY, "hmc_encoder_create failed"};
    return Encoder(std::move(h), allocator);
  }

  /// Replace the settings (start from defaults()).
  Result<Done> set_options(const hmc_encode_options& options) {
    return check(hmc_encoder_set_options(h_.get(), &options));
  }
  /// Threads an encode may use, the caller's included (hmc_encoder_set_threads()).
  Result<Done> set_threads(unsigned threads) { return check(hmc_encoder_set_threads(h_.get(), threads)); }
  /// The default settings.
  static hmc_encode_options defaults() noexcept {
    hmc_encode_options o;
    hmc_encode_options_init(&o);
    return o;
  }

  /// Encode 3 * `points` coordinates, with optional triangles (3 indices
  /// each) and tetrahedra (4 each); see hmc_encoder_encode().
  Result<Buffer<std::uint8_t>> encode(const double* xyz, std::size_t points, const std::uint32_t* triangles = nullptr,
                                      std::size_t triangle_count = 0, const std::uint32_t* tetrahedra = nullptr,
                                      std::size_t tetrahedron_count = 0) {
    std::uint8_t* bytes = nullptr;
    std::size_t size = 0;
    const hmc_status s = hmc_encoder_encode(h_.get(), xyz, points, triangles, triangle_count, tetrahedra,
                                            tetrahedron_count, &bytes, &size);
    if (s != HMC_OK) return error(s);
    return Buffer<std::uint8_t>(bytes, size, allocator());
  }

  /// The C handle, still owned by this object.
  hmc_encoder* get() const noexcept { return h_.get(); }
  /// hmc_encoder_message().
  std::string message() const { return hmc_encoder_message(h_.get()); }
  /// hmc_encoder_notes().
  std::string notes() const { return hmc_encoder_notes(h_.get()); }

 private:
  Encoder(EncoderHandle h, const hmc_allocator* a) : h_(std::move(h)), alloc_(a ? *a : hmc_allocator{}), custom_(a != nullptr) {}
  const hmc_allocator* allocator() const noexcept { return custom_ ? &alloc_ : nullptr; }
  Error error(hmc_status s) const { return Error{s, hmc_encoder_message(h_.get())}; }
  Result<Done> check(hmc_status s) const {
    if (s != HMC_OK) return error(s);
    return Done{};
  }
  EncoderHandle h_;
  hmc_allocator alloc_;
  bool custom_;
};

/// A decoder (hmc_decoder): whole buffers or a stream fed in pieces.
class Decoder {
 public:
  /// A new decoder; `allocator` (copied) as in hmc_decoder_create().
  static Result<Decoder> create(const hmc_allocator* allocator = nullptr) {
    DecoderHandle h(hmc_decoder_create(allocator));
    if (!h) return Error{allocator ? HMC_INVALID_ARGUMENT : HMC_OUT_OF_MEMORY, "hmc_decoder_create failed"};
    return Decoder(std::move(h), allocator);
  }

  /// Caps, before decoding begins (hmc_decoder_set_limits()).
  Result<Done> set_limits(std::uint64_t max_points, std::uint32_t max_levels, std::uint64_t max_bytes) {
    return check(hmc_decoder_set_limits(h_.get(), max_points, max_levels, max_bytes));
  }
  /// Memory cap, before decoding begins (hmc_decoder_set_memory_limit()).
  Result<Done> set_memory_limit(std::uint64_t max_memory) {
    return check(hmc_decoder_set_memory_limit(h_.get(), max_memory));
  }
  /// Stop after this level (hmc_decoder_set_finest_level()).
  Result<Done> set_finest_level(int level) { return check(hmc_decoder_set_finest_level(h_.get(), level)); }
  /// When defects are reported when feeding (hmc_decoder_set_error_order()).
  Result<Done> set_error_order(hmc_error_order order) {
    return check(hmc_decoder_set_error_order(h_.get(), order));
  }
  /// Rebuild triangles or tetrahedra, or only points (hmc_decoder_set_reconstruct()).
  Result<Done> set_reconstruct(bool on) { return check(hmc_decoder_set_reconstruct(h_.get(), on ? 1 : 0)); }
  /// Rebuild every level, or only the finest decoded one
  /// (hmc_decoder_set_rebuild_coarser_levels()).
  Result<Done> set_rebuild_coarser_levels(bool all) {
    return check(hmc_decoder_set_rebuild_coarser_levels(h_.get(), all ? 1 : 0));
  }
  /// Threads a whole-buffer decode may use, the caller's included
  /// (hmc_decoder_set_threads()).
  Result<Done> set_threads(unsigned threads) { return check(hmc_decoder_set_threads(h_.get(), threads)); }

  /// Decode a whole buffer (hmc_decoder_decode()).
  /// @param data the stream
  /// @param size its length in bytes
  /// @return HMC_OK, or HMC_INCOMPLETE for a stream cut after a complete
  ///         level (message() says where); or the error
  Result<hmc_status> decode(const void* data, std::size_t size) {
    return outcome(hmc_decoder_decode(h_.get(), data, size));
  }
  /// Feed the next bytes. Value: the number of complete levels so far.
  Result<std::size_t> feed(const void* data, std::size_t size) {
    const hmc_status s = hmc_decoder_feed(h_.get(), data, size);
    if (s != HMC_OK) return error(s);
    return level_count();
  }
  /// End of the stream (hmc_decoder_finish()).
  /// @return HMC_OK, or HMC_INCOMPLETE for a stream cut after a complete
  ///         level (message() says where); or the error
  Result<hmc_status> finish() { return outcome(hmc_decoder_finish(h_.get())); }

  /// Complete levels so far, numbered from 0 (the coarsest).
  std::size_t level_count() const noexcept { return hmc_decoder_level_count(h_.get()); }
  /// Header and progress.
  hmc_stream_info stream_info() const noexcept {
    hmc_stream_info i{};
    hmc_decoder_stream_info(h_.get(), &i);
    return i;
  }
  /// Figures of complete level `index` (0 = the coarsest).
  Result<hmc_level_info> level_info(std::size_t index) const {
    hmc_level_info i{};
    const hmc_status s = hmc_decoder_level_info(h_.get(), index, &i);
    if (s != HMC_OK) return error(s);
    return i;
  }
  /// Grid points, 3 per point.
  Result<Buffer<std::uint32_t>> points(std::size_t index) const {
    return take<std::uint32_t>(index, 3, hmc_decoder_level_points);
  }
  /// Dequantized positions, 3 per point.
  Result<Buffer<double>> positions(std::size_t index) const {
    return take<double>(index, 3, hmc_decoder_level_positions);
  }
  /// Triangles, 3 indices each.
  Result<Buffer<std::uint32_t>> triangles(std::size_t index) const {
    return take<std::uint32_t>(index, 3, hmc_decoder_level_triangles);
  }
  /// Tetrahedra, 4 indices each.
  Result<Buffer<std::uint32_t>> tetrahedra(std::size_t index) const {
    return take<std::uint32_t>(index, 4, hmc_decoder_level_tetrahedra);
  }

  /// hmc_decoder_status().
  hmc_status status() const noexcept { return hmc_decoder_status(h_.get()); }
  /// hmc_decoder_message().
  std::string message() const { return hmc_decoder_message(h_.get()); }
  /// The C handle, still owned by this object.
  hmc_decoder* get() const noexcept { return h_.get(); }

 private:
  Decoder(DecoderHandle h, const hmc_allocator* a) : h_(std::move(h)), alloc_(a ? *a : hmc_allocator{}), custom_(a != nullptr) {}
  const hmc_allocator* allocator() const noexcept { return custom_ ? &alloc_ : nullptr; }
  Error error(hmc_status s) const { return Error{s, hmc_decoder_message(h_.get())}; }
  Result<Done> check(hmc_status s) const {
    if (s != HMC_OK) return error(s);
    return Done{};
  }
  Result<hmc_status> outcome(hmc_status s) const {
    if (s != HMC_OK && s != HMC_INCOMPLETE) return error(s);
    return s;
  }
  template <class T, class F>
  Result<Buffer<T>> take(std::size_t index, std::size_t per, F f) const {
    T* p = nullptr;
    std::size_t n = 0;
    const hmc_status s = f(h_.get(), index, &p, &n);
    if (s != HMC_OK) return error(s);
    return Buffer<T>(p, per * n, allocator());
  }
  DecoderHandle h_;
  hmc_allocator alloc_;
  bool custom_;
};

}  // namespace hmc::capi
