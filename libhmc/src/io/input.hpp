// SPDX-License-Identifier: AGPL-3.0-or-later
// A read cursor over a whole file held in memory, for text (by line or by
// token, counting lines), binary data (by byte, counting the offset) and
// files that mix both (binary PLY, VTK and Gmsh). Every read is bounds
// checked, and every failure names the file and the line or byte offset of
// the item last read.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>

#include "io/common.hpp"

namespace hmc::io::detail {

class Input {
 public:
  /// `comment` (if not '\0') starts a comment that runs to the end of the
  /// line; it applies to next_token and next_data_line.
  Input(std::string name, std::string_view data, char comment = '\0')
      : name_(std::move(name)), data_(data), comment_(comment) {}

  const std::string& name() const noexcept { return name_; }
  std::string_view data() const noexcept { return data_; }
  std::size_t pos() const noexcept { return pos_; }
  std::size_t size() const noexcept { return data_.size(); }
  std::size_t remaining() const noexcept { return data_.size() - pos_; }
  bool at_end() const noexcept { return pos_ >= data_.size(); }
  std::string_view rest() const noexcept { return data_.substr(pos_); }

  /// Once set, failures report the byte offset instead of the line number.
  void set_binary(bool b) noexcept { binary_ = b; }
  bool binary() const noexcept { return binary_; }

  /// Saved position, to look ahead and come back.
  struct State {
    std::size_t pos, cur_line, line, mark;
  };
  State save() const noexcept { return {pos_, cur_line_, line_, mark_}; }
  void restore(const State& s) noexcept {
    pos_ = s.pos;
    cur_line_ = s.cur_line;
    line_ = s.line;
    mark_ = s.mark;
  }

  // ---- text -------------------------------------------------------------

  /// Number of the line last returned, or of the line of the last token.
  std::size_t line() const noexcept { return line_; }

  /// The next raw line, without its '\n' and a trailing '\r'.
  bool next_line(std::string_view& out) noexcept {
    if (pos_ >= data_.size()) return false;
    line_ = cur_line_;
    mark_ = pos_;
    const char* b = data_.data() + pos_;
    const auto* nl = static_cast<const char*>(std::memchr(b, '\n', data_.size() - pos_));
    std::size_t len = nl ? static_cast<std::size_t>(nl - b) : data_.size() - pos_;
    pos_ += nl ? len + 1 : len;
    if (nl) ++cur_line_;
    if (len > 0 && b[len - 1] == '\r') --len;
    out = std::string_view(b, len);
    return true;
  }

  /// The next line that has a field (skipping blank and comment-only lines),
  /// split into fields.
  bool next_data_line(Fields& fields, bool commas = false) noexcept {
    std::string_view l;
    while (next_line(l)) {
      fields = Fields(l, comment_, commas);
      if (!fields.done()) return true;
    }
    return false;
  }

  /// The next whitespace-separated token, across lines, skipping comments.
  bool next_token(std::string_view& out) noexcept {
    const std::size_t n = data_.size();
    while (pos_ < n) {
      const char c = data_[pos_];
      if (c == '\n') {
        ++cur_line_;
        ++pos_;
      } else if (is_space(c)) {
        ++pos_;
      } else if (comment_ != '\0' && c == comment_) {
        while (pos_ < n && data_[pos_] != '\n') ++pos_;
      } else {
        break;
      }
    }
    if (pos_ >= n) return false;
    const std::size_t begin = pos_;
    while (pos_ < n && !is_space(data_[pos_]) && !(comment_ != '\0' && data_[pos_] == comment_)) ++pos_;
    line_ = cur_line_;
    mark_ = begin;
    out = data_.substr(begin, pos_ - begin);
    return true;
  }

  /// The next token; fails at the end of the file naming what was expected.
  std::string_view token(std::string_view what);
  /// Fails unless the next token equals `keyword` (case-insensitively).
  void expect_keyword(std::string_view keyword);
  /// Skips the rest of the current line, including its '\n'.
  void skip_line() noexcept;
  /// After a header line that binary data follows: allows only blanks up to
  /// the '\n', then steps over it.
  void end_header_line(std::string_view what);
  /// Moves to `new_pos` (>= pos), counting the lines passed.
  void skip_to(std::size_t new_pos) noexcept;

  /// A finite coordinate or other real value; `what` names it.
  double real(std::string_view tok, std::string_view what) const;
  std::int64_t integer(std::string_view tok, std::string_view what) const;
  /// A non-negative integer (a count, a tag, an index before rebasing).
  std::uint64_t count(std::string_view tok, std::string_view what) const;

  /// Fails unless `n` items of at least `fields` whitespace-separated fields
  /// each could fit in the rest of the file; call before reserving memory.
  void check_text_count(std::uint64_t n, std::uint64_t fields, std::string_view what) const;
  /// Same for binary items of `bytes` bytes each (reported at the current
  /// offset in binary mode).
  void check_binary_count(std::uint64_t n, std::uint64_t bytes, std::string_view what) const;

  // ---- binary -----------------------------------------------------------

  /// Pointer to the next `n` bytes, which are consumed.
  const unsigned char* take(std::size_t n, std::string_view what) {
    mark_ = pos_;
    if (n > data_.size() - pos_) truncated(n, what);
    const auto* p = reinterpret_cast<const unsigned char*>(data_.data() + pos_);
    pos_ += n;
    return p;
  }
  void skip(std::uint64_t n, std::string_view what) {
    mark_ = pos_;
    if (n > data_.size() - pos_) truncated(n, what);
    pos_ += static_cast<std::size_t>(n);
  }
  template <class U>
  U read_uint(bool big_endian, std::string_view what) {
    return load_uint<U>(take(sizeof(U), what), big_endian);
  }
  std::int32_t read_i32(bool big_endian, std::string_view what) {
    return static_cast<std::int32_t>(read_uint<std::uint32_t>(big_endian, what));
  }
  double read_f64(bool big_endian, std::string_view what);
  /// A value of type `t` converted to double (not checked for finiteness).
  double read_scalar(Scalar t, bool big_endian, std::string_view what);
  /// An integer value of integer type `t`; uint64 values above INT64_MAX
  /// saturate (they are out of range for every use anyway).
  std::int64_t read_integer(Scalar t, bool big_endian, std::string_view what);

  // ---- failures ---------------------------------------------------------

  /// At the last line or token (text), or at the last item's byte offset
  /// once set_binary(true).
  [[noreturn]] void fail(const std::string& message) const;
  [[noreturn]] void fail_at_line(std::size_t line, const std::string& message) const;
  [[noreturn]] void fail_at_offset(std::size_t offset, const std::string& message) const;
  /// Offset of the last item read (start of the last token, line or value).
  std::size_t mark() const noexcept { return mark_; }

 private:
  [[noreturn]] void truncated(std::uint64_t n, std::string_view what) const;

  std::string name_;
  std::string_view data_;
  std::size_t pos_ = 0;
  std::size_t cur_line_ = 1;  // line the cursor is on
  std::size_t line_ = 1;      // line of the last item returned
  std::size_t mark_ = 0;      // byte offset of the last item returned
  char comment_;
  bool binary_ = false;
};

}  // namespace hmc::io::detail
