// SPDX-License-Identifier: AGPL-3.0-or-later
// The streaming decoder: incremental container framing (spec "Stream
// structure") in front of the whole-file decoder's per-chunk logic.
#include "codec/stream_decoder.hpp"

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <string>

#include "codec/format.hpp"
#include "util/error.hpp"

namespace hmc::detail {

namespace {

void* system_malloc(void*, std::size_t n) { return std::malloc(n); }
void* system_realloc(void*, void* p, std::size_t n) { return std::realloc(p, n); }
void system_free(void*, void* p) { std::free(p); }

// Above this, the buffer of a chunk is released once the chunk is decoded
// rather than kept for the next one.
constexpr std::size_t kKeepBuffer = std::size_t{1} << 20;

bool is_letter(char ch) { return (ch >= 'A' && ch <= 'Z') || (ch >= 'a' && ch <= 'z'); }

std::uint32_t load_u32(const std::uint8_t* p) {
  return std::uint32_t{p[0]} | std::uint32_t{p[1]} << 8 | std::uint32_t{p[2]} << 16 | std::uint32_t{p[3]} << 24;
}

}  // namespace

RawAllocator RawAllocator::system() {
  RawAllocator a;
  a.malloc_fn = system_malloc;
  a.realloc_fn = system_realloc;
  a.free_fn = system_free;
  return a;
}

StreamDecoder::StreamDecoder(const DecodeOptions& options, const RawAllocator& alloc, ErrorOrder order)
    : options_(options), alloc_(alloc), order_(order), chunks_(options) {}

StreamDecoder::~StreamDecoder() { release(); }

bool StreamDecoder::ended() const noexcept { return chunks_.ended(); }
bool StreamDecoder::header_ready() const noexcept { return chunks_.header_ready(); }
const Decoded& StreamDecoder::result() const noexcept { return chunks_.result(); }

void StreamDecoder::release() noexcept {
  if (body_) alloc_.free_fn(alloc_.user, body_);
  body_ = nullptr;
  body_cap_ = 0;
}

void StreamDecoder::reserve(std::size_t n) {
  if (n <= body_cap_) return;
  // Grow geometrically up to the chunk's size, never beyond what has
  // arrived: a header may declare 2 GiB that never come.
  std::size_t cap = body_cap_ ? body_cap_ : 256;
  while (cap < n) cap = cap > (SIZE_MAX >> 1) ? n : cap * 2;
  const std::size_t whole = std::size_t{length_} + 4;
  if (cap > whole) cap = whole;
  void* p = body_ ? alloc_.realloc_fn(alloc_.user, body_, cap) : alloc_.malloc_fn(alloc_.user, cap);
  if (!p) throw std::bad_alloc();
  body_ = static_cast<std::uint8_t*>(p);
  body_cap_ = cap;
}

Status StreamDecoder::feed(const std::uint8_t* data, std::size_t size) noexcept {
  if (failed()) return error_.status;
  if (finished_ || (!data && size)) return Status::invalid_argument;
  if (!size) return Status::ok;
  error_ = guarded<Error>([&] {
    consume(data, size);
    return Error{Status::ok, {}};
  });
  if (failed()) release();
  return error_.status;
}

Status StreamDecoder::finish() noexcept {
  if (failed() || finished_) return error_.status;
  finished_ = true;
  error_ = guarded<Error>([&] {
    if (held_) {
      if (held_after_end_)
        held_->message = std::to_string(fed_ - end_offset_) + " byte(s) follow the end chunk " + to_string(kEnd);
      return *held_;
    }
    chunks_.finish(tail());
    return Error{Status::ok, {}};
  });
  release();
  return error_.status;
}

// How the data ended, in the words parse_container uses for the same cut.
ContainerView StreamDecoder::tail() const {
  ContainerView v;
  switch (stage_) {
    case Stage::preamble:
      v.truncated = true;
      v.truncation = fed_ == 0 ? std::string("the stream is empty")
                               : "the stream ends inside the signature or version (" + std::to_string(fed_) + " bytes)";
      break;
    case Stage::chunk_header:
      if (head_len_ > 0) {
        v.truncated = true;
        v.truncation = "the stream ends inside a chunk header at offset " + std::to_string(chunk_offset_);
      }
      break;
    case Stage::chunk_body:
      v.truncated = true;
      v.truncation = "the stream ends inside chunk " + to_string(type_) + " at offset " + std::to_string(chunk_offset_) +
                     " (" + std::to_string(length_) + "-byte payload declared, " + std::to_string(body_len_) +
                     " bytes left)";
      break;
    case Stage::ended:
    case Stage::skip: break;
  }
  v.ended = !v.truncated;
  return v;
}

void StreamDecoder::complete_chunk(const ChunkType& type, std::uint32_t length, const std::uint8_t* body) {
  const std::uint32_t stored = load_u32(body + length);
  const std::uint32_t actual = chunk_crc(type, body, length);
  if (stored != actual)
    fail(Status::crc_mismatch, "chunk " + to_string(type) + " at offset " + std::to_string(chunk_offset_) +
                                   ": CRC-32 mismatch (stored " + std::to_string(stored) + ", computed " +
                                   std::to_string(actual) + ")");
  ChunkView c;
  c.type = type;
  c.offset = static_cast<std::size_t>(chunk_offset_);
  c.length = length;
  c.payload = body;
  if (order_ == ErrorOrder::stream) {
    chunks_.chunk(c);
  } else if (!held_) {  // after a content error, chunks are checked for framing only
    try {
      chunks_.chunk(c);
    } catch (const StreamError& e) {
      held_ = e.error();
    }
  }
  if (type == kEnd) end_offset_ = chunk_offset_ + kChunkOverhead + length;
  stage_ = type == kEnd ? Stage::ended : Stage::chunk_header;
  head_len_ = 0;
  body_len_ = 0;
}

void StreamDecoder::consume(const std::uint8_t* p, std::size_t n) {
  const std::uint64_t max = options_.limits.max_bytes;
  if (fed_ > max || n > max - fed_)
    fail(Status::limit_exceeded, "the stream has at least " + std::to_string(fed_ + n) +
                                     " bytes, over the limit of " + std::to_string(max));
  if (order_ == ErrorOrder::stream) return parse(p, n);
  // ErrorOrder::whole: a framing error outranks any content error held, and
  // ends parsing; the bytes after it are only counted (for the size limit).
  const std::uint64_t end = fed_ + n;
  if (stage_ != Stage::skip) {
    try {
      parse(p, n);
    } catch (const StreamError& e) {
      held_ = e.error();
      held_after_end_ = stage_ == Stage::ended;
      stage_ = Stage::skip;
    }
  }
  fed_ = end;
}

void StreamDecoder::parse(const std::uint8_t* p, std::size_t n) {
  while (n) {
    switch (stage_) {
      case Stage::preamble: {
        const std::size_t take = std::min(n, kPreambleSize - head_len_);
        std::memcpy(head_ + head_len_, p, take);
        head_len_ += take;
        p += take, n -= take, fed_ += take;
        const std::size_t sig = sizeof kSignature;
        if (std::memcmp(head_, kSignature, head_len_ < sig ? head_len_ : sig) != 0)
          fail(Status::bad_magic, "the first bytes are not the HMC signature 89 48 4D 43 0D 0A 1A 0A");
        if (head_len_ < kPreambleSize) break;
        const std::uint8_t major = head_[8], minor = head_[9];
        if (major != kVersionMajor)
          fail(Status::unsupported_version, "stream version " + std::to_string(major) + "." + std::to_string(minor) +
                                                "; this decoder reads major version " + std::to_string(kVersionMajor));
        chunks_.set_version(major, minor);
        stage_ = Stage::chunk_header;
        head_len_ = 0;
        break;
      }
      case Stage::chunk_header: {
        if (head_len_ == 0) chunk_offset_ = fed_;
        const std::size_t take = std::min(n, std::size_t{8} - head_len_);
        std::memcpy(head_ + head_len_, p, take);
        head_len_ += take;
        p += take, n -= take, fed_ += take;
        if (head_len_ < 8) break;
        std::memcpy(type_.data(), head_, 4);
        for (char ch : type_)
          if (!is_letter(ch))
            fail(Status::bad_chunk, "chunk at offset " + std::to_string(chunk_offset_) +
                                        " has a type that is not four ASCII letters");
        length_ = load_u32(head_ + 4);
        if (length_ > kMaxChunkLength)
          fail(Status::bad_chunk, "chunk " + to_string(type_) + " at offset " + std::to_string(chunk_offset_) +
                                      " declares length " + std::to_string(length_) + ", over the maximum 2^31-1");
        stage_ = Stage::chunk_body;
        body_len_ = 0;
        const std::size_t whole = std::size_t{length_} + 4;
        if (n >= whole) {  // the whole chunk is in this piece: decode it in place
          p += whole, n -= whole, fed_ += whole;
          complete_chunk(type_, length_, p - whole);
        }
        break;
      }
      case Stage::chunk_body: {
        const std::size_t whole = std::size_t{length_} + 4;
        const std::size_t take = std::min(n, whole - body_len_);
        reserve(body_len_ + take);
        std::memcpy(body_ + body_len_, p, take);
        body_len_ += take;
        p += take, n -= take, fed_ += take;
        if (body_len_ < whole) break;
        complete_chunk(type_, length_, body_);
        if (body_cap_ > kKeepBuffer) release();
        break;
      }
      case Stage::ended:
        fail(Status::bad_chunk, std::to_string(n) + " byte(s) follow the end chunk " + to_string(kEnd));
      case Stage::skip: return;
    }
  }
}

}  // namespace hmc::detail
