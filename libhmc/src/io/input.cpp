// SPDX-License-Identifier: AGPL-3.0-or-later
#include "io/input.hpp"

#include <cmath>
#include <limits>

namespace hmc::io::detail {

std::string_view Input::token(std::string_view what) {
  std::string_view t;
  if (!next_token(t)) {
    mark_ = pos_;  // the line stays that of the last token: the file may end in a newline
    fail("unexpected end of file, expected " + std::string(what));
  }
  return t;
}

void Input::expect_keyword(std::string_view keyword) {
  const std::string_view t = token(keyword);
  if (!iequals(t, keyword)) fail("expected " + std::string(keyword) + ", found " + quote(t));
}

void Input::skip_line() noexcept {
  if (pos_ >= data_.size()) return;
  const char* b = data_.data() + pos_;
  const auto* nl = static_cast<const char*>(std::memchr(b, '\n', data_.size() - pos_));
  if (nl) {
    pos_ += static_cast<std::size_t>(nl - b) + 1;
    ++cur_line_;
  } else {
    pos_ = data_.size();
  }
}

void Input::end_header_line(std::string_view what) {
  while (pos_ < data_.size() && (data_[pos_] == ' ' || data_[pos_] == '\t' || data_[pos_] == '\r')) ++pos_;
  if (pos_ >= data_.size()) return;
  if (data_[pos_] != '\n') {
    mark_ = pos_;
    fail("unexpected text after " + std::string(what) + " before its binary data");
  }
  ++pos_;
  ++cur_line_;
}

void Input::skip_to(std::size_t new_pos) noexcept {
  if (new_pos > data_.size()) new_pos = data_.size();
  for (; pos_ < new_pos; ++pos_)
    if (data_[pos_] == '\n') ++cur_line_;
}

double Input::real(std::string_view tok, std::string_view what) const {
  double v;
  if (!parse_double(tok, v)) fail("expected a number for " + std::string(what) + ", found " + quote(tok));
  if (!std::isfinite(v)) fail("non-finite " + std::string(what) + " " + quote(tok));
  return v;
}

std::int64_t Input::integer(std::string_view tok, std::string_view what) const {
  std::int64_t v;
  if (!parse_int(tok, v)) fail("expected an integer for " + std::string(what) + ", found " + quote(tok));
  return v;
}

std::uint64_t Input::count(std::string_view tok, std::string_view what) const {
  const std::int64_t v = integer(tok, what);
  if (v < 0) fail("negative " + std::string(what) + " " + quote(tok));
  return static_cast<std::uint64_t>(v);
}

void Input::check_text_count(std::uint64_t n, std::uint64_t fields, std::string_view what) const {
  // Each field takes at least one character plus a separator.
  const std::uint64_t per = 2 * (fields > 0 ? fields : 1);
  const std::uint64_t room = remaining() + 1;
  if (n > room / per)
    fail(std::string(what) + " count " + std::to_string(n) + " is more than the " + std::to_string(remaining()) +
         " remaining bytes of the file can hold");
}

void Input::check_binary_count(std::uint64_t n, std::uint64_t bytes, std::string_view what) const {
  if (bytes == 0) return;
  if (n <= remaining() / bytes) return;
  const std::string message = std::string(what) + " count " + std::to_string(n) + " needs more than the " +
                              std::to_string(remaining()) + " remaining bytes of the file";
  if (binary_) fail_at_offset(pos_, message);
  fail(message);
}

double Input::read_f64(bool big_endian, std::string_view what) {
  const std::uint64_t bits = read_uint<std::uint64_t>(big_endian, what);
  double v;
  std::memcpy(&v, &bits, sizeof v);
  return v;
}

double Input::read_scalar(Scalar t, bool big_endian, std::string_view what) {
  const unsigned char* p = take(scalar_size(t), what);
  switch (t) {
    case Scalar::i8: return static_cast<std::int8_t>(p[0]);
    case Scalar::u8: return p[0];
    case Scalar::i16: return static_cast<std::int16_t>(load_uint<std::uint16_t>(p, big_endian));
    case Scalar::u16: return load_uint<std::uint16_t>(p, big_endian);
    case Scalar::i32: return static_cast<std::int32_t>(load_uint<std::uint32_t>(p, big_endian));
    case Scalar::u32: return load_uint<std::uint32_t>(p, big_endian);
    case Scalar::i64: return static_cast<double>(static_cast<std::int64_t>(load_uint<std::uint64_t>(p, big_endian)));
    case Scalar::u64: return static_cast<double>(load_uint<std::uint64_t>(p, big_endian));
    case Scalar::f32: {
      const std::uint32_t bits = load_uint<std::uint32_t>(p, big_endian);
      float f;
      std::memcpy(&f, &bits, sizeof f);
      return f;
    }
    case Scalar::f64: {
      const std::uint64_t bits = load_uint<std::uint64_t>(p, big_endian);
      double d;
      std::memcpy(&d, &bits, sizeof d);
      return d;
    }
  }
  return 0;
}

std::int64_t Input::read_integer(Scalar t, bool big_endian, std::string_view what) {
  const unsigned char* p = take(scalar_size(t), what);
  switch (t) {
    case Scalar::i8: return static_cast<std::int8_t>(p[0]);
    case Scalar::u8: return p[0];
    case Scalar::i16: return static_cast<std::int16_t>(load_uint<std::uint16_t>(p, big_endian));
    case Scalar::u16: return load_uint<std::uint16_t>(p, big_endian);
    case Scalar::i32: return static_cast<std::int32_t>(load_uint<std::uint32_t>(p, big_endian));
    case Scalar::u32: return load_uint<std::uint32_t>(p, big_endian);
    case Scalar::i64: return static_cast<std::int64_t>(load_uint<std::uint64_t>(p, big_endian));
    case Scalar::u64: {
      const std::uint64_t v = load_uint<std::uint64_t>(p, big_endian);
      return v > static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max())
                 ? std::numeric_limits<std::int64_t>::max()
                 : static_cast<std::int64_t>(v);
    }
    case Scalar::f32:
    case Scalar::f64: break;
  }
  // Integer types only: callers check scalar_is_integer first.
  return 0;
}

void Input::fail(const std::string& message) const {
  if (binary_) fail_at_offset(mark_, message);
  fail_at_line(line_, message);
}

void Input::fail_at_line(std::size_t line, const std::string& message) const {
  hmc::detail::fail(Status::parse_error, name_ + ":" + std::to_string(line) + ": " + message);
}

void Input::fail_at_offset(std::size_t offset, const std::string& message) const {
  hmc::detail::fail(Status::parse_error, name_ + ": byte offset " + std::to_string(offset) + ": " + message);
}

void Input::truncated(std::uint64_t n, std::string_view what) const {
  fail_at_offset(pos_, "unexpected end of file in " + std::string(what) + " (needs " + std::to_string(n) +
                           " bytes, " + std::to_string(remaining()) + " left)");
}

}  // namespace hmc::io::detail
