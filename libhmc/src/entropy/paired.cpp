// SPDX-License-Identifier: AGPL-3.0-or-later
#include "entropy/paired.hpp"

#include <algorithm>

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

// Unused symbols given a phantom count, the first ones first, until two are
// used: a code of two symbols at least.
void two_at_least(std::vector<std::uint64_t>& freq) {
  auto used = std::count_if(freq.begin(), freq.end(), [](std::uint64_t v) { return v != 0; });
  for (std::size_t x = 0; x < freq.size() && used < 2; ++x)
    if (freq[x] == 0) freq[x] = 1, ++used;
}

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
  std::vector<std::uint64_t> padded = pairs;
  two_at_least(padded);
  const HuffmanCode code = HuffmanCode::from_frequencies(padded);
  BitWriter w;
  code.write(w, form);
  // An escape code follows when the pair code can give the escape, even a
  // phantom one (then a one-symbol code, of no escaped symbol).
  return w.bit_count() + code.cost(pairs) + (code.has(kPairEscape) ? coded_bits(escaped, form) : 0);
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

TableCode TableCode::build(const std::vector<std::uint32_t>& sequence, std::uint32_t alphabet, bool paired,
                           bool two_codes) {
  TableCode t;
  t.paired_ = paired;
  t.sequence_ = sequence;
  if (!paired) {
    std::vector<std::uint64_t> freq(alphabet, 0);
    for (std::uint32_t s : sequence) ++freq[s];
    if (two_codes) two_at_least(freq);
    t.code_ = HuffmanCode::from_frequencies(freq);
    return t;
  }
  std::vector<std::uint64_t> pairs, escaped;
  pair_frequencies(sequence, alphabet, pairs, escaped);
  if (two_codes) two_at_least(pairs);
  t.code_ = HuffmanCode::from_frequencies(pairs);
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
