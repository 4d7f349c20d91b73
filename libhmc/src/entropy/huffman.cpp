// SPDX-License-Identifier: AGPL-3.0-or-later
#include "entropy/huffman.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace hmc::detail {

namespace {

int symbol_width(std::uint32_t alphabet) {
  int w = 1;
  while ((std::uint64_t{1} << w) < alphabet) ++w;
  return w;
}

}  // namespace

double entropy_bits(const std::uint64_t* freq, std::size_t n) {
  double total = 0, bits = 0;
  for (std::size_t i = 0; i < n; ++i) total += static_cast<double>(freq[i]);
  for (std::size_t i = 0; i < n; ++i)
    if (freq[i]) bits -= static_cast<double>(freq[i]) * std::log2(static_cast<double>(freq[i]) / total);
  return bits;
}

std::vector<std::uint8_t> huffman_lengths(const std::vector<std::uint64_t>& freq, int max_len) {
  std::vector<std::uint8_t> len(freq.size(), 0);
  std::vector<std::uint32_t> used;
  for (std::uint32_t s = 0; s < freq.size(); ++s)
    if (freq[s]) used.push_back(s);
  if (used.size() < 2) return len;
  if ((std::size_t{1} << max_len) < used.size()) fail(Status::internal_error, "alphabet too large for code length limit");

  // Package-merge (Larmore & Hirschberg). The list of level 1 is the
  // leaves by weight; the list of level l + 1 merges the leaves with the
  // packages of two consecutive items of level l's list. The 2n-2 lightest
  // items of the last list give each leaf's code length: the number of times
  // it occurs inside them. Packages enter a list in the order they were
  // made, so the first k packages of level l + 1's list hold exactly the
  // first 2k items of level l's: walking the levels back from the last, each
  // level's selected items are a prefix, whose leaves count once each and
  // whose packages set the next prefix.
  std::sort(used.begin(), used.end(), [&](std::uint32_t a, std::uint32_t b) {
    return freq[a] != freq[b] ? freq[a] < freq[b] : a < b;
  });
  const std::size_t n = used.size();
  const auto levels = static_cast<std::size_t>(max_len);
  // Level l's list (l = 0 ... levels - 1) is items[l * 2n, l * 2n + size[l]):
  // a leaf's position in `used`, or kPackage. weight, next: the weights of
  // the list before and of the one being built.
  constexpr std::uint32_t kPackage = ~std::uint32_t{0};
  std::vector<std::uint32_t> items(levels * 2 * n);
  std::vector<std::size_t> size(levels);
  std::vector<std::uint64_t> weight(2 * n), next(2 * n);
  for (std::uint32_t i = 0; i < n; ++i) items[i] = i, weight[i] = freq[used[i]];
  size[0] = n;
  for (std::size_t level = 1; level < levels; ++level) {
    std::uint32_t* out = items.data() + level * 2 * n;
    std::size_t m = 0, a = 0, b = 0;  // the next leaf; the next package, weight[2b] + weight[2b + 1]
    const std::size_t packages = size[level - 1] / 2;
    while (a < n || b < packages) {
      // Leaves go first on equal weight: deterministic and keeps codes short.
      const std::uint64_t leaf = a < n ? freq[used[a]] : 0;
      const std::uint64_t package = b < packages ? weight[2 * b] + weight[2 * b + 1] : 0;
      if (b >= packages || (a < n && leaf <= package)) {
        out[m] = static_cast<std::uint32_t>(a++);
        next[m++] = leaf;
      } else {
        out[m] = kPackage;
        next[m++] = package;
        ++b;
      }
    }
    size[level] = m;
    weight.swap(next);
  }
  std::size_t take = 2 * n - 2;
  for (std::size_t level = levels; level-- > 0;) {
    const std::uint32_t* in = items.data() + level * 2 * n;
    std::size_t packages = 0;
    for (std::size_t i = 0; i < take; ++i) {
      if (in[i] == kPackage) ++packages;
      else ++len[used[in[i]]];
    }
    take = 2 * packages;
  }
  return len;
}

HuffmanCode HuffmanCode::from_lengths(const std::vector<std::uint8_t>& lengths, const std::string& what) {
  HuffmanCode c;
  c.what_ = what;
  c.lengths_ = lengths;
  std::uint32_t used = 0;
  std::uint64_t kraft = 0;
  for (std::uint32_t s = 0; s < lengths.size(); ++s) {
    if (lengths[s] > kHuffmanMaxLength)
      fail(Status::bad_huffman_table, what + ": code length " + std::to_string(lengths[s]) + " exceeds 15");
    if (lengths[s]) {
      ++used;
      kraft += std::uint64_t{1} << (kHuffmanMaxLength - lengths[s]);
    }
  }
  if (used < 2) fail(Status::bad_huffman_table, what + ": fewer than two symbols have a code length");
  if (kraft != (std::uint64_t{1} << kHuffmanMaxLength))
    fail(Status::bad_huffman_table,
         what + (kraft > (std::uint64_t{1} << kHuffmanMaxLength) ? ": code lengths are over-subscribed"
                                                                 : ": code lengths are incomplete"));
  c.assign_codes();
  return c;
}

HuffmanCode HuffmanCode::from_frequencies(const std::vector<std::uint64_t>& freq) {
  std::uint32_t used = 0, last = 0;
  for (std::uint32_t s = 0; s < freq.size(); ++s)
    if (freq[s]) ++used, last = s;
  if (used <= 1) {
    HuffmanCode c;
    c.single_ = true;
    c.single_symbol_ = last;
    c.lengths_.assign(freq.size(), 0);
    c.codes_.assign(freq.size(), 0);
    return c;
  }
  return from_lengths(huffman_lengths(freq), "encoder");
}

void HuffmanCode::assign_codes() {
  const auto a = static_cast<std::uint32_t>(lengths_.size());
  codes_.assign(a, 0);
  sorted_.resize(a);
  std::iota(sorted_.begin(), sorted_.end(), 0u);
  std::stable_sort(sorted_.begin(), sorted_.end(),
                   [&](std::uint32_t x, std::uint32_t y) { return lengths_[x] < lengths_[y]; });
  std::uint32_t code = 0;
  std::uint32_t index = 0;
  while (index < a && lengths_[sorted_[index]] == 0) ++index;
  int prev = 0;
  for (int len = 1; len <= kHuffmanMaxLength; ++len) {
    code <<= (len - prev);
    prev = len;
    first_code_[len] = code;
    first_index_[len] = index;
    while (index < a && lengths_[sorted_[index]] == len) codes_[sorted_[index++]] = code++;
    // Left-justified end of this length's codes: a 15-bit peek below it
    // decodes with a length <= len.
    limit_[len] = code << (kHuffmanMaxLength - len);
  }
  fast_.assign(std::size_t{1} << kFastBits, 0);
  for (std::uint32_t s = 0; s < a; ++s) {
    const int len = lengths_[s];
    if (len == 0 || len > kFastBits) continue;
    const std::uint32_t first = codes_[s] << (kFastBits - len);
    for (std::uint32_t i = 0; i < (1u << (kFastBits - len)); ++i)
      fast_[first + i] = (static_cast<std::uint32_t>(len) << 24) | s;
  }
}

namespace {

// The delta form (spec 7.1): the length before the first non-zero one, and
// the tokens, read most significant bit first:
//   00 same length    100 +1    1100 +2    1110 end (the rest are zero)
//   01 zero run       101 -1    1101 -2    1111 s ue: -(ue + 3) if s, else +(ue + 3)
constexpr int kDeltaStart = 3;
enum class Token { same, zero, up1, down1, up2, down2, end, far };

Token read_token(BitReader& in) {
  if (!in.get(1)) return in.get(1) ? Token::zero : Token::same;
  if (!in.get(1)) return in.get(1) ? Token::down1 : Token::up1;
  if (!in.get(1)) return in.get(1) ? Token::down2 : Token::up2;
  return in.get(1) ? Token::far : Token::end;
}

}  // namespace

HuffmanCode HuffmanCode::read(BitReader& in, std::uint32_t alphabet, const std::string& what, TableForm form) {
  if (in.get(1)) {
    HuffmanCode c;
    c.what_ = what;
    c.single_ = true;
    c.single_symbol_ = in.get(symbol_width(alphabet));
    if (c.single_symbol_ >= alphabet)
      fail(Status::bad_huffman_table, what + ": single symbol " + std::to_string(c.single_symbol_) +
                                          " outside the alphabet of " + std::to_string(alphabet));
    c.lengths_.assign(alphabet, 0);
    return c;
  }
  std::vector<std::uint8_t> lengths(alphabet, 0);
  std::uint32_t s = 0;
  auto zero_run = [&] {
    const std::uint64_t run = std::uint64_t{in.exp_golomb()} + 1;
    if (run > alphabet - s)
      fail(Status::bad_huffman_table, what + ": zero run of " + std::to_string(run) + " passes the end of the alphabet");
    s += static_cast<std::uint32_t>(run);
  };
  if (form == TableForm::nibbles) {
    while (s < alphabet) {
      if (const std::uint32_t v = in.get(4)) lengths[s++] = static_cast<std::uint8_t>(v);
      else zero_run();
    }
    return from_lengths(lengths, what);
  }
  std::int64_t previous = kDeltaStart;
  while (s < alphabet) {
    std::int64_t delta = 0;
    switch (read_token(in)) {
      case Token::zero: zero_run(); continue;
      case Token::end: s = alphabet; continue;
      case Token::same: break;
      case Token::up1: delta = 1; break;
      case Token::down1: delta = -1; break;
      case Token::up2: delta = 2; break;
      case Token::down2: delta = -2; break;
      case Token::far: {
        const bool down = in.get(1) != 0;
        const std::int64_t m = std::int64_t{in.exp_golomb()} + 3;
        delta = down ? -m : m;
        break;
      }
    }
    const std::int64_t len = previous + delta;
    if (len < 1 || len > kHuffmanMaxLength)
      fail(Status::bad_huffman_table, what + ": length " + std::to_string(len) + " of symbol " + std::to_string(s) +
                                          " is outside 1.." + std::to_string(kHuffmanMaxLength));
    lengths[s++] = static_cast<std::uint8_t>(len);
    previous = len;
  }
  return from_lengths(lengths, what);
}

namespace {

// Counts the bits a BitWriter would be given (coded_bits).
struct BitCounter {
  std::uint64_t bits = 0;
  void put(std::uint32_t, int n) { bits += static_cast<std::uint64_t>(n); }
  void exp_golomb(std::uint32_t v) {
    std::uint32_t x = v + 1;
    int b = 0;
    while ((x >> b) > 1) ++b;
    bits += static_cast<std::uint64_t>(2 * b + 1);
  }
};

// The table syntax (spec 7.1) of a code with these lengths (or the
// one-symbol form), written to a BitWriter or counted by a BitCounter.
template <class Out>
void write_table(Out& out, const std::vector<std::uint8_t>& lengths, bool single, std::uint32_t single_symbol,
                 TableForm form) {
  const auto a = static_cast<std::uint32_t>(lengths.size());
  if (single) {
    out.put(1, 1);
    out.put(single_symbol, symbol_width(a));
    return;
  }
  out.put(0, 1);
  std::uint32_t s = 0;
  int previous = kDeltaStart;
  while (s < a) {
    if (lengths[s]) {
      if (form == TableForm::nibbles) {
        out.put(lengths[s++], 4);
        continue;
      }
      const int delta = lengths[s] - previous;
      previous = lengths[s++];
      switch (delta) {
        case 0: out.put(0b00, 2); break;
        case 1: out.put(0b100, 3); break;
        case -1: out.put(0b101, 3); break;
        case 2: out.put(0b1100, 4); break;
        case -2: out.put(0b1101, 4); break;
        default:
          out.put(0b1111, 4);
          out.put(delta < 0 ? 1u : 0u, 1);
          out.exp_golomb(static_cast<std::uint32_t>((delta < 0 ? -delta : delta) - 3));
      }
      continue;
    }
    std::uint32_t run = 0;
    while (s + run < a && lengths[s + run] == 0) ++run;
    if (form == TableForm::nibbles) {
      out.put(0, 4);
    } else {
      // Trailing zeros: the end token (4 bits), unless a run of one (01 1) is shorter.
      if (s + run == a && run > 1) {
        out.put(0b1110, 4);
        return;
      }
      out.put(0b01, 2);
    }
    out.exp_golomb(run - 1);
    s += run;
  }
}

}  // namespace

void HuffmanCode::write(BitWriter& out, TableForm form) const {
  write_table(out, lengths_, single_, single_symbol_, form);
}

std::vector<std::uint64_t> two_symbols_at_least(std::vector<std::uint64_t> freq) {
  auto used = std::count_if(freq.begin(), freq.end(), [](std::uint64_t v) { return v != 0; });
  for (std::size_t x = 0; x < freq.size() && used < 2; ++x)
    if (freq[x] == 0) freq[x] = 1, ++used;
  return freq;
}

std::uint64_t table_and_symbols(const std::vector<std::uint64_t>& freq, const HuffmanCode& code, TableForm form) {
  BitWriter w;
  code.write(w, form);
  return w.bit_count() + code.cost(freq);
}

std::uint64_t coded_bits(const std::vector<std::uint64_t>& freq, TableForm form) {
  std::uint32_t used = 0, last = 0;
  for (std::uint32_t s = 0; s < freq.size(); ++s)
    if (freq[s]) ++used, last = s;
  BitCounter counter;
  if (used <= 1) {
    write_table(counter, std::vector<std::uint8_t>(freq.size(), 0), true, last, form);
    return counter.bits;
  }
  const std::vector<std::uint8_t> lengths = huffman_lengths(freq);
  write_table(counter, lengths, false, 0, form);
  std::uint64_t bits = counter.bits;
  for (std::size_t s = 0; s < freq.size(); ++s) bits += freq[s] * lengths[s];
  return bits;
}

std::uint32_t HuffmanCode::decode(BitReader& in) const {
  if (single_) return single_symbol_;
  const std::uint32_t peek = in.peek(kHuffmanMaxLength);
  if (const std::uint32_t e = fast_[peek >> (kHuffmanMaxLength - kFastBits)]) {
    in.consume(static_cast<int>(e >> 24));
    return e & 0xffffffu;
  }
  int len = kFastBits + 1;
  while (peek >= limit_[len]) ++len;  // terminates: the code is complete, limit_[15] == 2^15
  in.consume(len);
  const std::uint32_t code = peek >> (kHuffmanMaxLength - len);
  return sorted_[first_index_[len] + (code - first_code_[len])];
}

std::uint64_t HuffmanCode::cost(const std::vector<std::uint64_t>& freq) const {
  std::uint64_t bits = 0;
  for (std::size_t s = 0; s < freq.size() && s < lengths_.size(); ++s) bits += freq[s] * lengths_[s];
  return bits;
}

}  // namespace hmc::detail
