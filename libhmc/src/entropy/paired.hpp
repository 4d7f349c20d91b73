// SPDX-License-Identifier: AGPL-3.0-or-later
// Paired tables (spec 7.4): a table that codes its symbols two at a time, so
// that a context whose most likely symbol is far above one half costs less
// than the one bit per symbol a Huffman code needs at least.
//
// A table of a layer is used by the nodes of its slots in the order the
// decoder visits them: its symbols form a sequence. A paired table codes
// that sequence in pairs; the pair is read when its first symbol is needed,
// and its second symbol waits in the table until the next node that uses the
// table. Pairs of the symbols 0 to 7 (the ranks of a single occupied child,
// where skewed contexts occur) have codes of their own; any other pair is an
// escape followed by its two symbols, in a code of the whole alphabet.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "entropy/bitio.hpp"
#include "entropy/huffman.hpp"

namespace hmc::detail {

/// Symbols below this pair up in the pair code (spec 7.4).
constexpr std::uint32_t kPairedSymbols = 8;
/// The pair code's alphabet: 8 · a + b for a pair (a, b) of symbols below 8,
/// and the escape.
constexpr std::uint32_t kPairEscape = kPairedSymbols * kPairedSymbols;
constexpr std::uint32_t kPairAlphabet = kPairEscape + 1;

/// The bits of the paired form of a table (the pair code, the escape code
/// when used, and every symbol of `sequence`), its flag excluded: what
/// writing it would take (encoders' plans). `sequence`: the table's symbols
/// in the order of use, each below `alphabet`. `two_codes`: the pair code
/// must have codes for two pairs at least (not the one-symbol form: where
/// every pair must cost a bit, spec 8.2).
std::uint64_t paired_bits(const std::vector<std::uint32_t>& sequence, std::uint32_t alphabet, TableForm form,
                          bool two_codes = false);

/// One table of a layer that may pair its symbols: either a plain code
/// (spec 7.1) or the paired form (spec 7.4). Decoders read it and decode;
/// encoders build it from the table's whole symbol sequence, which tells the
/// second symbol of a pair when the first is written.
class TableCode {
 public:
  /// Reads a table; with `flagged`, a flag first says whether it is paired
  /// (streams whose layer allows pairing), else it is plain.
  static TableCode read(BitReader& in, std::uint32_t alphabet, bool flagged, const std::string& what, TableForm form);
  /// The encoder's table for `sequence`, paired or not as asked; with
  /// `two_codes`, its code (the pair code when paired) gives codes to two
  /// symbols at least.
  static TableCode build(std::vector<std::uint32_t> sequence, std::uint32_t alphabet, bool paired,
                         bool two_codes = false);

  void write(BitWriter& out, bool flagged, TableForm form) const;
  /// Codes the next symbol of the sequence given to build(), which must be
  /// `symbol` (calls follow the sequence).
  void encode(BitWriter& out, std::uint32_t symbol);
  /// Decodes the next symbol of the table's sequence.
  std::uint32_t decode(BitReader& in);

  bool paired() const { return paired_; }
  /// Whether its code, or its pair code when paired, is the one-symbol
  /// form: then a symbol, or a pair, costs no bits.
  bool free() const { return code_.single(); }

 private:
  bool paired_ = false;
  bool escape_used_ = false;
  HuffmanCode code_;    // plain: the code; paired: the pair code
  HuffmanCode escape_;  // paired with escape_used_: the code of escaped symbols
  std::int32_t pending_ = -1;            // the second symbol of the last pair, not yet used
  std::vector<std::uint32_t> sequence_;  // encoder: the symbols in order
  std::size_t next_ = 0;                 // encoder: the next symbol of sequence_
};

}  // namespace hmc::detail
