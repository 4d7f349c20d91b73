// SPDX-License-Identifier: AGPL-3.0-or-later
#include "io/common.hpp"

#include <charconv>
#include <cmath>
#include <cstring>
#include <limits>


namespace hmc::io::detail {

namespace {

char lower(char c) noexcept { return (c >= 'A' && c <= 'Z') ? static_cast<char>(c - 'A' + 'a') : c; }

// Strips one leading '+', which from_chars does not accept; "+-1" stays
// invalid.
bool strip_plus(std::string_view& s) noexcept {
  if (!s.empty() && s[0] == '+') {
    s.remove_prefix(1);
    if (s.empty() || s[0] == '-' || s[0] == '+') return false;
  }
  return !s.empty();
}

// from_chars reports out-of-range without a value; decide from the decimal
// exponent whether the number was too large (-> infinity) or too small (-> 0).
double out_of_range_value(std::string_view s) noexcept {
  bool neg = false;
  std::size_t i = 0;
  if (i < s.size() && (s[i] == '-' || s[i] == '+')) neg = s[i++] == '-';
  std::int64_t int_digits = 0, lead_zeros = 0;
  bool nonzero = false, after_point = false;
  for (; i < s.size(); ++i) {
    const char c = s[i];
    if (c == '.') {
      after_point = true;
    } else if (c >= '0' && c <= '9') {
      if (c != '0') nonzero = true;
      if (!after_point && nonzero) ++int_digits;
      if (after_point && !nonzero && c == '0') ++lead_zeros;
    } else {
      break;
    }
  }
  std::int64_t exp = 0;
  if (i < s.size() && (s[i] == 'e' || s[i] == 'E')) {
    ++i;
    bool eneg = false;
    if (i < s.size() && (s[i] == '-' || s[i] == '+')) eneg = s[i++] == '-';
    for (; i < s.size() && s[i] >= '0' && s[i] <= '9'; ++i)
      if (exp < 1000000) exp = exp * 10 + (s[i] - '0');
    if (eneg) exp = -exp;
  }
  const std::int64_t magnitude = (int_digits > 0 ? int_digits : -lead_zeros) + exp;
  const double v = magnitude > 0 ? std::numeric_limits<double>::infinity() : 0.0;
  return neg ? -v : v;
}

}  // namespace

bool iequals(std::string_view a, std::string_view b) noexcept {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (lower(a[i]) != lower(b[i])) return false;
  return true;
}

bool istarts_with(std::string_view s, std::string_view prefix) noexcept {
  return s.size() >= prefix.size() && iequals(s.substr(0, prefix.size()), prefix);
}

std::string_view trim(std::string_view s) noexcept {
  while (!s.empty() && is_space(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_space(s.back())) s.remove_suffix(1);
  return s;
}

std::string to_lower(std::string_view s) {
  std::string r(s);
  for (char& c : r) c = lower(c);
  return r;
}

std::string quote(std::string_view s) {
  constexpr std::size_t kMax = 40;
  std::string r = "'";
  const std::size_t n = s.size() < kMax ? s.size() : kMax;
  for (std::size_t i = 0; i < n; ++i) {
    const auto c = static_cast<unsigned char>(s[i]);
    if (c >= 0x20 && c < 0x7f && c != '\\') {
      r += static_cast<char>(c);
    } else {
      static const char hex[] = "0123456789abcdef";
      r += "\\x";
      r += hex[c >> 4];
      r += hex[c & 15];
    }
  }
  if (s.size() > kMax) r += "...";
  r += "'";
  return r;
}

bool parse_double(std::string_view s, double& out) noexcept {
  if (!strip_plus(s)) return false;
  double v = 0;
  const auto r = std::from_chars(s.data(), s.data() + s.size(), v, std::chars_format::general);
  if (r.ptr != s.data() + s.size()) return false;
  if (r.ec == std::errc::result_out_of_range) {
    out = out_of_range_value(s);
    return true;
  }
  if (r.ec != std::errc()) return false;
  out = v;
  return true;
}

bool parse_int(std::string_view s, std::int64_t& out) noexcept {
  if (!strip_plus(s)) return false;
  std::int64_t v = 0;
  const auto r = std::from_chars(s.data(), s.data() + s.size(), v, 10);
  if (r.ec != std::errc() || r.ptr != s.data() + s.size()) return false;
  out = v;
  return true;
}

std::size_t scalar_size(Scalar t) noexcept {
  switch (t) {
    case Scalar::i8:
    case Scalar::u8: return 1;
    case Scalar::i16:
    case Scalar::u16: return 2;
    case Scalar::i32:
    case Scalar::u32:
    case Scalar::f32: return 4;
    case Scalar::i64:
    case Scalar::u64:
    case Scalar::f64: return 8;
  }
  return 1;
}

bool scalar_is_integer(Scalar t) noexcept { return t != Scalar::f32 && t != Scalar::f64; }

void append_uint(std::string& out, std::uint64_t v) {
  char buf[24];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  out.append(buf, static_cast<std::size_t>(r.ptr - buf));
}

void append_real(std::string& out, double v, int precision) {
  char buf[64];
  const auto r = precision >= 17 ? std::to_chars(buf, buf + sizeof buf, v)
                                 : std::to_chars(buf, buf + sizeof buf, v, std::chars_format::general, precision);
  out.append(buf, static_cast<std::size_t>(r.ptr - buf));
}

void append_point_line(std::string& out, const char* prefix, const Vec3& p, int precision) {
  out += prefix;
  append_real(out, p[0], precision);
  out += ' ';
  append_real(out, p[1], precision);
  out += ' ';
  append_real(out, p[2], precision);
  out += '\n';
}

namespace {

template <class U>
char* put_bytes(char* dst, U v, bool big_endian) {
  for (std::size_t i = 0; i < sizeof(U); ++i)
    dst[big_endian ? sizeof(U) - 1 - i : i] = static_cast<char>(static_cast<unsigned char>(v >> (8 * i)));
  return dst + sizeof(U);
}

}  // namespace

void append_points(std::string& out, const std::vector<Vec3>& points, bool float32, bool big_endian) {
  const std::size_t start = out.size();
  out.resize(start + points.size() * 3 * (float32 ? 4 : 8));
  char* dst = out.data() + start;
  for (const Vec3& p : points)
    for (double c : p) {
      if (float32) {
        const auto f = static_cast<float>(c);
        std::uint32_t bits;
        std::memcpy(&bits, &f, sizeof bits);
        dst = put_bytes(dst, bits, big_endian);
      } else {
        std::uint64_t bits;
        std::memcpy(&bits, &c, sizeof bits);
        dst = put_bytes(dst, bits, big_endian);
      }
    }
}

void add_fan(Mesh& mesh, const std::uint32_t* corners, std::size_t n) {
  for (std::size_t i = 1; i + 1 < n; ++i) mesh.triangles.push_back({corners[0], corners[i], corners[i + 1]});
}

}  // namespace hmc::io::detail
