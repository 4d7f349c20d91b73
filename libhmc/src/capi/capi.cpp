// SPDX-License-Identifier: AGPL-3.0-or-later
// The C API (hmc/hmc.h) over the C++ library. Every entry point catches
// everything: no exception leaves this file.
#include "hmc/hmc.h"

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <new>
#include <optional>
#include <string>
#include <type_traits>
#include <utility>

#include "codec/stream_decoder.hpp"
#include "hmc/codec.hpp"

using hmc::Decoded;
using hmc::Status;

static_assert(sizeof(hmc::GridPoint) == 3 * sizeof(std::uint32_t), "GridPoint must be three packed uint32");
static_assert(sizeof(hmc::Triangle) == 3 * sizeof(std::uint32_t), "Triangle must be three packed uint32");
static_assert(sizeof(hmc::Tetrahedron) == 4 * sizeof(std::uint32_t), "Tetrahedron must be four packed uint32");
static_assert(static_cast<int>(Status::internal_error) == HMC_INTERNAL_ERROR &&
                  static_cast<int>(Status::limit_exceeded) == HMC_LIMIT_EXCEEDED &&
                  static_cast<int>(Status::bad_magic) == HMC_BAD_MAGIC,
              "hmc_status mirrors hmc::Status");

namespace {

void* system_malloc(void*, std::size_t n) { return std::malloc(n); }
void* system_realloc(void*, void* p, std::size_t n) { return std::realloc(p, n); }
void system_free(void*, void* p) { std::free(p); }

constexpr hmc_allocator kSystem = {system_malloc, system_realloc, system_free, nullptr};

bool usable(const hmc_allocator* a) { return !a || (a->malloc_fn && a->realloc_fn && a->free_fn); }

hmc::detail::RawAllocator raw(const hmc_allocator& a) {
  hmc::detail::RawAllocator r;
  r.malloc_fn = a.malloc_fn;
  r.realloc_fn = a.realloc_fn;
  r.free_fn = a.free_fn;
  r.user = a.user;
  return r;
}

hmc_status to_c(Status s) { return static_cast<hmc_status>(static_cast<int>(s)); }

// Handles live in memory from the caller's allocator.
template <class T>
T* create_handle(const hmc_allocator* allocator) noexcept {
  if (!usable(allocator)) return nullptr;
  const hmc_allocator a = allocator ? *allocator : kSystem;
  void* mem = a.malloc_fn(a.user, sizeof(T));
  if (!mem) return nullptr;
  try {
    return new (mem) T(a);
  } catch (...) {
    a.free_fn(a.user, mem);
    return nullptr;
  }
}

template <class T>
void destroy_handle(T* h) noexcept {
  if (!h) return;
  const hmc_allocator a = h->alloc;
  h->~T();
  a.free_fn(a.user, h);
}

// Runs `f`, turning any exception into a status and a message.
template <class F>
hmc_status guard(std::string& message, F&& f) noexcept {
  try {
    return f();
  } catch (const std::bad_alloc&) {
    try {
      message = "allocation failed";
    } catch (...) {
    }
    return HMC_OUT_OF_MEMORY;
  } catch (const std::exception& e) {
    try {
      message = e.what();
    } catch (...) {
    }
    return HMC_INTERNAL_ERROR;
  } catch (...) {
    return HMC_INTERNAL_ERROR;
  }
}

// Copies `n` values into a buffer from the caller's allocator.
template <class T>
hmc_status hand_out(const hmc_allocator& a, const void* src, std::size_t n, T** out, std::string& message) {
  *out = nullptr;
  if (n == 0) return HMC_OK;
  if (n > SIZE_MAX / sizeof(T)) {
    message = "the buffer would exceed the address space";
    return HMC_OUT_OF_MEMORY;
  }
  void* p = a.malloc_fn(a.user, n * sizeof(T));
  if (!p) {
    message = "the allocator returned NULL for " + std::to_string(n * sizeof(T)) + " bytes";
    return HMC_OUT_OF_MEMORY;
  }
  if (src) std::memcpy(p, src, n * sizeof(T));
  *out = static_cast<T*>(p);
  return HMC_OK;
}

}  // namespace

struct hmc_encoder {
  explicit hmc_encoder(const hmc_allocator& a) : alloc(a) {}
  hmc_allocator alloc;
  hmc::EncodeOptions options;
  std::string message;
  std::string notes;  // of the last successful encode, a line each
};

struct hmc_decoder {
  explicit hmc_decoder(const hmc_allocator& a) : alloc(a) {}
  hmc_allocator alloc;
  hmc::DecodeOptions options;
  hmc::detail::StreamDecoder::ErrorOrder order = hmc::detail::StreamDecoder::ErrorOrder::stream;
  std::optional<hmc::detail::StreamDecoder> stream;  // fed in pieces
  std::optional<Decoded> whole;                      // or decoded at once
  std::uint64_t whole_size = 0;
  hmc_status state = HMC_OK;  // HMC_OK, HMC_INCOMPLETE after a cut stream, or the error
  bool finished = false;
  std::string failure;          // the error's message, once failed
  mutable std::string message;  // the last non-OK status' message

  bool failed() const { return state != HMC_OK && state != HMC_INCOMPLETE; }
  bool begun() const { return stream || whole || failed(); }
  const Decoded* result() const { return whole ? &*whole : stream ? &stream->result() : nullptr; }
  hmc_status fail(hmc_status s, std::string m) {
    state = s;
    failure = std::move(m);
    message = failure;
    return s;
  }
  hmc_status misuse(std::string m) const {
    message = std::move(m);
    return HMC_INVALID_ARGUMENT;
  }
  // After hmc_decoder_finish or a whole decode: incomplete if the end chunk was missing.
  hmc_status finished_ok(const Decoded& d) {
    finished = true;
    if (d.warning.empty()) return state = HMC_OK;
    message = d.warning;
    return state = HMC_INCOMPLETE;
  }
  const hmc::DecodedLevel* level(std::size_t index) const {
    const Decoded* d = result();
    if (!d || index >= d->levels.size()) {
      message = "level " + std::to_string(index) + " is not complete (" +
                std::to_string(d ? d->levels.size() : 0) + " levels are)";
      return nullptr;
    }
    return &d->levels[index];
  }
};

extern "C" {

const char* hmc_version_string(void) { return hmc::version_string(); }

const char* hmc_status_string(hmc_status status) {
  if (status == HMC_INCOMPLETE) return "incomplete";
  return hmc::status_name(static_cast<Status>(static_cast<int>(status)));
}

const char* hmc_status_description(hmc_status status) {
  if (status == HMC_INCOMPLETE) return "the stream stopped before its end, after at least one complete level";
  return hmc::status_description(static_cast<Status>(static_cast<int>(status)));
}

void hmc_free(const hmc_allocator* allocator, void* ptr) {
  if (!ptr) return;
  const hmc_allocator& a = allocator ? *allocator : kSystem;
  a.free_fn(a.user, ptr);
}

// ---------------------------------------------------------------- encoder

void hmc_encode_options_init(hmc_encode_options* options) {
  if (!options) return;
  const hmc::EncodeOptions d;
  options->bits = d.bits;
  options->levels = d.levels;
  options->removal_ratio = d.removal_ratio;
  options->kind = HMC_KIND_AUTO;
  options->fidelity = static_cast<int>(d.fidelity);
  options->boundary_mode = static_cast<int>(d.boundary_mode);
  options->optimizer = static_cast<int>(d.optimizer);
  options->write_info = d.write_info ? 1 : 0;
  options->fast_decode = d.fast_decode ? 1 : 0;
}

hmc_encoder* hmc_encoder_create(const hmc_allocator* allocator) { return create_handle<hmc_encoder>(allocator); }

void hmc_encoder_destroy(hmc_encoder* encoder) { destroy_handle(encoder); }

hmc_status hmc_encoder_set_threads(hmc_encoder* encoder, unsigned threads) {
  if (!encoder) return HMC_INVALID_ARGUMENT;
  return guard(encoder->message, [&]() -> hmc_status {
    if (threads < 1 || threads > 64) {
      encoder->message = "threads must be between 1 and 64, got " + std::to_string(threads);
      return HMC_INVALID_ARGUMENT;
    }
    encoder->options.threads = threads;
    return HMC_OK;
  });
}

hmc_status hmc_encoder_set_preview_ratio(hmc_encoder* encoder, double ratio) {
  if (!encoder) return HMC_INVALID_ARGUMENT;
  return guard(encoder->message, [&]() -> hmc_status {
    if (!(ratio >= 0 && ratio < 1)) {
      encoder->message = "preview ratio must be in [0, 1), got " + std::to_string(ratio);
      return HMC_INVALID_ARGUMENT;
    }
    encoder->options.preview_ratio = ratio;
    return HMC_OK;
  });
}

hmc_status hmc_encoder_set_options(hmc_encoder* encoder, const hmc_encode_options* o) {
  if (!encoder) return HMC_INVALID_ARGUMENT;
  return guard(encoder->message, [&]() -> hmc_status {
    auto bad = [&](const std::string& m) {
      encoder->message = m;
      return HMC_INVALID_ARGUMENT;
    };
    if (!o) return bad("options is NULL");
    if (o->bits < 1 || o->bits > 21) return bad("bits must be between 1 and 21, got " + std::to_string(o->bits));
    if (o->levels < 1 || o->levels > HMC_MAX_LEVELS)
      return bad("levels must be between 1 and 64, got " + std::to_string(o->levels));
    if (!(o->removal_ratio > 0 && o->removal_ratio <= 1)) return bad("removal_ratio must be in (0, 1]");
    if (o->kind < HMC_KIND_AUTO || o->kind > HMC_KIND_VOLUME) return bad("unknown kind " + std::to_string(o->kind));
    if (o->fidelity < 0 || o->fidelity > 3) return bad("unknown fidelity " + std::to_string(o->fidelity));
    if (o->boundary_mode < 0 || o->boundary_mode > 2)
      return bad("unknown boundary mode " + std::to_string(o->boundary_mode));
    if (o->optimizer < 0 || o->optimizer > 3) return bad("unknown optimizer " + std::to_string(o->optimizer));
    hmc::EncodeOptions e;
    e.bits = o->bits;
    e.levels = o->levels;
    e.removal_ratio = o->removal_ratio;
    if (o->kind != HMC_KIND_AUTO) e.kind = static_cast<hmc::Kind>(o->kind);
    e.fidelity = static_cast<hmc::Fidelity>(o->fidelity);
    e.boundary_mode = static_cast<hmc::BoundaryMode>(o->boundary_mode);
    e.optimizer = static_cast<hmc::Optimizer>(o->optimizer);
    e.write_info = o->write_info != 0;
    e.fast_decode = o->fast_decode != 0;
    e.threads = encoder->options.threads;  // set apart (hmc_encoder_set_threads)
    e.preview_ratio = encoder->options.preview_ratio;  // and hmc_encoder_set_preview_ratio
    encoder->options = e;
    return HMC_OK;
  });
}

hmc_status hmc_encoder_encode(hmc_encoder* encoder, const double* xyz, size_t point_count, const uint32_t* triangles,
                              size_t triangle_count, const uint32_t* tetrahedra, size_t tetrahedron_count,
                              uint8_t** out_bytes, size_t* out_size) {
  if (out_bytes) *out_bytes = nullptr;
  if (out_size) *out_size = 0;
  if (!encoder) return HMC_INVALID_ARGUMENT;
  encoder->notes.clear();
  return guard(encoder->message, [&]() -> hmc_status {
    auto bad = [&](const char* m) {
      encoder->message = m;
      return HMC_INVALID_ARGUMENT;
    };
    if (!out_bytes || !out_size) return bad("out_bytes and out_size must not be NULL");
    if (!xyz && point_count) return bad("xyz is NULL");
    if (!triangles && triangle_count) return bad("triangles is NULL but triangle_count is not 0");
    if (!tetrahedra && tetrahedron_count) return bad("tetrahedra is NULL but tetrahedron_count is not 0");
    hmc::Mesh m;
    m.points.resize(point_count);
    for (std::size_t i = 0; i < point_count; ++i) m.points[i] = {xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]};
    m.triangles.resize(triangle_count);
    for (std::size_t i = 0; i < triangle_count; ++i)
      m.triangles[i] = {triangles[3 * i], triangles[3 * i + 1], triangles[3 * i + 2]};
    m.tetrahedra.resize(tetrahedron_count);
    for (std::size_t i = 0; i < tetrahedron_count; ++i)
      m.tetrahedra[i] = {tetrahedra[4 * i], tetrahedra[4 * i + 1], tetrahedra[4 * i + 2], tetrahedra[4 * i + 3]};
#ifdef HMC_NO_ENCODER
    // A decoder-only build (HMC_BUILD_ENCODER=OFF): the handle and its options
    // still work, so that the ABI is the same, but nothing can be encoded.
    encoder->message = "libhmc was built without the encoder (HMC_BUILD_ENCODER=OFF)";
    return HMC_UNSUPPORTED_FORMAT;
#else
    auto r = hmc::encode(m, encoder->options);
    if (!r) {
      encoder->message = r.error().message;
      return to_c(r.status());
    }
    const auto& bytes = r.value().bytes;
    const hmc_status s = hand_out(encoder->alloc, bytes.data(), bytes.size(), out_bytes, encoder->message);
    if (s == HMC_OK) {
      *out_size = bytes.size();
      for (const auto& n : r.value().report.notes) encoder->notes += n + "\n";
    }
    return s;
#endif
  });
}

const char* hmc_encoder_message(const hmc_encoder* encoder) { return encoder ? encoder->message.c_str() : ""; }
const char* hmc_encoder_notes(const hmc_encoder* encoder) { return encoder ? encoder->notes.c_str() : ""; }

// ---------------------------------------------------------------- decoder

hmc_decoder* hmc_decoder_create(const hmc_allocator* allocator) { return create_handle<hmc_decoder>(allocator); }

void hmc_decoder_destroy(hmc_decoder* decoder) { destroy_handle(decoder); }

hmc_status hmc_decoder_set_limits(hmc_decoder* decoder, uint64_t max_points, uint32_t max_levels, uint64_t max_bytes) {
  if (!decoder) return HMC_INVALID_ARGUMENT;
  return guard(decoder->message, [&]() -> hmc_status {
    if (decoder->begun()) return decoder->misuse("limits must be set before decoding begins");
    decoder->options.limits.max_points = max_points;
    decoder->options.limits.max_levels = max_levels;
    decoder->options.limits.max_bytes = max_bytes;
    return HMC_OK;
  });
}

hmc_status hmc_decoder_set_memory_limit(hmc_decoder* decoder, uint64_t max_memory) {
  if (!decoder) return HMC_INVALID_ARGUMENT;
  return guard(decoder->message, [&]() -> hmc_status {
    if (decoder->begun()) return decoder->misuse("limits must be set before decoding begins");
    decoder->options.limits.max_memory = max_memory;
    return HMC_OK;
  });
}

uint64_t hmc_decoder_memory_limit(const hmc_decoder* decoder) {
  return decoder ? decoder->options.limits.max_memory : 0;
}

hmc_status hmc_decoder_get_limits(const hmc_decoder* decoder, uint64_t* max_points, uint32_t* max_levels,
                                  uint64_t* max_bytes) {
  if (!decoder) return HMC_INVALID_ARGUMENT;
  if (max_points) *max_points = decoder->options.limits.max_points;
  if (max_levels) *max_levels = decoder->options.limits.max_levels;
  if (max_bytes) *max_bytes = decoder->options.limits.max_bytes;
  return HMC_OK;
}

hmc_status hmc_decoder_set_finest_level(hmc_decoder* decoder, int level) {
  if (!decoder) return HMC_INVALID_ARGUMENT;
  return guard(decoder->message, [&]() -> hmc_status {
    if (decoder->begun()) return decoder->misuse("the finest level must be set before decoding begins");
    if (level < 0 || level >= HMC_MAX_LEVELS)
      return decoder->misuse("the finest level must be between 0 and 63, got " + std::to_string(level));
    decoder->options.finest_level = level;
    return HMC_OK;
  });
}

hmc_status hmc_decoder_set_reconstruct(hmc_decoder* decoder, int reconstruct) {
  if (!decoder) return HMC_INVALID_ARGUMENT;
  return guard(decoder->message, [&]() -> hmc_status {
    if (decoder->begun()) return decoder->misuse("reconstruction must be chosen before decoding begins");
    decoder->options.reconstruct = reconstruct != 0;
    return HMC_OK;
  });
}

hmc_status hmc_decoder_set_threads(hmc_decoder* decoder, unsigned threads) {
  if (!decoder) return HMC_INVALID_ARGUMENT;
  return guard(decoder->message, [&]() -> hmc_status {
    if (decoder->begun()) return decoder->misuse("threads must be set before decoding begins");
    if (threads < 1 || threads > 64)
      return decoder->misuse("threads must be between 1 and 64, got " + std::to_string(threads));
    decoder->options.threads = threads;
    return HMC_OK;
  });
}

hmc_status hmc_decoder_set_rebuild_coarser_levels(hmc_decoder* decoder, int all) {
  if (!decoder) return HMC_INVALID_ARGUMENT;
  return guard(decoder->message, [&]() -> hmc_status {
    if (decoder->begun()) return decoder->misuse("which levels to rebuild must be chosen before decoding begins");
    decoder->options.rebuild_coarser_levels = all != 0;
    return HMC_OK;
  });
}

hmc_status hmc_decoder_set_error_order(hmc_decoder* decoder, int order) {
  if (!decoder) return HMC_INVALID_ARGUMENT;
  return guard(decoder->message, [&]() -> hmc_status {
    if (decoder->begun()) return decoder->misuse("the error order must be chosen before decoding begins");
    if (order != HMC_ERRORS_IN_STREAM_ORDER && order != HMC_ERRORS_AS_WHOLE)
      return decoder->misuse("unknown error order " + std::to_string(order));
    decoder->order = order == HMC_ERRORS_AS_WHOLE ? hmc::detail::StreamDecoder::ErrorOrder::whole
                                                  : hmc::detail::StreamDecoder::ErrorOrder::stream;
    return HMC_OK;
  });
}

hmc_status hmc_decoder_decode(hmc_decoder* decoder, const void* data, size_t size) {
  if (!decoder) return HMC_INVALID_ARGUMENT;
  const hmc_status s = guard(decoder->message, [&]() -> hmc_status {
    if (decoder->failed()) {
      decoder->message = decoder->failure;
      return decoder->state;
    }
    if (!data && size) return decoder->misuse("data is NULL");
    if (decoder->begun()) return decoder->misuse("the decoder has already decoded or been fed");
    auto r = hmc::decode(static_cast<const std::uint8_t*>(data), size, decoder->options);
    if (!r) return decoder->fail(to_c(r.status()), r.error().message);
    decoder->whole = std::move(r).value();
    decoder->whole_size = size;
    return decoder->finished_ok(*decoder->whole);
  });
  if (s == HMC_OUT_OF_MEMORY || s == HMC_INTERNAL_ERROR) decoder->fail(s, decoder->message);
  return s;
}

hmc_status hmc_decoder_feed(hmc_decoder* decoder, const void* data, size_t size) {
  if (!decoder) return HMC_INVALID_ARGUMENT;
  const hmc_status s = guard(decoder->message, [&]() -> hmc_status {
    if (decoder->failed()) {
      decoder->message = decoder->failure;
      return decoder->state;
    }
    if (!data && size) return decoder->misuse("data is NULL");
    if (decoder->finished || decoder->whole) return decoder->misuse("the stream was finished: nothing can be fed");
    if (!decoder->stream) decoder->stream.emplace(decoder->options, raw(decoder->alloc), decoder->order);
    const Status st = decoder->stream->feed(static_cast<const std::uint8_t*>(data), size);
    if (st != Status::ok) return decoder->fail(to_c(st), decoder->stream->error().message);
    return HMC_OK;
  });
  if (s == HMC_OUT_OF_MEMORY || s == HMC_INTERNAL_ERROR) decoder->fail(s, decoder->message);
  return s;
}

hmc_status hmc_decoder_finish(hmc_decoder* decoder) {
  if (!decoder) return HMC_INVALID_ARGUMENT;
  const hmc_status s = guard(decoder->message, [&]() -> hmc_status {
    if (decoder->failed()) {
      decoder->message = decoder->failure;
      return decoder->state;
    }
    if (decoder->finished) {
      if (decoder->state == HMC_INCOMPLETE) decoder->message = decoder->result()->warning;
      return decoder->state;
    }
    if (!decoder->stream) decoder->stream.emplace(decoder->options, raw(decoder->alloc), decoder->order);
    const Status st = decoder->stream->finish();
    if (st != Status::ok) return decoder->fail(to_c(st), decoder->stream->error().message);
    return decoder->finished_ok(decoder->stream->result());
  });
  if (s == HMC_OUT_OF_MEMORY || s == HMC_INTERNAL_ERROR) decoder->fail(s, decoder->message);
  return s;
}

hmc_status hmc_decoder_status(const hmc_decoder* decoder) { return decoder ? decoder->state : HMC_INVALID_ARGUMENT; }

const char* hmc_decoder_message(const hmc_decoder* decoder) { return decoder ? decoder->message.c_str() : ""; }

hmc_status hmc_decoder_stream_info(const hmc_decoder* decoder, hmc_stream_info* info) {
  if (!decoder || !info) return HMC_INVALID_ARGUMENT;
  std::memset(info, 0, sizeof *info);
  const Decoded* d = decoder->result();
  if (!d) return HMC_OK;
  info->header_ready = decoder->whole ? 1 : decoder->stream->header_ready() ? 1 : 0;
  info->version_major = d->version_major;
  info->version_minor = d->version_minor;
  if (info->header_ready) {
    info->kind = static_cast<int>(d->kind);
    info->bits = d->quantizer.bits;
    for (int a = 0; a < 3; ++a) info->origin[a] = d->quantizer.origin[a];
    info->step = d->quantizer.step;
    info->declared_levels = static_cast<std::uint32_t>(d->declared_points.size());
    for (std::size_t i = 0; i < d->declared_points.size() && i < HMC_MAX_LEVELS; ++i)
      info->declared_points[i] = d->declared_points[i];
  }
  info->bytes_consumed = decoder->whole ? decoder->whole_size : decoder->stream->bytes_fed();
  info->complete_levels = static_cast<std::uint32_t>(d->levels.size());
  info->ended = decoder->whole ? d->warning.empty() : decoder->stream->ended();
  info->truncated = d->truncated ? 1 : 0;
  return HMC_OK;
}

size_t hmc_decoder_level_count(const hmc_decoder* decoder) {
  const Decoded* d = decoder ? decoder->result() : nullptr;
  return d ? d->levels.size() : 0;
}

hmc_status hmc_decoder_level_info(const hmc_decoder* decoder, size_t index, hmc_level_info* info) {
  if (!decoder || !info) return HMC_INVALID_ARGUMENT;
  return guard(decoder->message, [&]() -> hmc_status {
    const hmc::DecodedLevel* l = decoder->level(index);
    if (!l) return HMC_INVALID_ARGUMENT;
    info->lod = l->lod;
    info->point_count = l->points.size();
    info->triangle_count = l->triangles.size();
    info->tetrahedron_count = l->tetrahedra.size();
    info->stream_bytes = l->stream_bytes;
    return HMC_OK;
  });
}

hmc_status hmc_decoder_level_points(const hmc_decoder* decoder, size_t index, uint32_t** out_xyz, size_t* out_count) {
  if (out_xyz) *out_xyz = nullptr;
  if (out_count) *out_count = 0;
  if (!decoder || !out_xyz || !out_count) return HMC_INVALID_ARGUMENT;
  return guard(decoder->message, [&]() -> hmc_status {
    const hmc::DecodedLevel* l = decoder->level(index);
    if (!l) return HMC_INVALID_ARGUMENT;
    const hmc_status s = hand_out(decoder->alloc, l->points.data(), 3 * l->points.size(), out_xyz, decoder->message);
    if (s == HMC_OK) *out_count = l->points.size();
    return s;
  });
}

hmc_status hmc_decoder_level_positions(const hmc_decoder* decoder, size_t index, double** out_xyz, size_t* out_count) {
  if (out_xyz) *out_xyz = nullptr;
  if (out_count) *out_count = 0;
  if (!decoder || !out_xyz || !out_count) return HMC_INVALID_ARGUMENT;
  return guard(decoder->message, [&]() -> hmc_status {
    const hmc::DecodedLevel* l = decoder->level(index);
    if (!l) return HMC_INVALID_ARGUMENT;
    const hmc::ScalarQuantizer& q = decoder->result()->quantizer;
    const hmc_status s = hand_out(decoder->alloc, nullptr, 3 * l->points.size(), out_xyz, decoder->message);
    if (s != HMC_OK) return s;
    for (std::size_t i = 0; i < l->points.size(); ++i) {
      const hmc::Vec3 v = q.dequantize(l->points[i]);
      for (int a = 0; a < 3; ++a) (*out_xyz)[3 * i + static_cast<std::size_t>(a)] = v[static_cast<std::size_t>(a)];
    }
    *out_count = l->points.size();
    return HMC_OK;
  });
}

extern "C++" {
namespace {
// A copy of one level's triangles or tetrahedra (E: 3 or 4 indices each).
template <class E>
hmc_status level_elements(const hmc_decoder* decoder, size_t index, uint32_t** out_indices, size_t* out_count,
                          const std::vector<E> hmc::DecodedLevel::*elements) {
  if (out_indices) *out_indices = nullptr;
  if (out_count) *out_count = 0;
  if (!decoder || !out_indices || !out_count) return HMC_INVALID_ARGUMENT;
  return guard(decoder->message, [&]() -> hmc_status {
    const hmc::DecodedLevel* l = decoder->level(index);
    if (!l) return HMC_INVALID_ARGUMENT;
    const std::vector<E>& e = l->*elements;
    const hmc_status s = hand_out(decoder->alloc, e.empty() ? nullptr : e.front().data(),
                                  std::tuple_size<E>::value * e.size(), out_indices, decoder->message);
    if (s == HMC_OK) *out_count = e.size();
    return s;
  });
}
}  // namespace
}  // extern "C++"

hmc_status hmc_decoder_level_triangles(const hmc_decoder* decoder, size_t index, uint32_t** out_indices,
                                       size_t* out_count) {
  return level_elements(decoder, index, out_indices, out_count, &hmc::DecodedLevel::triangles);
}

hmc_status hmc_decoder_level_tetrahedra(const hmc_decoder* decoder, size_t index, uint32_t** out_indices,
                                        size_t* out_count) {
  return level_elements(decoder, index, out_indices, out_count, &hmc::DecodedLevel::tetrahedra);
}

}  // extern "C"
