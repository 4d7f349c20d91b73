// SPDX-License-Identifier: AGPL-3.0-or-later
// The container (spec "Container"): signature, version, then chunks of
// type (4 ASCII letters), length (u32 LE), payload and CRC-32 (u32 LE, over
// type and payload). A chunk whose type starts with an upper-case letter is
// critical; lower-case is ancillary and may be skipped by a decoder that
// does not know it. This layer checks framing and CRCs only; which chunks
// may appear where is the codec's business (codec/format.hpp).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace hmc::detail {

constexpr std::uint8_t kSignature[8] = {0x89, 'H', 'M', 'C', 0x0D, 0x0A, 0x1A, 0x0A};
constexpr std::uint8_t kVersionMajor = 0;
constexpr std::uint8_t kVersionMinor = 27;
constexpr std::uint32_t kMaxChunkLength = 0x7fffffffu;
constexpr std::size_t kPreambleSize = 10;       // signature + major + minor
constexpr std::size_t kChunkOverhead = 12;      // type + length + CRC

using ChunkType = std::array<char, 4>;

constexpr ChunkType chunk_type(const char (&s)[5]) { return {s[0], s[1], s[2], s[3]}; }
inline std::string to_string(const ChunkType& t) { return std::string(t.data(), 4); }
inline bool is_critical(const ChunkType& t) { return t[0] >= 'A' && t[0] <= 'Z'; }

/// CRC-32 (ISO-HDLC polynomial, as zlib's crc32) of type bytes then payload.
std::uint32_t chunk_crc(const ChunkType& type, const std::uint8_t* payload, std::size_t n);

class ContainerWriter {
 public:
  ContainerWriter();
  void chunk(const ChunkType& type, const std::vector<std::uint8_t>& payload);
  std::vector<std::uint8_t> finish() { return std::move(out_); }
  std::size_t size() const { return out_.size(); }

 private:
  std::vector<std::uint8_t> out_;
};

struct ChunkView {
  ChunkType type{};
  std::size_t offset = 0;  ///< offset of the chunk's type field in the stream
  std::uint32_t length = 0;
  const std::uint8_t* payload = nullptr;
};

struct ContainerView {
  std::uint8_t major = 0, minor = 0;
  std::vector<ChunkView> chunks;  ///< complete chunks with valid CRCs, in stream order
  bool ended = false;             ///< the stream stops where a chunk ends (no partial chunk)
  bool truncated = false;         ///< the data ends inside a chunk (or before the first one)
  std::string truncation;         ///< where and how, when truncated
};

// The framing checks, one place for both readers of the container: the
// whole-buffer parse_container() below and the streaming decoder
// (codec/stream_decoder.cpp), which receives the same bytes in pieces. Each
// raises the spec's error with the same message for the same defect.

/// The first `n` bytes (n <= kPreambleSize) of a stream: bad_magic when they
/// are not a prefix of the signature; once all kPreambleSize bytes are
/// there, unsupported_version for a major version this decoder does not read.
void check_preamble(const std::uint8_t* head, std::size_t n);

struct ChunkHeader {
  ChunkType type{};
  std::uint32_t length = 0;
};
/// The 8 bytes of a chunk header at stream offset `offset`: bad_chunk for
/// type bytes that are not four ASCII letters or a length over 2^31-1.
ChunkHeader read_chunk_header(const std::uint8_t* h, std::uint64_t offset);
/// crc_mismatch unless the 4 bytes after `length` bytes of `payload` hold
/// the CRC-32 of `type` and the payload.
void check_chunk_crc(const ChunkHeader& c, const std::uint8_t* payload, std::uint64_t offset);
/// The bad_chunk raised for `n` bytes after the end chunk `end`, and its message.
[[noreturn]] void fail_after_end(std::uint64_t n, const ChunkType& end);
std::string after_end(std::uint64_t n, const ChunkType& end);

/// How a cut stream ends, in the words both readers report.
std::string cut_in_preamble(std::uint64_t n);
std::string cut_in_chunk_header(std::uint64_t offset);
std::string cut_in_chunk(const ChunkHeader& c, std::uint64_t offset, std::uint64_t left);

/// Parse the framing of `size` bytes. Raises bad_magic, unsupported_version,
/// bad_chunk (invalid type bytes, length over 2^31-1) and crc_mismatch.
/// Stopping inside a chunk is not an error here: it is reported in
/// `truncated` and the codec decides whether enough came before it.
/// `stop_after` ends parsing after a chunk of that type (the end chunk); any
/// bytes after it raise bad_chunk.
ContainerView parse_container(const std::uint8_t* data, std::size_t size, const ChunkType& stop_after);

}  // namespace hmc::detail
