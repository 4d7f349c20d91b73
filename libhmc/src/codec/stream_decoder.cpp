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
  const std::size_t whole = std::size_t{header_.length} + 4;
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
        held_->message = after_end(fed_ - end_offset_, kEnd);
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
      v.truncation = cut_in_preamble(fed_);
      break;
    case Stage::chunk_header:
      if (head_len_ > 0) {
        v.truncated = true;
        v.truncation = cut_in_chunk_header(chunk_offset_);
      }
      break;
    case Stage::chunk_body:
      v.truncated = true;
      v.truncation = cut_in_chunk(header_, chunk_offset_, body_len_);
      break;
    case Stage::ended:
    case Stage::skip: break;
  }
  v.ended = !v.truncated;
  return v;
}

void StreamDecoder::complete_chunk(const std::uint8_t* body) {
  check_chunk_crc(header_, body, chunk_offset_);
  const ChunkType type = header_.type;
  ChunkView c;
  c.type = type;
  c.offset = static_cast<std::size_t>(chunk_offset_);
  c.length = header_.length;
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
  if (type == kEnd) end_offset_ = chunk_offset_ + kChunkOverhead + header_.length;
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
        check_preamble(head_, head_len_);
        if (head_len_ < kPreambleSize) break;
        chunks_.set_version(head_[8], head_[9]);
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
        header_ = read_chunk_header(head_, chunk_offset_);
        stage_ = Stage::chunk_body;
        body_len_ = 0;
        const std::size_t whole = std::size_t{header_.length} + 4;
        if (n >= whole) {  // the whole chunk is in this piece: decode it in place
          p += whole, n -= whole, fed_ += whole;
          complete_chunk(p - whole);
        }
        break;
      }
      case Stage::chunk_body: {
        const std::size_t whole = std::size_t{header_.length} + 4;
        const std::size_t take = std::min(n, whole - body_len_);
        reserve(body_len_ + take);
        std::memcpy(body_ + body_len_, p, take);
        body_len_ += take;
        p += take, n -= take, fed_ += take;
        if (body_len_ < whole) break;
        complete_chunk(body_);
        if (body_cap_ > kKeepBuffer) release();
        break;
      }
      case Stage::ended: fail_after_end(n, kEnd);
      case Stage::skip: return;
    }
  }
}

}  // namespace hmc::detail
