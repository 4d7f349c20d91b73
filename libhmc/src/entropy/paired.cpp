// SPDX-License-Identifier: AGPL-3.0-or-later
#include "entropy/paired.hpp"

#include <utility>

#include "util/error.hpp"

namespace hmc::detail {

namespace {

// The pairs of a sequence (spec 7.4): (s0, s1), (s2, s3), …; an odd
// sequence's last pair takes 0 as its second symbol, which is never used.
template <class F>
void for_each_pair(const std::vector<std::uint32_t>& sequence, F&& f) {
  for (std::size_t i = 0; i < sequence.size(); i += 2) f(sequence[i], i + 1 < sequence.size() ? sequence[i + 1] : 0u);
}

bool pairs_up(std::uint32_t a, std::uint32_t b) { return a < kPairedSymbols && b < kPairedSymbols; }

// The frequencies of the pair code's symbols and of the escaped symbols.
void pair_frequencies(const std::vector<std::uint32_t>& sequence, std::uint32_t alphabet,
                      std::vector<std::uint64_t>& pairs, std::vector<std::uint64_t>& escaped) {
  pairs.assign(kPairAlphabet, 0);
  escaped.assign(alphabet, 0);
  for_each_pair(sequence, [&](std::uint32_t a, std::uint32_t b) {
    if (pairs_up(a, b)) {
      ++pairs[a * kPairedSymbols + b];
    } else {
      ++pairs[kPairEscape];
      ++escaped[a];
      ++escaped[b];
    }
  });
}

}  // namespace

std::uint64_t paired_bits(const std::vector<std::uint32_t>& sequence, std::uint32_t alphabet, TableForm form,
                          bool two_codes) {
  std::vector<std::uint64_t> pairs, escaped;
  pair_frequencies(sequence, alphabet, pairs, escaped);
  const bool escape_used = pairs[kPairEscape] != 0;
  if (!two_codes) return coded_bits(pairs, form) + (escape_used ? coded_bits(escaped, form) : 0);
  // The phantom symbols' codes are written but never used.
  const HuffmanCode code = HuffmanCode::from_frequencies(two_symbols_at_least(pairs));
  // An escape code follows when the pair code can give the escape, even a
  // phantom one (then a one-symbol code, of no escaped symbol).
  return table_and_symbols(pairs, code, form) + (code.has(kPairEscape) ? coded_bits(escaped, form) : 0);
}

TableCode TableCode::read(BitReader& in, std::uint32_t alphabet, bool flagged, const std::string& what,
                          TableForm form) {
  TableCode t;
  t.paired_ = flagged && in.get(1) != 0;
  if (!t.paired_) {
    t.code_ = HuffmanCode::read(in, alphabet, what, form);
    return t;
  }
  t.code_ = HuffmanCode::read(in, kPairAlphabet, what + " (pairs)", form);
  t.escape_used_ = t.code_.has(kPairEscape);
  if (t.escape_used_) t.escape_ = HuffmanCode::read(in, alphabet, what + " (escaped pairs)", form);
  return t;
}

TableCode TableCode::build(std::vector<std::uint32_t> sequence, std::uint32_t alphabet, bool paired,
                           bool two_codes) {
  TableCode t;
  t.paired_ = paired;
  t.sequence_ = std::move(sequence);
  if (!paired) {
    std::vector<std::uint64_t> freq(alphabet, 0);
    for (std::uint32_t s : t.sequence_) ++freq[s];
    t.code_ = HuffmanCode::from_frequencies(two_codes ? two_symbols_at_least(std::move(freq)) : freq);
    return t;
  }
  std::vector<std::uint64_t> pairs, escaped;
  pair_frequencies(t.sequence_, alphabet, pairs, escaped);
  t.code_ = HuffmanCode::from_frequencies(two_codes ? two_symbols_at_least(std::move(pairs)) : pairs);
  // The escape code follows whenever the pair code can give the escape (a
  // phantom escape included).
  t.escape_used_ = t.code_.has(kPairEscape);
  if (t.escape_used_) t.escape_ = HuffmanCode::from_frequencies(escaped);
  return t;
}

void TableCode::write(BitWriter& out, bool flagged, TableForm form) const {
  if (flagged) out.put(paired_ ? 1u : 0u, 1);
  code_.write(out, form);
  if (paired_ && escape_used_) escape_.write(out, form);
}

void TableCode::encode(BitWriter& out, std::uint32_t symbol) {
  if (next_ >= sequence_.size() || sequence_[next_] != symbol)
    fail(Status::internal_error, "paired table: symbols out of sequence");
  ++next_;
  if (!paired_) {
    code_.encode(out, symbol);
    return;
  }
  if (pending_ >= 0) {
    pending_ = -1;
    return;
  }
  const std::uint32_t second = next_ < sequence_.size() ? sequence_[next_] : 0u;
  if (pairs_up(symbol, second)) {
    code_.encode(out, symbol * kPairedSymbols + second);
  } else {
    code_.encode(out, kPairEscape);
    escape_.encode(out, symbol);
    escape_.encode(out, second);
  }
  pending_ = static_cast<std::int32_t>(second);
}

std::uint32_t TableCode::decode(BitReader& in) {
  if (!paired_) return code_.decode(in);
  if (pending_ >= 0) {
    const auto s = static_cast<std::uint32_t>(pending_);
    pending_ = -1;
    return s;
  }
  std::uint32_t first, second;
  const std::uint32_t v = code_.decode(in);
  if (v < kPairEscape) {
    first = v / kPairedSymbols;
    second = v % kPairedSymbols;
  } else {
    first = escape_.decode(in);
    second = escape_.decode(in);
  }
  pending_ = static_cast<std::int32_t>(second);
  return first;
}

}  // namespace hmc::detail
