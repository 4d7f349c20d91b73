// SPDX-License-Identifier: AGPL-3.0-or-later
// Decoding chunk by chunk, and the streaming decoder built on it.
//
// ChunkDecoder is the whole-file decoder's per-chunk logic (spec "Decoding
// process and output", steps 2-6): decode() in decoder.cpp runs it over the
// chunks of a parsed container, and StreamDecoder runs it over chunks as
// their last byte arrives. Both therefore apply the same order rules, the
// same layer and reconstruction code and the same truncation rules.
//
// StreamDecoder receives the container incrementally: it keeps only the
// chunk being received, checks each chunk's CRC once it is complete (with
// the framing checks of container/, shared with parse_container), and hands
// it to the ChunkDecoder. A level is reported as soon as
// the chunk that completes it (its layer chunk, or for surfaces and volumes
// its RCON) has arrived.
//
// Errors. decode() checks the size limit before reading anything, then the
// framing (signature, version, chunk types, lengths, CRCs, bytes after
// HEND) of the whole stream, and only then interprets chunks (spec section
// 13). A streaming decoder cannot see ahead, so it offers two orders:
//  - ErrorOrder::stream (the default): it fails at once on the first defect
//    in stream order. On a stream with several defects it may then report a
//    content error (say bad_layer) where decode() reports a framing error
//    further on (say crc_mismatch), or a framing error where decode()
//    reports the size limit.
//  - ErrorOrder::whole: it reports what decode() reports. A defect is held
//    (later bytes are still checked for framing, or only counted after a
//    framing error) and becomes the error at finish(), unless a defect that
//    decode() ranks first turns up (a framing error after a content error;
//    the size limit at any time, reported at once).
// Either way the levels complete before the first defect are reported as
// they arrive. On valid and cut streams, and (in stream order) on streams
// with one defect, the outcome (levels, points, simplices, status,
// truncation and warning) is the same as decode()'s.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "container/container.hpp"
#include "hmc/codec.hpp"

namespace hmc::detail {

/// The decoder's per-chunk state machine (defined in decoder.cpp). Raises
/// StreamError like the rest of detail.
class ChunkDecoder {
 public:
  explicit ChunkDecoder(const DecodeOptions& options);
  ~ChunkDecoder();
  ChunkDecoder(const ChunkDecoder&) = delete;
  ChunkDecoder& operator=(const ChunkDecoder&) = delete;

  /// The preamble's version bytes, recorded in the output.
  void set_version(std::uint8_t major, std::uint8_t minor);
  /// Interpret one complete chunk whose CRC has been checked. Returns true
  /// when it completed a level (appended to result().levels).
  bool chunk(const ChunkView& c);
  /// The data ended: `tail.truncated` and `tail.truncation` say whether it
  /// ended inside a chunk (other fields are ignored). Applies the truncation
  /// rules: fails with Status::truncated when no level is complete, else sets
  /// the output's warning and truncated flag when HEND was not read.
  void finish(const ContainerView& tail);

  /// What is decoded so far (levels coarsest first).
  const Decoded& result() const;
  /// The result, once every reconstruction has finished.
  Decoded take();
  /// Reconstruct each level on a second thread while the next chunks are
  /// decoded (DecodeOptions::threads). A completed level's connectivity is
  /// then in place only after the next chunk() or finish(), so only the
  /// whole-buffer decode() turns it on; the default is off.
  void set_overlap(bool on);
  /// Every chunk of the stream, in order, whose memory outlives the
  /// decoder: with overlap, the refinement layers' points are then decoded
  /// ahead on the second thread (decode() only).
  void set_chunks(const std::vector<ChunkView>* chunks);
  /// HEAD and SQNT have been read (kind, quantizer and declared levels are known).
  bool header_ready() const;
  /// HEND has been read.
  bool ended() const;

 private:
  bool chunk_impl(const ChunkView& c);
  void finish_impl(const ContainerView& tail);
  struct State;
  std::unique_ptr<State> s_;
};

/// malloc/realloc/free-style functions with a user pointer; the streaming
/// decoder takes its input buffer from them.
struct RawAllocator {
  void* (*malloc_fn)(void* user, std::size_t size) = nullptr;
  void* (*realloc_fn)(void* user, void* ptr, std::size_t size) = nullptr;
  void (*free_fn)(void* user, void* ptr) = nullptr;
  void* user = nullptr;

  /// malloc, realloc and free from the C library.
  static RawAllocator system();
};

/// Incremental decoder: feed bytes in pieces of any size. Never throws.
///
/// After an error every later feed() and finish() returns the same error
/// (a permanent failed state); the levels completed before it stay readable.
class StreamDecoder {
 public:
  /// When errors are reported (see the top of this file).
  enum class ErrorOrder { stream, whole };

  explicit StreamDecoder(const DecodeOptions& options = {}, const RawAllocator& alloc = RawAllocator::system(),
                         ErrorOrder order = ErrorOrder::stream);
  ~StreamDecoder();
  StreamDecoder(const StreamDecoder&) = delete;
  StreamDecoder& operator=(const StreamDecoder&) = delete;

  /// Consume `size` more bytes of the stream, decoding every chunk they
  /// complete. Status::ok, or the stream's error. Feeding after finish()
  /// is invalid_argument (and leaves the decoder as it was).
  Status feed(const std::uint8_t* data, std::size_t size) noexcept;
  /// No more bytes will come. Status::ok when the stream was complete or
  /// was cut after at least one complete level (then result().warning says
  /// where, and result().truncated whether a requested level is missing);
  /// Status::truncated, an error, when no level is complete.
  Status finish() noexcept;

  /// Status::ok, or the error that put the decoder in its failed state.
  Status status() const noexcept { return error_.status; }
  bool failed() const noexcept { return error_.status != Status::ok; }
  const Error& error() const noexcept { return error_; }
  bool finished() const noexcept { return finished_; }
  /// HEND has been read.
  bool ended() const noexcept;
  /// HEAD and SQNT have been read.
  bool header_ready() const noexcept;
  /// Levels decoded so far, coarsest first, and the stream's header fields.
  const Decoded& result() const noexcept;
  /// Bytes consumed so far.
  std::uint64_t bytes_fed() const noexcept { return fed_; }

 private:
  // skip: ErrorOrder::whole after a framing error; bytes are only counted.
  enum class Stage { preamble, chunk_header, chunk_body, ended, skip };
  void consume(const std::uint8_t* data, std::size_t size);  // raises StreamError
  void parse(const std::uint8_t* data, std::size_t size);    // raises StreamError
  void complete_chunk(const std::uint8_t* body);
  void reserve(std::size_t n);
  void release() noexcept;
  ContainerView tail() const;

  DecodeOptions options_;
  RawAllocator alloc_;
  ErrorOrder order_;
  std::optional<Error> held_;      // ErrorOrder::whole: what decode() would report so far
  bool held_after_end_ = false;    // held_ is "bytes after HEND": its count grows
  std::uint64_t end_offset_ = 0;   // where HEND ended
  ChunkDecoder chunks_;
  Error error_{Status::ok, {}};
  bool finished_ = false;
  Stage stage_ = Stage::preamble;
  std::uint64_t fed_ = 0;            // bytes consumed
  std::uint64_t chunk_offset_ = 0;   // stream offset of the chunk being received
  std::uint8_t head_[kPreambleSize > 8 ? kPreambleSize : 8] = {};  // preamble or chunk header bytes
  std::size_t head_len_ = 0;
  ChunkHeader header_{};            // type and payload length of the chunk being received
  std::uint8_t* body_ = nullptr;     // payload + CRC of the chunk being received
  std::size_t body_len_ = 0, body_cap_ = 0;
};

}  // namespace hmc::detail
