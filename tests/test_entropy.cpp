// SPDX-License-Identifier: AGPL-3.0-or-later
// Bit I/O and canonical Huffman codes.
#include <doctest/doctest.h>

#include <algorithm>
#include <functional>
#include <random>

#include "entropy/huffman.hpp"
#include "entropy/paired.hpp"
#include "entropy/rice.hpp"

using namespace hmc;
using namespace hmc::detail;

namespace {

Status status_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const StreamError& e) {
    return e.error().status;
  }
  return Status::ok;
}

std::uint64_t kraft_sum(const std::vector<std::uint8_t>& len) {
  std::uint64_t k = 0;
  for (auto l : len)
    if (l) k += std::uint64_t{1} << (15 - l);
  return k;
}

}  // namespace

TEST_CASE("bits are packed most significant first and padded with zeros") {
  BitWriter w;
  w.put(1, 1);
  w.put(0, 1);
  w.put(0x5, 3);  // 101
  auto bytes = w.finish();
  REQUIRE(bytes.size() == 1);
  CHECK(bytes[0] == 0xA8);  // 1 0 101 000
  BitReader r(bytes.data(), bytes.size(), "t");
  CHECK(r.get(2) == 2);
  CHECK(r.get(3) == 5);
  r.expect_end();
}

TEST_CASE("reading past the end of a bit stream is bad_layer") {
  std::uint8_t b = 0xff;
  BitReader r(&b, 1, "t");
  CHECK(r.get(8) == 0xff);
  CHECK(status_of([&] { r.get(1); }) == Status::bad_layer);
}

TEST_CASE("non-zero padding and trailing bytes are rejected") {
  std::uint8_t b[2] = {0x81, 0x00};
  BitReader r(b, 1, "t");
  r.get(1);
  CHECK(status_of([&] { r.expect_end(); }) == Status::bad_layer);
  BitReader r2(b, 2, "t");
  r2.get(8);
  CHECK(status_of([&] { r2.expect_end(); }) == Status::bad_layer);
}

TEST_CASE("exp-Golomb codes round trip") {
  BitWriter w;
  const std::vector<std::uint32_t> vals{0, 1, 2, 3, 7, 8, 255, 256, 65535, 1u << 20, 0x7ffffffe};
  for (auto v : vals) w.exp_golomb(v);
  auto bytes = w.finish();
  BitReader r(bytes.data(), bytes.size(), "t");
  for (auto v : vals) CHECK(r.exp_golomb() == v);
}

TEST_CASE("Huffman lengths are optimal on a textbook example") {
  // Frequencies 45 13 12 16 9 5: optimal lengths 1 3 3 3 4 4 (cost 224).
  auto len = huffman_lengths({45, 13, 12, 16, 9, 5});
  CHECK(len == std::vector<std::uint8_t>{1, 3, 3, 3, 4, 4});
  CHECK(kraft_sum(len) == (1u << 15));
}

TEST_CASE("Huffman lengths cost what a Huffman tree costs when it is no deeper than 15") {
  std::mt19937_64 rng(11);
  for (int trial = 0; trial < 200; ++trial) {
    const std::size_t n = 2 + rng() % 255;
    std::vector<std::uint64_t> f(n);
    for (auto& x : f) x = trial % 3 == 0 ? rng() % 4 : 1 + rng() % (trial % 3 == 1 ? 100 : 100000);
    if (std::count_if(f.begin(), f.end(), [](std::uint64_t x) { return x != 0; }) < 2) f[0] = f[1] = 1;
    // A Huffman tree's cost (the sum of its merges) and depth, by a min-heap.
    std::vector<std::pair<std::uint64_t, int>> heap;  // (weight, depth)
    for (auto x : f)
      if (x) heap.push_back({x, 0});
    const auto greater = [](const auto& a, const auto& b) { return a > b; };
    std::make_heap(heap.begin(), heap.end(), greater);
    std::uint64_t tree_cost = 0;
    int depth = 0;
    while (heap.size() > 1) {
      std::pop_heap(heap.begin(), heap.end(), greater);
      const auto a = heap.back();
      heap.pop_back();
      std::pop_heap(heap.begin(), heap.end(), greater);
      const auto b = heap.back();
      heap.pop_back();
      tree_cost += a.first + b.first;
      depth = std::max(a.second, b.second) + 1;
      heap.push_back({a.first + b.first, depth});
      std::push_heap(heap.begin(), heap.end(), greater);
    }
    const auto len = huffman_lengths(f);
    std::uint64_t cost = 0;
    for (std::size_t i = 0; i < n; ++i) cost += f[i] * len[i];
    CHECK(kraft_sum(len) == (1u << 15));
    if (depth <= 15) CHECK(cost == tree_cost);
    else CHECK(cost >= tree_cost);
  }
}

TEST_CASE("Huffman lengths respect the 15-bit limit and stay complete") {
  // Fibonacci frequencies force a depth of n-1 without a limit.
  std::vector<std::uint64_t> f{1, 1};
  while (f.size() < 30) f.push_back(f[f.size() - 1] + f[f.size() - 2]);
  auto len = huffman_lengths(f);
  for (auto l : len) {
    CHECK(l >= 1);
    CHECK(l <= 15);
  }
  CHECK(kraft_sum(len) == (1u << 15));
}

TEST_CASE("a single used symbol costs no bits") {
  std::vector<std::uint64_t> f(256, 0);
  f[77] = 1000;
  auto code = HuffmanCode::from_frequencies(f);
  BitWriter w;
  code.write(w);
  const auto table_bits = w.bit_count();
  for (int i = 0; i < 1000; ++i) code.encode(w, 77);
  CHECK(w.bit_count() == table_bits);
  CHECK(coded_bits(f) == table_bits);
  auto bytes = w.finish();
  BitReader r(bytes.data(), bytes.size(), "t");
  auto back = HuffmanCode::read(r, 256, "t");
  for (int i = 0; i < 1000; ++i) CHECK(back.decode(r) == 77);
}

TEST_CASE("Huffman tables and symbols round trip for many distributions") {
  std::mt19937_64 rng(7);
  for (int trial = 0; trial < 60; ++trial) {
    const std::uint32_t alphabet = 2 + static_cast<std::uint32_t>(rng() % 300);
    std::vector<std::uint64_t> freq(alphabet, 0);
    std::vector<std::uint32_t> msg;
    const int used = 2 + static_cast<int>(rng() % std::min<std::uint32_t>(alphabet - 1, 40));
    std::geometric_distribution<int> geo(0.2 + 0.7 * (trial % 5) / 5.0);
    for (int i = 0; i < 2000; ++i) {
      std::uint32_t s = static_cast<std::uint32_t>(geo(rng) % used) * (alphabet / used);
      msg.push_back(s);
      ++freq[s];
    }
    auto code = HuffmanCode::from_frequencies(freq);
    // Both table forms (spec 7.1), alternately.
    const TableForm form = trial % 2 ? TableForm::nibbles : TableForm::deltas;
    BitWriter w;
    code.write(w, form);
    for (auto s : msg) code.encode(w, s);
    CHECK(coded_bits(freq, form) == w.bit_count());  // what the encoders' plans count
    auto bytes = w.finish();
    BitReader r(bytes.data(), bytes.size(), "t");
    auto back = HuffmanCode::read(r, alphabet, "t", form);
    for (std::uint32_t s = 0; s < alphabet; ++s) REQUIRE(back.length(s) == code.length(s));
    for (auto s : msg) REQUIRE(back.decode(r) == s);
    r.expect_end();
  }
}

TEST_CASE("invalid code-length tables are bad_huffman_table") {
  auto table = [](const std::function<void(BitWriter&)>& f, std::uint32_t alphabet,
                  TableForm form = TableForm::nibbles) {
    BitWriter w;
    f(w);
    auto bytes = w.finish();
    bytes.resize(bytes.size() + 8, 0);
    return status_of([&] {
      BitReader r(bytes.data(), bytes.size(), "t");
      HuffmanCode::read(r, alphabet, "t", form);
    });
  };
  // Over-subscribed: three symbols of length 1.
  CHECK(table([](BitWriter& w) { w.put(0, 1); for (int i = 0; i < 3; ++i) w.put(1, 4); }, 3) == Status::bad_huffman_table);
  // Incomplete: lengths 1, 2.
  CHECK(table([](BitWriter& w) { w.put(0, 1); w.put(1, 4); w.put(2, 4); }, 2) == Status::bad_huffman_table);
  // One symbol only in the explicit form.
  CHECK(table([](BitWriter& w) { w.put(0, 1); w.put(1, 4); w.put(0, 4); w.exp_golomb(0); }, 2) == Status::bad_huffman_table);
  // A zero run past the end of the alphabet.
  CHECK(table([](BitWriter& w) { w.put(0, 1); w.put(1, 4); w.put(1, 4); w.put(0, 4); w.exp_golomb(5); }, 4) == Status::bad_huffman_table);
  // Single-symbol form naming a symbol outside the alphabet (alphabet 5 -> 3 bits).
  CHECK(table([](BitWriter& w) { w.put(1, 1); w.put(6, 3); }, 5) == Status::bad_huffman_table);
  // A valid table for contrast: lengths 1, 2, 2.
  CHECK(table([](BitWriter& w) { w.put(0, 1); w.put(1, 4); w.put(2, 4); w.put(2, 4); }, 3) == Status::ok);

  // The delta form: tokens 00 same, 01 zero run, 100 +1, 101 -1, 1100 +2,
  // 1101 -2, 1110 end, 1111 s ue far; the first length is relative to 3.
  const auto d = TableForm::deltas;
  // Lengths 1, 2, 2 (3 -2 = 1, +1, same): valid.
  CHECK(table([](BitWriter& w) { w.put(0, 1); w.put(0b1101, 4); w.put(0b100, 3); w.put(0b00, 2); }, 3, d) == Status::ok);
  // The same with a zero run between and the end token after: valid.
  CHECK(table([](BitWriter& w) {
          w.put(0, 1); w.put(0b1101, 4); w.put(0b01, 2); w.exp_golomb(1); w.put(0b100, 3); w.put(0b00, 2); w.put(0b1110, 4);
        }, 9, d) == Status::ok);
  // Over-subscribed: three lengths 1.
  CHECK(table([](BitWriter& w) { w.put(0, 1); w.put(0b1101, 4); w.put(0b00, 2); w.put(0b00, 2); }, 3, d) == Status::bad_huffman_table);
  // Incomplete: lengths 1, 2, then the end token.
  CHECK(table([](BitWriter& w) { w.put(0, 1); w.put(0b1101, 4); w.put(0b100, 3); w.put(0b1110, 4); }, 5, d) == Status::bad_huffman_table);
  // A length below 1 (3 - 2 - 1 = 0) and above 15 (3 + 13 = 16, a far token).
  CHECK(table([](BitWriter& w) { w.put(0, 1); w.put(0b1101, 4); w.put(0b101, 3); }, 3, d) == Status::bad_huffman_table);
  CHECK(table([](BitWriter& w) { w.put(0, 1); w.put(0b1111, 4); w.put(0, 1); w.exp_golomb(10); }, 3, d) == Status::bad_huffman_table);
  // One symbol only, then the end token; a zero run past the alphabet.
  CHECK(table([](BitWriter& w) { w.put(0, 1); w.put(0b00, 2); w.put(0b1110, 4); }, 4, d) == Status::bad_huffman_table);
  CHECK(table([](BitWriter& w) { w.put(0, 1); w.put(0b1101, 4); w.put(0b01, 2); w.exp_golomb(5); }, 4, d) == Status::bad_huffman_table);
}

TEST_CASE("delta-form tables: every length and every token, and smaller than 4-bit lengths on skewed codes") {
  // Each length 1..15 after each length 1..15 (so every difference from
  // -14 to +14), on a code that stays complete: a chain of lengths
  // 1, 2, ..., 14, 15, 15 padded with pairs so that the deltas vary.
  for (int a = 1; a <= 15; ++a)
    for (int b = 1; b <= 15; ++b) {
      // Lengths: a, b somewhere in a complete code built around them.
      std::vector<std::uint8_t> lengths;
      std::uint64_t kraft = 0;  // in units of 2^-15
      auto add = [&](int len) {
        lengths.push_back(static_cast<std::uint8_t>(len));
        kraft += std::uint64_t{1} << (15 - len);
      };
      add(a);
      if (kraft + (std::uint64_t{1} << (15 - b)) > (1u << 15)) continue;
      add(b);
      lengths.push_back(0);  // a zero run between
      // Fill the rest with the longest lengths that fit, greedily.
      for (int len = 1; len <= 15 && kraft < (1u << 15); ++len)
        while (kraft + (std::uint64_t{1} << (15 - len)) <= (1u << 15)) add(len);
      if (lengths.size() < 3) continue;
      lengths.resize(lengths.size() + 5, 0);  // trailing zeros: the end token
      CAPTURE(a);
      CAPTURE(b);
      const auto code = HuffmanCode::from_lengths(lengths, "t");
      for (const TableForm form : {TableForm::deltas, TableForm::nibbles}) {
        BitWriter w;
        code.write(w, form);
        auto bytes = w.finish();
        BitReader r(bytes.data(), bytes.size(), "t");
        const auto back = HuffmanCode::read(r, static_cast<std::uint32_t>(lengths.size()), "t", form);
        for (std::uint32_t s = 0; s < lengths.size(); ++s) REQUIRE(back.length(s) == lengths[s]);
      }
    }
  // A geometric distribution over 255 symbols, as ranked occupancies are.
  std::vector<std::uint64_t> freq(255, 0);
  for (std::size_t s = 0; s < 40; ++s) freq[s] = 1 + (std::uint64_t{1} << 20 >> (s / 2));
  const auto code = HuffmanCode::from_frequencies(freq);
  BitWriter nib, del;
  code.write(nib, TableForm::nibbles);
  code.write(del, TableForm::deltas);
  CHECK(del.bit_count() < nib.bit_count() * 3 / 4);
}

TEST_CASE("canonical codes are assigned by (length, symbol)") {
  // Lengths 2 1 3 3 -> symbol 1: 0, symbol 0: 10, symbol 2: 110, symbol 3: 111.
  auto code = HuffmanCode::from_lengths({2, 1, 3, 3}, "t");
  BitWriter w;
  for (std::uint32_t s : {1u, 0u, 2u, 3u}) code.encode(w, s);
  auto bytes = w.finish();
  REQUIRE(bytes.size() == 2);
  CHECK(bytes[0] == 0x5B);  // 0 10 110 11|1
  CHECK(bytes[1] == 0x80);
}

namespace {

// Symbols 0 .. 7 with rank 0 of probability `p0` and the rest spread evenly,
// and now and then a symbol above 7 (a node with several children).
std::vector<std::uint32_t> skewed(std::size_t n, double p0, double escapes, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<std::uint32_t> out;
  for (std::size_t i = 0; i < n; ++i) {
    const double x = u(rng);
    out.push_back(x < escapes ? 8 + static_cast<std::uint32_t>(rng() % 247)
                  : x < escapes + p0 ? 0u
                                     : 1 + static_cast<std::uint32_t>(rng() % 7));
  }
  return out;
}

}  // namespace

TEST_CASE("paired tables (spec 7.4): tables and interleaved symbols round trip, and cost what paired_bits says") {
  const std::vector<std::vector<std::uint32_t>> sequences{
      skewed(1001, 0.9, 0.0, 1),  // odd: the last pair's second symbol is never used
      skewed(500, 0.6, 0.05, 2),  // escapes
      skewed(64, 0.3, 0.5, 3),    // mostly escapes
      {5},                        // one symbol: one pair (5, 0)
      std::vector<std::uint32_t>(40, 0),
      {254, 254, 254},            // only escapes: a one-symbol pair code of the escape
  };
  for (bool paired : {false, true})
    for (std::size_t first = 0; first < sequences.size(); ++first) {
      CAPTURE(paired);
      CAPTURE(first);
      // Two tables whose uses interleave: each keeps its own pending symbol.
      const auto& a = sequences[first];
      const auto& b = sequences[(first + 1) % sequences.size()];
      TableCode ta = TableCode::build(a, 255, paired), tb = TableCode::build(b, 255, paired);
      BitWriter w;
      ta.write(w, true, TableForm::deltas);
      const std::uint64_t table_a = w.bit_count();
      tb.write(w, true, TableForm::deltas);
      const std::uint64_t tables = w.bit_count();
      std::uint64_t bits_a = 0;
      for (std::size_t i = 0, j = 0; i < a.size() || j < b.size();) {
        if (i < a.size()) {
          const std::uint64_t before = w.bit_count();
          ta.encode(w, a[i++]);
          bits_a += w.bit_count() - before;
        }
        for (int k = 0; k < 3 && j < b.size(); ++k) tb.encode(w, b[j++]);
      }
      if (paired) CHECK(table_a - 1 + bits_a == paired_bits(a, 255, TableForm::deltas));
      const auto bytes = w.finish();
      BitReader r(bytes.data(), bytes.size(), "test");
      TableCode ra = TableCode::read(r, 255, true, "a", TableForm::deltas);
      TableCode rb = TableCode::read(r, 255, true, "b", TableForm::deltas);
      CHECK(ra.paired() == paired);
      CHECK(r.bits_left() == 8 * bytes.size() - tables);
      std::vector<std::uint32_t> da, db;
      for (std::size_t i = 0, j = 0; i < a.size() || j < b.size();) {
        if (i < a.size()) da.push_back(ra.decode(r)), ++i;
        for (int k = 0; k < 3 && j < b.size(); ++k) db.push_back(rb.decode(r)), ++j;
      }
      CHECK(da == a);
      CHECK(db == b);
      CHECK(r.bits_left() < 8);
    }
}

TEST_CASE("paired tables: cheaper than a plain code where one symbol dominates, free when every pair is the same") {
  std::vector<std::uint64_t> freq(255, 0);
  const auto seq = skewed(4000, 0.9, 0.0, 7);
  for (std::uint32_t s : seq) ++freq[s];
  const double entropy = entropy_bits(freq.data(), freq.size());
  const std::uint64_t plain = coded_bits(freq), pairs = paired_bits(seq, 255, TableForm::deltas);
  MESSAGE("p(0) = 0.9: entropy ", entropy, " bits, plain code ", plain, ", paired ", pairs);
  CHECK(plain >= seq.size());  // a Huffman code spends a bit per symbol at least
  CHECK(pairs < plain);
  CHECK(pairs > entropy);
  // Every pair (0, 0): the pair code's one-symbol form, 1 + 7 bits in all.
  CHECK(paired_bits(std::vector<std::uint32_t>(1000, 0), 255, TableForm::deltas) == 8);
  // Evenly spread ranks gain nothing from pairs (the code and its escape
  // cost more than the plain code).
  const auto flat = skewed(4000, 0.125, 0.0, 8);
  std::fill(freq.begin(), freq.end(), 0);
  for (std::uint32_t s : flat) ++freq[s];
  CHECK(paired_bits(flat, 255, TableForm::deltas) >= coded_bits(freq));
}

TEST_CASE("paired tables: a pair code that gives the escape is followed by the escape code; damaged tables fail") {
  // Hand-made: the paired flag, a pair code of one symbol (1, then 64, the
  // escape, in 7 bits), then the escape code: lengths 1 for symbols 3 and 9
  // in the delta form (a zero run of 3, -2 from the start length 3, a zero
  // run of 5, the same length, end).
  BitWriter w;
  w.put(1, 1);   // paired
  w.put(1, 1);   // pair code: one symbol
  w.put(64, 7);  // the escape
  w.put(0, 1);   // escape code: lengths
  w.put(1, 2);   // 01 zero run
  w.exp_golomb(2);  // of 3
  w.put(0b1101, 4);  // -2: length 1 for symbol 3
  w.put(1, 2);       // zero run
  w.exp_golomb(4);   // of 5
  w.put(0, 2);       // same: length 1 for symbol 9
  w.put(0b1110, 4);  // end
  // Symbols: escape (no bits), then 9 (code 1) and 3 (code 0); then the
  // pending 3 with no bits; then another pair: 3, 3.
  w.put(1, 1);
  w.put(0, 1);
  w.put(0, 1);
  w.put(0, 1);
  const auto bytes = w.finish();
  BitReader r(bytes.data(), bytes.size(), "test");
  TableCode t = TableCode::read(r, 255, true, "t", TableForm::deltas);
  CHECK(t.paired());
  std::vector<std::uint32_t> got;
  for (int i = 0; i < 4; ++i) got.push_back(t.decode(r));
  CHECK(got == std::vector<std::uint32_t>{9, 3, 3, 3});
  // Cut inside the escape code: a bit-stream error, not a table error.
  BitReader cut(bytes.data(), 2, "test");  // 16 of the table's 25 bits
  CHECK(status_of([&] { TableCode::read(cut, 255, true, "t", TableForm::deltas); }) == Status::bad_layer);
  // Not flagged: the first bit is the table's own (here: a one-symbol code).
  BitReader plain(bytes.data(), bytes.size(), "test");
  CHECK_FALSE(TableCode::read(plain, 255, false, "t", TableForm::deltas).paired());
}

TEST_CASE("the Rice parameter chosen is the first of the fewest bits, as trying all 32 finds") {
  std::mt19937_64 rng(31);
  int lists = 0, nonzero_k = 0, high_k = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    // Gaps of one scale (a list over a large range), mixed scales, runs of
    // zeros, and lists short and long.
    const std::size_t n = trial % 7 == 0 ? 0 : 1 + rng() % (trial % 3 == 0 ? 4 : 300);
    const int scale = static_cast<int>(rng() % 40);
    std::vector<std::uint64_t> gaps(n);
    for (auto& g : gaps) {
      const int s = trial % 5 == 0 ? static_cast<int>(rng() % 40) : scale;
      g = (rng() % 4 == 0 && trial % 2) || s == 0 ? 0 : rng() >> (64 - s);
    }
    RiceChoice want{0, ~std::uint64_t{0}};
    for (int k = 0; k < 32; ++k) {
      std::uint64_t bits = 0;
      for (auto g : gaps) bits += (g >> k) + 1 + static_cast<std::uint64_t>(k);
      if (bits < want.bits) want = {k, bits};
    }
    const RiceChoice got = best_rice(gaps);
    CHECK(got.k == want.k);
    CHECK(got.bits == want.bits);
    ++lists;
    nonzero_k += want.k > 0;
    high_k += want.k >= 20;
  }
  CHECK(lists == 3000);
  CHECK(nonzero_k > 1000);
  CHECK(high_k > 100);
}
