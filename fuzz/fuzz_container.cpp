// SPDX-License-Identifier: AGPL-3.0-or-later
// Fuzz target: the container framing (hmc::detail::parse_container) on
// arbitrary bytes, checked against a straightforward reading of spec
// section 2 written here (with its own bitwise CRC-32): the same error
// class, the same chunks, the same truncation verdict.
#include <cstring>
#include <string>
#include <vector>

#include "container/container.hpp"
#include "fuzz_check.hpp"
#include "util/error.hpp"

namespace {

using hmc::Status;
using hmc::detail::ChunkType;

std::uint32_t crc32_bitwise(const std::uint8_t* p, std::size_t n, std::uint32_t crc) {
  for (std::size_t i = 0; i < n; ++i) {
    crc ^= p[i];
    for (int k = 0; k < 8; ++k) crc = (crc & 1u) ? (crc >> 1) ^ 0xEDB88320u : crc >> 1;
  }
  return crc;
}

std::uint32_t le32(const std::uint8_t* p) {
  return p[0] | (std::uint32_t{p[1]} << 8) | (std::uint32_t{p[2]} << 16) | (std::uint32_t{p[3]} << 24);
}

struct RefChunk {
  std::size_t offset;
  std::uint32_t length;
};

struct RefResult {
  Status status = Status::ok;
  bool truncated = false;
  std::vector<RefChunk> chunks;
};

bool is_letter(std::uint8_t c) { return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z'); }

RefResult reference_parse(const std::uint8_t* d, std::size_t size, const ChunkType& stop) {
  static const std::uint8_t sig[8] = {0x89, 0x48, 0x4D, 0x43, 0x0D, 0x0A, 0x1A, 0x0A};
  RefResult r;
  if (size == 0) {
    r.truncated = true;
    return r;
  }
  for (std::size_t i = 0; i < 8 && i < size; ++i)
    if (d[i] != sig[i]) {
      r.status = Status::bad_magic;
      return r;
    }
  if (size < 10) {
    r.truncated = true;
    return r;
  }
  if (d[8] != 0) {
    r.status = Status::unsupported_version;
    return r;
  }
  std::size_t pos = 10;
  while (pos < size) {
    if (size - pos < 8) {
      r.truncated = true;
      return r;
    }
    for (int i = 0; i < 4; ++i)
      if (!is_letter(d[pos + static_cast<std::size_t>(i)])) {
        r.status = Status::bad_chunk;
        return r;
      }
    const std::uint32_t len = le32(d + pos + 4);
    if (len > 0x7fffffffu) {
      r.status = Status::bad_chunk;
      return r;
    }
    if (size - pos - 8 < std::size_t{len} + 4) {
      r.truncated = true;
      return r;
    }
    std::uint32_t crc = crc32_bitwise(d + pos, 4, 0xffffffffu);
    crc = crc32_bitwise(d + pos + 8, len, crc) ^ 0xffffffffu;
    if (crc != le32(d + pos + 8 + len)) {
      r.status = Status::crc_mismatch;
      return r;
    }
    r.chunks.push_back({pos, len});
    const bool last = std::memcmp(d + pos, stop.data(), 4) == 0;
    pos += 12 + std::size_t{len};
    if (last) {
      if (pos != size) r.status = Status::bad_chunk;
      return r;
    }
  }
  return r;
}

void check(const std::uint8_t* data, std::size_t size, const ChunkType& stop) {
  const RefResult ref = reference_parse(data, size, stop);
  hmc::detail::ContainerView v;
  try {
    v = hmc::detail::parse_container(data, size, stop);
  } catch (const hmc::detail::StreamError& e) {
    FUZZ_CHECK(e.error().status == ref.status, "parse_container raised %s (%s), the reference says %s",
               hmc::status_name(e.error().status), e.what(), hmc::status_name(ref.status));
    return;
  }
  FUZZ_CHECK(ref.status == Status::ok, "parse_container succeeded, the reference says %s",
             hmc::status_name(ref.status));
  FUZZ_CHECK(v.truncated == ref.truncated, "truncated %d, the reference says %d", int(v.truncated),
             int(ref.truncated));
  FUZZ_CHECK(v.ended == !v.truncated, "ended %d with truncated %d", int(v.ended), int(v.truncated));
  FUZZ_CHECK(!v.truncated || !v.truncation.empty(), "truncated without a message");
  FUZZ_CHECK(v.chunks.size() == ref.chunks.size(), "%zu chunks, the reference finds %zu", v.chunks.size(),
             ref.chunks.size());
  if (size >= 10) FUZZ_CHECK(v.major == data[8] && v.minor == data[9], "version bytes not reported");

  // Every chunk re-serializes to the bytes it came from.
  hmc::detail::ContainerWriter w;
  for (std::size_t i = 0; i < v.chunks.size(); ++i) {
    const auto& c = v.chunks[i];
    FUZZ_CHECK(c.offset == ref.chunks[i].offset && c.length == ref.chunks[i].length,
               "chunk %zu at %zu (length %u), the reference has %zu (length %u)", i, c.offset, c.length,
               ref.chunks[i].offset, ref.chunks[i].length);
    FUZZ_CHECK(c.payload == data + c.offset + 8, "chunk %zu payload pointer is off", i);
    FUZZ_CHECK(std::memcmp(c.type.data(), data + c.offset, 4) == 0, "chunk %zu type differs", i);
    FUZZ_CHECK(hmc::detail::chunk_crc(c.type, c.payload, c.length) == le32(c.payload + c.length),
               "chunk %zu CRC accepted but wrong", i);
    w.chunk(c.type, std::vector<std::uint8_t>(c.payload, c.payload + c.length));
  }
  const std::vector<std::uint8_t> again = w.finish();
  // (The writer always adds a 10-byte preamble, which a short input lacks.)
  if (!v.chunks.empty()) {
    FUZZ_CHECK(again.size() <= size, "re-serialized chunks are longer than the input");
    FUZZ_CHECK(std::memcmp(again.data() + 10, data + 10, again.size() - 10) == 0,
               "re-serialized chunks differ from the input");
  }
  if (!v.truncated && size >= 10)
    FUZZ_CHECK(again.size() == size, "a complete container of %zu bytes re-serializes to %zu", size,
               again.size());
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  check(data, size, hmc::detail::chunk_type("HEND"));
  // Also with an end chunk type taken from the input when it has one, so
  // that the "bytes after the end chunk" path sees other types.
  if (size >= 14) {
    ChunkType t;
    std::memcpy(t.data(), data + 10, 4);
    check(data, size, t);
  }
  return 0;
}
