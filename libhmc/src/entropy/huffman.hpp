// SPDX-License-Identifier: AGPL-3.0-or-later
// Canonical Huffman codes (spec "Canonical Huffman codes"): length-limited
// code construction, the code-length table syntax, encoding and decoding.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "entropy/bitio.hpp"

namespace hmc::detail {

constexpr int kHuffmanMaxLength = 15;

/// Optimal code lengths (<= max_len) for the given symbol frequencies, by
/// package-merge; ties broken by symbol value so the result is deterministic.
/// Symbols with zero frequency get length 0. A single used symbol gets length
/// 0 as well (it is sent with the single-symbol form and costs no bits).
std::vector<std::uint8_t> huffman_lengths(const std::vector<std::uint64_t>& freq, int max_len = kHuffmanMaxLength);

/// The empirical entropy, in bits, of the n symbol counts freq[0, n): what
/// an ideal code of them would cost, tables aside (encoders' estimates).
double entropy_bits(const std::uint64_t* freq, std::size_t n);

/// The two syntaxes of a code-length table (spec 7.1): each length in 4 bits
/// (streams whose HEAD flag bit 0 is clear), or each length as a token that
/// gives its difference from the previous length (the bit set; what the
/// encoder writes since spec 0.10).
enum class TableForm : std::uint8_t { nibbles, deltas };

/// The bits of the code-length table of the code from_frequencies(freq)
/// builds, in `form`, plus those of the symbols counted in freq: what writing
/// both would take, computed without building the code (encoders' plans).
std::uint64_t coded_bits(const std::vector<std::uint64_t>& freq, TableForm form = TableForm::deltas);

/// The counts with unused symbols given a phantom count, the first ones
/// first, until two symbols are used: for a code that gives codes to two
/// symbols at least, so that each of its symbols costs a bit (spec 8.2).
std::vector<std::uint64_t> two_symbols_at_least(std::vector<std::uint64_t> freq);

class HuffmanCode;
/// The bits of `code`'s table in `form` plus those of the symbols counted
/// in freq coded with it (encoders' plans, for codes built from other counts).
std::uint64_t table_and_symbols(const std::vector<std::uint64_t>& freq, const HuffmanCode& code,
                                TableForm form = TableForm::deltas);

/// A canonical code over an alphabet of `size` symbols.
class HuffmanCode {
 public:
  /// Build from code lengths; validates them (bad_huffman_table on failure).
  static HuffmanCode from_lengths(const std::vector<std::uint8_t>& lengths, const std::string& what);
  /// Build from frequencies (encoder side).
  static HuffmanCode from_frequencies(const std::vector<std::uint64_t>& freq);
  /// Read the table syntax for an alphabet of `alphabet` symbols.
  static HuffmanCode read(BitReader& in, std::uint32_t alphabet, const std::string& what,
                          TableForm form = TableForm::deltas);
  /// Write the table syntax.
  void write(BitWriter& out, TableForm form = TableForm::deltas) const;
  void encode(BitWriter& out, std::uint32_t symbol) const {
    if (single_) return;
    out.put(codes_[symbol], lengths_[symbol]);
  }
  std::uint32_t decode(BitReader& in) const;

  std::uint32_t alphabet() const { return static_cast<std::uint32_t>(lengths_.size()); }
  /// True for the one-symbol form, whose symbols cost no bits.
  bool single() const { return single_; }
  /// Whether `symbol` can occur: it has a code, or is the one symbol.
  bool has(std::uint32_t symbol) const {
    return single_ ? symbol == single_symbol_ : symbol < lengths_.size() && lengths_[symbol] != 0;
  }
  int length(std::uint32_t symbol) const { return lengths_[symbol]; }
  /// Total bits to code `freq` with this code.
  std::uint64_t cost(const std::vector<std::uint64_t>& freq) const;

 private:
  void assign_codes();
  bool single_ = false;
  std::uint32_t single_symbol_ = 0;
  std::vector<std::uint8_t> lengths_;
  std::vector<std::uint32_t> codes_;
  // Decoding: symbols sorted by (length, value) and, per length, the first
  // code left-justified to 15 bits and the index of its first symbol.
  std::vector<std::uint32_t> sorted_;
  std::uint32_t limit_[kHuffmanMaxLength + 2] = {};
  std::uint32_t first_code_[kHuffmanMaxLength + 1] = {};
  std::uint32_t first_index_[kHuffmanMaxLength + 1] = {};
  // Codes of up to kFastBits bits decode with one lookup: entry =
  // (length << 24) | symbol, 0 where the code is longer.
  static constexpr int kFastBits = 10;
  std::vector<std::uint32_t> fast_;
  std::string what_;
};

}  // namespace hmc::detail
