// SPDX-License-Identifier: AGPL-3.0-or-later
#include "container/container.hpp"

#ifndef HMC_NO_ZLIB
#include <zlib.h>
#endif

#include <array>
#include <cstring>

#include "util/bytes.hpp"
#include "util/error.hpp"

namespace hmc::detail {

#ifdef HMC_NO_ZLIB
namespace {
// A build without zlib (HMC_WITH_ZLIB=OFF, e.g. WebAssembly): the same
// CRC-32 as zlib's crc32() (reflected polynomial 0xEDB88320, initial value
// and final xor 0xFFFFFFFF), one table look-up per byte.
std::array<std::uint32_t, 256> make_crc_table() {
  std::array<std::uint32_t, 256> t{};
  for (std::uint32_t i = 0; i < 256; ++i) {
    std::uint32_t c = i;
    for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
    t[i] = c;
  }
  return t;
}

std::uint32_t crc_update(std::uint32_t crc, const std::uint8_t* p, std::size_t n) {
  static const std::array<std::uint32_t, 256> table = make_crc_table();
  crc = ~crc;
  for (std::size_t i = 0; i < n; ++i) crc = table[(crc ^ p[i]) & 0xFFu] ^ (crc >> 8);
  return ~crc;
}
}  // namespace

std::uint32_t chunk_crc(const ChunkType& type, const std::uint8_t* payload, std::size_t n) {
  const std::uint32_t crc = crc_update(0u, reinterpret_cast<const std::uint8_t*>(type.data()), 4);
  return crc_update(crc, payload, n);
}
#else
std::uint32_t chunk_crc(const ChunkType& type, const std::uint8_t* payload, std::size_t n) {
  uLong crc = crc32(0L, Z_NULL, 0);
  crc = crc32(crc, reinterpret_cast<const Bytef*>(type.data()), 4);
  // zlib takes uInt lengths: feed large payloads in pieces.
  while (n) {
    const uInt piece = n > 0x40000000u ? 0x40000000u : static_cast<uInt>(n);
    crc = crc32(crc, payload, piece);
    payload += piece;
    n -= piece;
  }
  return static_cast<std::uint32_t>(crc);
}
#endif

ContainerWriter::ContainerWriter() {
  out_.assign(std::begin(kSignature), std::end(kSignature));
  out_.push_back(kVersionMajor);
  out_.push_back(kVersionMinor);
}

void ContainerWriter::chunk(const ChunkType& type, const std::vector<std::uint8_t>& payload) {
  if (payload.size() > kMaxChunkLength) fail(Status::invalid_argument, "chunk " + to_string(type) + " is too large");
  ByteWriter w;
  w.bytes(reinterpret_cast<const std::uint8_t*>(type.data()), 4);
  w.u32(static_cast<std::uint32_t>(payload.size()));
  w.bytes(payload);
  w.u32(chunk_crc(type, payload.data(), payload.size()));
  out_.insert(out_.end(), w.data().begin(), w.data().end());
}

namespace {
std::uint32_t load_u32(const std::uint8_t* p) {
  return std::uint32_t{p[0]} | std::uint32_t{p[1]} << 8 | std::uint32_t{p[2]} << 16 | std::uint32_t{p[3]} << 24;
}
bool is_letter(char ch) { return (ch >= 'A' && ch <= 'Z') || (ch >= 'a' && ch <= 'z'); }
}  // namespace

void check_preamble(const std::uint8_t* head, std::size_t n) {
  if (n == 0) return;
  const std::size_t sig = sizeof kSignature;
  if (std::memcmp(head, kSignature, n < sig ? n : sig) != 0)
    fail(Status::bad_magic, "the first bytes are not the HMC signature 89 48 4D 43 0D 0A 1A 0A");
  if (n < kPreambleSize) return;
  const std::uint8_t major = head[8], minor = head[9];
  if (major != kVersionMajor)
    fail(Status::unsupported_version, "stream version " + std::to_string(major) + "." + std::to_string(minor) +
                                          "; this decoder reads major version " + std::to_string(kVersionMajor));
}

ChunkHeader read_chunk_header(const std::uint8_t* h, std::uint64_t offset) {
  ChunkHeader c;
  std::memcpy(c.type.data(), h, 4);
  for (char ch : c.type)
    if (!is_letter(ch))
      fail(Status::bad_chunk, "chunk at offset " + std::to_string(offset) + " has a type that is not four ASCII letters");
  c.length = load_u32(h + 4);
  if (c.length > kMaxChunkLength)
    fail(Status::bad_chunk, "chunk " + to_string(c.type) + " at offset " + std::to_string(offset) + " declares length " +
                                std::to_string(c.length) + ", over the maximum 2^31-1");
  return c;
}

void check_chunk_crc(const ChunkHeader& c, const std::uint8_t* payload, std::uint64_t offset) {
  const std::uint32_t stored = load_u32(payload + c.length);
  const std::uint32_t actual = chunk_crc(c.type, payload, c.length);
  if (stored != actual)
    fail(Status::crc_mismatch, "chunk " + to_string(c.type) + " at offset " + std::to_string(offset) +
                                   ": CRC-32 mismatch (stored " + std::to_string(stored) + ", computed " +
                                   std::to_string(actual) + ")");
}

std::string after_end(std::uint64_t n, const ChunkType& end) {
  return std::to_string(n) + " byte(s) follow the end chunk " + to_string(end);
}

void fail_after_end(std::uint64_t n, const ChunkType& end) { fail(Status::bad_chunk, after_end(n, end)); }

std::string cut_in_preamble(std::uint64_t n) {
  return n == 0 ? std::string("the stream is empty")
                : "the stream ends inside the signature or version (" + std::to_string(n) + " bytes)";
}

std::string cut_in_chunk_header(std::uint64_t offset) {
  return "the stream ends inside a chunk header at offset " + std::to_string(offset);
}

std::string cut_in_chunk(const ChunkHeader& c, std::uint64_t offset, std::uint64_t left) {
  return "the stream ends inside chunk " + to_string(c.type) + " at offset " + std::to_string(offset) + " (" +
         std::to_string(c.length) + "-byte payload declared, " + std::to_string(left) + " bytes left)";
}

ContainerView parse_container(const std::uint8_t* data, std::size_t size, const ChunkType& stop_after) {
  ContainerView v;
  check_preamble(data, size < kPreambleSize ? size : kPreambleSize);
  if (size < kPreambleSize) {
    v.truncated = true;
    v.truncation = cut_in_preamble(size);
    return v;
  }
  v.major = data[8];
  v.minor = data[9];
  std::size_t pos = kPreambleSize;
  while (pos < size) {
    if (size - pos < 8) {
      v.truncated = true;
      v.truncation = cut_in_chunk_header(pos);
      return v;
    }
    const ChunkHeader h = read_chunk_header(data + pos, pos);
    if (size - pos - 8 < std::uint64_t{h.length} + 4) {
      v.truncated = true;
      v.truncation = cut_in_chunk(h, pos, size - pos - 8);
      return v;
    }
    check_chunk_crc(h, data + pos + 8, pos);
    ChunkView c;
    c.offset = pos;
    c.type = h.type;
    c.length = h.length;
    c.payload = data + pos + 8;
    v.chunks.push_back(c);
    pos += kChunkOverhead + c.length;
    if (c.type == stop_after) {
      if (pos != size) fail_after_end(size - pos, stop_after);
      break;
    }
  }
  v.ended = true;
  return v;
}

}  // namespace hmc::detail
