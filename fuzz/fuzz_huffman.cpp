// SPDX-License-Identifier: AGPL-3.0-or-later
// Fuzz target: canonical Huffman code-length tables (HuffmanCode::read) on
// arbitrary bits, then symbol decoding until the bits run out.
//
// Input: u8 table form (bit 0: 1 the delta form, 0 the 4-bit form of spec
// 7.1), u16 alphabet size minus one (1 ... 65536), then the bit stream.
// Checks: only bad_huffman_table / bad_layer are raised; an accepted table
// writes back to a table that reads to the same lengths; every decoded
// symbol is in the alphabet; re-encoding the decoded symbols gives exactly
// the bits the decoder consumed.
#include <vector>

#include "entropy/huffman.hpp"
#include "fuzz_check.hpp"
#include "util/error.hpp"

namespace {

using hmc::Status;
using hmc::detail::BitReader;
using hmc::detail::BitWriter;
using hmc::detail::HuffmanCode;

int bit_at(const std::uint8_t* p, std::uint64_t i) { return (p[i >> 3] >> (7 - (i & 7))) & 1; }

bool expected_error(Status s) { return s == Status::bad_huffman_table || s == Status::bad_layer; }

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  hmc_fuzz::Params params(data, size);
  const auto form = params.u8() & 1 ? hmc::detail::TableForm::deltas : hmc::detail::TableForm::nibbles;
  const std::uint32_t alphabet = params.u16() + 1;
  const std::uint8_t* bits = params.rest();
  const std::size_t nbytes = params.rest_size();
  const std::uint64_t nbits = std::uint64_t{nbytes} * 8;

  BitReader in(bits, nbytes, "fuzz");
  HuffmanCode code;
  try {
    code = HuffmanCode::read(in, alphabet, "fuzz table", form);
  } catch (const hmc::detail::StreamError& e) {
    FUZZ_CHECK(expected_error(e.error().status), "table read raised %s: %s", hmc::status_name(e.error().status),
               e.what());
    return 0;
  }
  FUZZ_CHECK(code.alphabet() == alphabet, "alphabet %u, asked for %u", code.alphabet(), alphabet);
  const std::uint64_t table_end = nbits - in.bits_left();

  // Lengths: a single-symbol code has none; otherwise the code is complete.
  std::vector<std::uint8_t> lengths(alphabet);
  std::uint64_t kraft = 0;
  unsigned used = 0;
  for (std::uint32_t s = 0; s < alphabet; ++s) {
    lengths[s] = static_cast<std::uint8_t>(code.length(s));
    FUZZ_CHECK(lengths[s] <= hmc::detail::kHuffmanMaxLength, "length %u > 15", unsigned(lengths[s]));
    if (lengths[s]) {
      ++used;
      kraft += std::uint64_t{1} << (15 - lengths[s]);
    }
  }
  const bool single = used == 0;
  FUZZ_CHECK(single || (used >= 2 && kraft == (1u << 15)), "accepted an invalid code (%u used, Kraft %llu)", used,
             static_cast<unsigned long long>(kraft));

  // The table writes back to one that reads to the same code.
  {
    BitWriter w;
    code.write(w, form);
    const std::vector<std::uint8_t> table = w.finish();
    BitReader again(table.data(), table.size(), "fuzz rewrite");
    HuffmanCode back;
    try {
      back = HuffmanCode::read(again, alphabet, "fuzz rewritten table", form);
    } catch (const hmc::detail::StreamError& e) {
      FUZZ_CHECK(false, "a written table does not read back: %s", e.what());
    }
    FUZZ_CHECK(again.bits_left() < 8, "the rewritten table leaves %llu bits",
               static_cast<unsigned long long>(again.bits_left()));
    for (std::uint32_t s = 0; s < alphabet; ++s)
      FUZZ_CHECK(back.length(s) == lengths[s], "symbol %u: length %d after rewriting, was %u", s, back.length(s),
                 unsigned(lengths[s]));
  }

  // Decode until the bits run out. A single-symbol code reads no bits, so
  // it decodes once.
  std::vector<std::uint32_t> symbols;
  std::uint64_t consumed_end = table_end;
  for (;;) {
    if (in.bits_left() == 0 && !single) break;
    std::uint32_t s;
    try {
      s = code.decode(in);
    } catch (const hmc::detail::StreamError& e) {
      FUZZ_CHECK(e.error().status == Status::bad_layer, "decode raised %s: %s", hmc::status_name(e.error().status),
                 e.what());
      FUZZ_CHECK(in.bits_left() < 15, "decode failed with %llu bits left",
                 static_cast<unsigned long long>(in.bits_left()));
      break;
    }
    FUZZ_CHECK(s < alphabet, "decoded symbol %u outside the alphabet of %u", s, alphabet);
    FUZZ_CHECK(single || lengths[s] != 0, "decoded symbol %u has no code", s);
    const std::uint64_t now = nbits - in.bits_left();
    FUZZ_CHECK(now - consumed_end == lengths[s], "symbol %u took %llu bits, its length is %u", s,
               static_cast<unsigned long long>(now - consumed_end), unsigned(lengths[s]));
    consumed_end = now;
    symbols.push_back(s);
    if (single) break;
  }

  // Re-encoding the symbols reproduces the consumed bits.
  BitWriter w;
  for (std::uint32_t s : symbols) code.encode(w, s);
  const std::uint64_t written = w.bit_count();
  const std::vector<std::uint8_t> out = w.finish();
  FUZZ_CHECK(written == consumed_end - table_end, "re-encoding wrote %llu bits, decoding consumed %llu",
             static_cast<unsigned long long>(written), static_cast<unsigned long long>(consumed_end - table_end));
  for (std::uint64_t i = 0; i < written; ++i)
    FUZZ_CHECK(bit_at(out.data(), i) == bit_at(bits, table_end + i), "re-encoded bit %llu differs",
               static_cast<unsigned long long>(i));
  return 0;
}
