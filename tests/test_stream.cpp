// SPDX-License-Identifier: AGPL-3.0-or-later
// The streaming decoder: fed in pieces of any size (down to one byte), it
// outputs what decode() outputs for the same bytes — levels, points,
// simplices, warnings, truncation and error classes — and reports each
// level as soon as its last byte is in.
#include <doctest/doctest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <vector>

#include "codec/format.hpp"
#include "codec/stream_decoder.hpp"
#include "container/container.hpp"
#include "hmc/codec.hpp"
#include "hmc/hmc.hpp"
#include "samples.hpp"
#include "support/why.hpp"

using namespace hmc;
using hmc::detail::StreamDecoder;

namespace {

using Bytes = std::vector<std::uint8_t>;

struct Sample {
  std::string name;
  Bytes bytes;
};

Bytes encode_sample(const Mesh& m, int levels, std::optional<Kind> kind = std::nullopt, int bits = 12) {
  EncodeOptions o;
  o.levels = levels;
  o.kind = kind;
  o.bits = bits;
  o.boundary_mode = BoundaryMode::linear;
  auto e = encode(m, o);
  REQUIRE_MESSAGE(e.ok(), hmc::testgen::why(e));
  return std::move(e).value().bytes;
}

// Multi-level streams of each kind, built once.
const std::vector<Sample>& samples_of_each_kind() {
  static const std::vector<Sample> s = [] {
    std::vector<Sample> v;
    v.push_back({"points", encode_sample(samples::random_ball(600, 11), 3, Kind::points)});
    v.push_back({"surface", encode_sample(samples::torus(40, 16), 4)});
    v.push_back({"volume", encode_sample(samples::random_ball(400, 7), 3, Kind::volume)});
    v.push_back({"single-level surface", encode_sample(samples::uv_sphere(8, 16), 1, std::nullopt, 10)});
    // Open: its finer levels inherit the coarser level's border (RCON flag bit 3).
    v.push_back({"open surface", encode_sample(samples::height_field(16, 0.15), 3, std::nullopt, 10)});
    return v;
  }();
  return s;
}

// Outcome of a decode: the result or the error, comparable field by field.
struct Outcome {
  Status status = Status::ok;
  std::string message;  // error message
  Decoded decoded;
};

Outcome whole(const std::uint8_t* data, std::size_t size, const DecodeOptions& o = {}) {
  auto r = decode(data, size, o);
  if (!r) return {r.status(), r.error().message, {}};
  return {Status::ok, {}, std::move(r).value()};
}

// Feeds `size` bytes in pieces drawn by `next_piece`, checking after each
// piece that every level whose last byte is in has been reported.
using Order = StreamDecoder::ErrorOrder;

template <class Next>
Outcome streamed(const std::uint8_t* data, std::size_t size, Next next_piece, const DecodeOptions& o = {},
                 const Decoded* reference = nullptr, Order order = Order::stream) {
  StreamDecoder sd(o, detail::RawAllocator::system(), order);
  std::size_t pos = 0;
  while (pos < size) {
    const std::size_t n = std::min(size - pos, next_piece());
    const Status s = sd.feed(data + pos, n);
    pos += n;
    if (s != Status::ok) return {s, sd.error().message, {}};
    CHECK(sd.bytes_fed() == pos);
    if (reference) {
      // Exactly the levels whose prefix is in are complete (or all the requested ones).
      std::size_t expect = 0;
      for (const auto& l : reference->levels) expect += l.stream_bytes <= pos;
      CHECK(sd.result().levels.size() == expect);
    }
  }
  const Status s = sd.finish();
  if (s != Status::ok) return {s, sd.error().message, {}};
  CHECK(sd.finished());
  return {Status::ok, {}, sd.result()};
}

// `messages`: also compare error messages (they differ where the streaming
// decoder cannot know what follows: the count of bytes after HEND, the size
// of a stream over the byte limit).
void check_same(const Outcome& a, const Outcome& b, bool messages = true) {
  REQUIRE(status_name(a.status) == std::string(status_name(b.status)));
  if (messages) CHECK(a.message == b.message);
  if (a.status != Status::ok) return;
  const Decoded& x = a.decoded;
  const Decoded& y = b.decoded;
  CHECK(x.kind == y.kind);
  CHECK(x.quantizer.bits == y.quantizer.bits);
  CHECK(x.quantizer.origin == y.quantizer.origin);
  CHECK(x.quantizer.step == y.quantizer.step);
  CHECK(x.version_major == y.version_major);
  CHECK(x.version_minor == y.version_minor);
  CHECK(x.declared_points == y.declared_points);
  CHECK(x.info == y.info);
  CHECK(x.truncated == y.truncated);
  CHECK(x.warning == y.warning);
  REQUIRE(x.levels.size() == y.levels.size());
  for (std::size_t i = 0; i < x.levels.size(); ++i) {
    CAPTURE(i);
    CHECK(x.levels[i].lod == y.levels[i].lod);
    CHECK(x.levels[i].stream_bytes == y.levels[i].stream_bytes);
    CHECK(x.levels[i].points == y.levels[i].points);
    CHECK(x.levels[i].triangles == y.levels[i].triangles);
    CHECK(x.levels[i].tetrahedra == y.levels[i].tetrahedra);
    CHECK(x.levels[i].rebuilt == y.levels[i].rebuilt);
  }
}

// Piece sizes: 1 byte, fixed sizes, and random sizes spanning 1 byte to
// several chunks.
struct Pieces {
  std::mt19937_64 rng;
  std::size_t max;
  std::size_t operator()() {
    // Log-uniform: small pieces often, large ones sometimes.
    std::uniform_real_distribution<double> u(0.0, std::log(static_cast<double>(max)));
    return std::max<std::size_t>(1, static_cast<std::size_t>(std::exp(u(rng))));
  }
};

void check_stream_equivalence(const Bytes& b, const DecodeOptions& o = {}) {
  const Outcome ref = whole(b.data(), b.size(), o);
  const Decoded* levels = ref.status == Status::ok ? &ref.decoded : nullptr;
  {
    INFO("1-byte pieces");
    check_same(streamed(b.data(), b.size(), [] { return std::size_t{1}; }, o, levels), ref);
  }
  {
    INFO("the whole stream in one piece");
    check_same(streamed(b.data(), b.size(), [&] { return b.size(); }, o, levels), ref);
  }
  for (std::size_t fixed : {2, 3, 7, 64, 1000}) {
    INFO("pieces of " << fixed);
    check_same(streamed(b.data(), b.size(), [&] { return fixed; }, o, levels), ref);
  }
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    INFO("random pieces, seed " << seed);
    check_same(streamed(b.data(), b.size(), Pieces{std::mt19937_64(seed), b.size()}, o, levels), ref);
  }
}

// The payload length of the chunk whose type field is at `at`.
std::uint32_t chunk_length(const Bytes& b, std::size_t at) {
  return std::uint32_t{b[at + 4]} | std::uint32_t{b[at + 5]} << 8 | std::uint32_t{b[at + 6]} << 16 |
         std::uint32_t{b[at + 7]} << 24;
}

// Rewrites the CRC of the chunk at `at` to match its type and payload.
void fix_crc(Bytes& b, std::size_t at) {
  const std::uint32_t len = chunk_length(b, at);
  const detail::ChunkType type{static_cast<char>(b[at]), static_cast<char>(b[at + 1]), static_cast<char>(b[at + 2]),
                               static_cast<char>(b[at + 3])};
  const std::uint32_t crc = detail::chunk_crc(type, b.data() + at + 8, len);
  for (int k = 0; k < 4; ++k) b[at + 8 + len + k] = static_cast<std::uint8_t>(crc >> (8 * k));
}

std::vector<std::size_t> chunk_boundaries(const Bytes& b) {
  std::vector<std::size_t> v;
  std::size_t pos = 10;
  while (pos + 8 <= b.size()) {
    v.push_back(pos);
    pos += 12 + std::size_t{chunk_length(b, pos)};
  }
  v.push_back(b.size());
  return v;
}

Bytes read_file(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return Bytes(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

}  // namespace

TEST_CASE("streaming equals whole-stream decoding, for every kind and piece size") {
  for (const auto& s : samples_of_each_kind()) {
    CAPTURE(s.name);
    const Outcome ref = whole(s.bytes.data(), s.bytes.size());
    REQUIRE(ref.status == Status::ok);
    CHECK(ref.decoded.warning.empty());
    if (s.name != "single-level surface") CHECK(ref.decoded.levels.size() >= 3);
    if (s.name == "volume") CHECK_FALSE(ref.decoded.finest().tetrahedra.empty());
    if (s.name == "surface") CHECK_FALSE(ref.decoded.finest().triangles.empty());
    check_stream_equivalence(s.bytes);
  }
}

TEST_CASE("streaming with options: a coarser requested level, points only") {
  for (const auto& s : samples_of_each_kind()) {
    CAPTURE(s.name);
    DecodeOptions o;
    o.finest_level = 1;
    check_stream_equivalence(s.bytes, o);
    DecodeOptions p;
    p.reconstruct = false;
    Pieces pieces{std::mt19937_64(9), 300};
    check_same(streamed(s.bytes.data(), s.bytes.size(), pieces, p), whole(s.bytes.data(), s.bytes.size(), p));
    // Only the finest decoded level rebuilt: also on cut streams, where
    // that level is known only when the data ends (finish()).
    DecodeOptions f;
    f.rebuild_coarser_levels = false;
    check_stream_equivalence(s.bytes, f);
    for (std::size_t n : chunk_boundaries(s.bytes)) {
      CAPTURE(n);
      Pieces cut{std::mt19937_64(n), 200};
      check_same(streamed(s.bytes.data(), n, cut, f), whole(s.bytes.data(), n, f));
    }
  }
}

TEST_CASE("a level is reported the moment its last byte is in, not before") {
  const Bytes& b = samples_of_each_kind()[1].bytes;  // surface, 4 levels
  const Outcome ref = whole(b.data(), b.size());
  REQUIRE(ref.decoded.levels.size() == 4);
  StreamDecoder sd;
  std::size_t reported = 0;
  for (std::size_t i = 0; i < b.size(); ++i) {
    REQUIRE(sd.feed(&b[i], 1) == Status::ok);
    const std::size_t n = sd.result().levels.size();
    if (n != reported) {
      REQUIRE(n == reported + 1);  // one level per byte at most: one RCON chunk completes it
      CHECK(i + 1 == ref.decoded.levels[reported].stream_bytes);
      CHECK(sd.result().levels.back().points == ref.decoded.levels[reported].points);
      CHECK(sd.result().levels.back().triangles == ref.decoded.levels[reported].triangles);
      reported = n;
    }
  }
  CHECK(reported == 4);
  CHECK(sd.ended());
  CHECK(sd.finish() == Status::ok);
}

TEST_CASE("cut streams: the same levels, warning, truncation and errors as decode()") {
  for (const auto& s : samples_of_each_kind()) {
    CAPTURE(s.name);
    const Bytes& b = s.bytes;
    // Every chunk boundary, one byte either side, and cuts inside the preamble.
    std::vector<std::size_t> cuts = {0, 1, 5, 8, 9, 10, 11, 17};
    for (std::size_t at : chunk_boundaries(b)) {
      cuts.push_back(at);
      cuts.push_back(at - 1);
      if (at + 1 < b.size()) cuts.push_back(at + 1);
    }
    std::mt19937_64 rng(3);
    for (int i = 0; i < 20; ++i) cuts.push_back(std::uniform_int_distribution<std::size_t>(0, b.size())(rng));
    for (std::size_t n : cuts) {
      CAPTURE(n);
      const Outcome ref = whole(b.data(), n);
      Pieces pieces{std::mt19937_64(n), 200};
      check_same(streamed(b.data(), n, pieces), ref);
      check_same(streamed(b.data(), n, [] { return std::size_t{1}; }), ref);
    }
  }
}

TEST_CASE("damaged streams: the same error class as decode(), and a permanent failed state") {
  const Bytes& good = samples_of_each_kind()[0].bytes;  // points, 3 levels
  std::mt19937_64 rng(5);
  std::vector<std::size_t> at = {0, 3, 8, 9, 10, 12, 14, 22};
  for (std::size_t c : chunk_boundaries(good))
    if (c + 8 < good.size()) at.insert(at.end(), {c, c + 4, c + 7, c + 8});
  for (int i = 0; i < 60; ++i) at.push_back(std::uniform_int_distribution<std::size_t>(0, good.size() - 1)(rng));
  for (std::size_t i : at) {
    for (int mask : {0x01, 0x80, 0xff}) {
      Bytes b = good;
      b[i] = static_cast<std::uint8_t>(b[i] ^ mask);
      CAPTURE(i);
      CAPTURE(mask);
      const Outcome ref = whole(b.data(), b.size());
      const Outcome got = streamed(b.data(), b.size(), Pieces{std::mt19937_64(i), 100});
      CHECK(status_name(got.status) == std::string(status_name(ref.status)));
      if (ref.status == Status::ok) check_same(got, ref);
      // Reporting as decode() does: the same status and message, always.
      check_same(streamed(b.data(), b.size(), Pieces{std::mt19937_64(i + 1), 100}, {}, nullptr, Order::whole), ref);
    }
  }
  // Bytes after the end chunk.
  Bytes extra = good;
  extra.push_back(0);
  CHECK(whole(extra.data(), extra.size()).status == Status::bad_chunk);
  StreamDecoder sd;
  CHECK(sd.feed(extra.data(), good.size()) == Status::ok);
  CHECK(sd.ended());
  CHECK(sd.feed(extra.data() + good.size(), 1) == Status::bad_chunk);
  // Failed for good, with the levels completed before the error still there.
  CHECK(sd.failed());
  CHECK(sd.feed(good.data(), 1) == Status::bad_chunk);
  CHECK(sd.finish() == Status::bad_chunk);
  CHECK(sd.result().levels.size() == 3);
  // Reporting as decode() does, with every byte after the end counted.
  extra.insert(extra.end(), 4, 7);
  const Outcome ref = whole(extra.data(), extra.size());
  check_same(streamed(extra.data(), extra.size(), [] { return std::size_t{1}; }, {}, nullptr, Order::whole), ref);
  check_same(streamed(extra.data(), extra.size(), [] { return std::size_t{3}; }, {}, nullptr, Order::whole), ref);
}

TEST_CASE("several defects: at once in stream order, or exactly what decode() reports") {
  // A content defect (an unknown BASE coder, CRC made valid) followed by a
  // framing defect (a damaged CRC further on).
  const Bytes& good = samples_of_each_kind()[1].bytes;  // surface, 4 levels
  const auto chunks = chunk_boundaries(good);
  std::size_t base = 0, last = 0;
  for (std::size_t c : chunks)
    if (c + 8 <= good.size()) {
      if (std::string(reinterpret_cast<const char*>(good.data() + c), 4) == "BASE") base = c;
      last = c;
    }
  REQUIRE(base > 0);
  REQUIRE(last > base);
  Bytes b = good;
  b[base + 8] = 9;  // coder 9
  fix_crc(b, base);
  const std::uint32_t len = chunk_length(b, base);
  Bytes only_content = b;
  b[last - 1] = static_cast<std::uint8_t>(b[last - 1] ^ 0x5a);  // the CRC of the chunk before the last
  REQUIRE(whole(only_content.data(), only_content.size()).status == Status::bad_layer);
  const Outcome ref = whole(b.data(), b.size());
  REQUIRE(ref.status == Status::crc_mismatch);
  auto one = [] { return std::size_t{1}; };
  // In stream order: the content defect, at once (as soon as BASE is in).
  StreamDecoder sd;
  CHECK(sd.feed(b.data(), base + 12 + len) == Status::bad_layer);
  CHECK(streamed(b.data(), b.size(), one).status == Status::bad_layer);
  // As a whole: what decode() says, at the end.
  StreamDecoder w({}, detail::RawAllocator::system(), Order::whole);
  CHECK(w.feed(b.data(), base + 12 + len) == Status::ok);
  CHECK(w.feed(b.data() + base + 12 + len, b.size() - base - 12 - len) == Status::ok);
  CHECK(w.result().levels.empty());
  CHECK(w.finish() == Status::crc_mismatch);
  check_same(streamed(b.data(), b.size(), one, {}, nullptr, Order::whole), ref);
  check_same(streamed(only_content.data(), only_content.size(), one, {}, nullptr, Order::whole),
             whole(only_content.data(), only_content.size()));
  // The size limit outranks everything, and is reported at once.
  DecodeOptions small;
  small.limits.max_bytes = b.size() - 1;
  CHECK(whole(b.data(), b.size(), small).status == Status::limit_exceeded);
  CHECK(streamed(b.data(), b.size(), one, small, nullptr, Order::whole).status == Status::limit_exceeded);
  Bytes bad_magic = good;
  bad_magic[0] = 'x';
  CHECK(streamed(bad_magic.data(), bad_magic.size(), one, small, nullptr, Order::whole).status ==
        Status::limit_exceeded);
  CHECK(streamed(bad_magic.data(), bad_magic.size(), one, small).status == Status::bad_magic);
}

TEST_CASE("decode() on two threads: the base layer's neighbour searches run ahead, the same points and errors") {
  // Depths of the ranked base layer with at least 2,048 nodes have their
  // nearest-node searches made by a helper thread ahead of the decoding
  // (pointset/octree.cpp, SearchAhead). A 1-level torus of about 6,000
  // points has several such depths; damaged base layers (valid CRCs) make
  // the decoding stop, or decode other points, partway through a depth
  // whose searches are running ahead.
  const Bytes good = encode_sample(samples::torus(120, 50), 1);
  std::size_t base = 0;
  for (std::size_t c : chunk_boundaries(good))
    if (std::string(reinterpret_cast<const char*>(good.data() + c), 4) == "BASE") base = c;
  REQUIRE(base > 0);
  REQUIRE(good[base + 8] >= 1);  // a ranked coder
  DecodeOptions one, two;
  two.threads = 2;
  one.reconstruct = two.reconstruct = false;
  const Outcome ref = whole(good.data(), good.size(), one);
  REQUIRE(ref.status == Status::ok);
  REQUIRE(ref.decoded.finest().points.size() == 6000);
  check_same(whole(good.data(), good.size(), two), ref);
  const std::uint32_t len = chunk_length(good, base);
  std::mt19937_64 rng(5);
  std::size_t errors = 0;
  for (int trial = 0; trial < 24; ++trial) {
    CAPTURE(trial);
    Bytes b = good;
    // In the second half of the payload: the deepest depths, the largest.
    const std::size_t pos = base + 8 + len / 2 + std::uniform_int_distribution<std::size_t>(0, len / 2 - 1)(rng);
    b[pos] = static_cast<std::uint8_t>(b[pos] ^ (1u << std::uniform_int_distribution<int>(0, 7)(rng)));
    fix_crc(b, base);
    const Outcome a = whole(b.data(), b.size(), one);
    errors += a.status != Status::ok;
    check_same(whole(b.data(), b.size(), two), a);
  }
  CHECK(errors >= 8);
}

TEST_CASE("decode() on two threads: the same levels, simplices and errors as on one") {
  // Damaged content with valid CRCs (so that the chunks reach the decoder):
  // byte flips in one layer or side-information chunk, alone and together
  // with one in a later chunk, so that a reconstruction running on the
  // second thread and the main thread's next chunk can both fail; the error
  // reported must be the one the single-threaded decoder meets first.
  auto is_level_chunk = [](const Bytes& b, std::size_t at) {
    const std::string type(reinterpret_cast<const char*>(b.data() + at), 4);
    return type == "BASE" || type == "REFN" || type == "RCON";
  };
  DecodeOptions one, two;
  two.threads = 2;
  std::size_t errors = 0, rebuilt = 0;
  for (const auto& s : samples_of_each_kind()) {
    CAPTURE(s.name);
    const Bytes& good = s.bytes;
    const Outcome ref = whole(good.data(), good.size(), one);
    REQUIRE(ref.status == Status::ok);
    check_same(whole(good.data(), good.size(), two), ref);
    for (const auto& l : ref.decoded.levels) rebuilt += l.rebuilt && (!l.triangles.empty() || !l.tetrahedra.empty());
    // Cut at every chunk boundary: the levels complete by then. Also with
    // only the finest decoded level rebuilt (the second thread builds the
    // coarser levels' tetrahedralizations ahead, the finest one's is refined
    // from them, and its reconstruction runs on the second thread), and with
    // a coarser level requested.
    for (std::size_t n : chunk_boundaries(good)) {
      CAPTURE(n);
      check_same(whole(good.data(), n, two), whole(good.data(), n, one));
      DecodeOptions one_finest = one, two_finest = two;
      one_finest.rebuild_coarser_levels = two_finest.rebuild_coarser_levels = false;
      const Outcome f = whole(good.data(), n, one_finest);
      check_same(whole(good.data(), n, two_finest), f);
      if (n == good.size()) {
        REQUIRE(f.status == Status::ok);
        REQUIRE_FALSE(f.decoded.levels.empty());
        CHECK(f.decoded.levels.back().triangles == ref.decoded.levels.back().triangles);
        CHECK(f.decoded.levels.back().tetrahedra == ref.decoded.levels.back().tetrahedra);
        one_finest.finest_level = two_finest.finest_level = 1;
        check_same(whole(good.data(), n, two_finest), whole(good.data(), n, one_finest));
      }
    }
    std::vector<std::size_t> chunks;
    for (std::size_t c : chunk_boundaries(good))
      if (c + 12 <= good.size() && is_level_chunk(good, c)) chunks.push_back(c);
    std::mt19937_64 rng(17);
    for (std::size_t i = 0; i < chunks.size(); ++i) {
      for (int trial = 0; trial < 6; ++trial) {
        Bytes b = good;
        auto damage = [&](std::size_t at) {
          const std::uint32_t len = chunk_length(b, at);
          if (len == 0) return;
          const std::size_t pos = at + 8 + std::uniform_int_distribution<std::size_t>(0, len - 1)(rng);
          b[pos] = static_cast<std::uint8_t>(b[pos] ^ (1u << std::uniform_int_distribution<int>(0, 7)(rng)));
          fix_crc(b, at);
        };
        damage(chunks[i]);
        if (trial % 2 == 1 && i + 1 < chunks.size()) damage(chunks[i + 1 + rng() % (chunks.size() - i - 1)]);
        CAPTURE(chunks[i]);
        CAPTURE(trial);
        const Outcome a = whole(b.data(), b.size(), one);
        errors += a.status != Status::ok;
        check_same(whole(b.data(), b.size(), two), a);
        // Only the finest level rebuilt: the second thread tetrahedralizes
        // the coarser levels ahead, speculatively.
        DecodeOptions one_finest = one, two_finest = two;
        one_finest.rebuild_coarser_levels = two_finest.rebuild_coarser_levels = false;
        check_same(whole(b.data(), b.size(), two_finest), whole(b.data(), b.size(), one_finest));
      }
    }
  }
  // The comparisons above covered rebuilt levels and failures.
  CHECK(rebuilt >= 8);
  CHECK(errors >= 10);

  // An error only the reconstruction can find (spec 10: a toggled
  // tetrahedron that does not exist) in the coarsest level, then one in the
  // next layer (an unknown coder) that the main thread meets while that
  // reconstruction may still run: the first is reported, as on one thread.
  const Bytes& good = samples_of_each_kind()[1].bytes;  // surface, 4 levels
  const Outcome ref = whole(good.data(), good.size(), one);
  REQUIRE(ref.status == Status::ok);
  std::vector<std::size_t> rcon, refn;
  for (std::size_t c : chunk_boundaries(good)) {
    if (c + 12 > good.size()) continue;
    const std::string type(reinterpret_cast<const char*>(good.data() + c), 4);
    if (type == "RCON") rcon.push_back(c);
    if (type == "REFN") refn.push_back(c);
  }
  REQUIRE(rcon.size() == 4);
  REQUIRE(refn.size() == 3);
  const std::size_t r = rcon[0];
  const std::uint32_t len = chunk_length(good, r);
  detail::ChunkView view{detail::chunk_type("RCON"), r, len, good.data() + r + 8};
  detail::ReconParams p = detail::read_recon(view, ref.decoded.levels[0].points.size());
  p.compact = false;
  p.candidate_contexts = p.vertex_contexts = false;
  p.toggle_ranks = {};
  p.toggles = {1u << 30};
  const auto payload = detail::write_recon(p);
  Bytes bad(good.begin(), good.begin() + static_cast<std::ptrdiff_t>(r));
  const auto n = static_cast<std::uint32_t>(payload.size());
  for (std::uint8_t x : {std::uint8_t{'R'}, std::uint8_t{'C'}, std::uint8_t{'O'}, std::uint8_t{'N'},
                         static_cast<std::uint8_t>(n), static_cast<std::uint8_t>(n >> 8),
                         static_cast<std::uint8_t>(n >> 16), static_cast<std::uint8_t>(n >> 24)})
    bad.push_back(x);
  bad.insert(bad.end(), payload.begin(), payload.end());
  bad.insert(bad.end(), 4, 0);
  fix_crc(bad, r);
  const std::size_t next = bad.size();  // the first REFN follows
  bad.insert(bad.end(), good.begin() + static_cast<std::ptrdiff_t>(r + 12 + len), good.end());
  REQUIRE(std::string(reinterpret_cast<const char*>(bad.data() + next), 4) == "REFN");
  const Outcome toggle = whole(bad.data(), bad.size(), one);
  REQUIRE(toggle.status == Status::bad_layer);
  CHECK(toggle.message.find("toggled tetrahedron") != std::string::npos);
  check_same(whole(bad.data(), bad.size(), two), toggle);
  Bytes both = bad;
  both[next + 8] = 99;  // REFN coder
  fix_crc(both, next);
  check_same(whole(both.data(), both.size(), one), toggle);
  check_same(whole(both.data(), both.size(), two), toggle);
  // The later error alone, for contrast.
  Bytes later = good;
  later[refn[0] + 8] = 99;
  fix_crc(later, refn[0]);
  const Outcome coder = whole(later.data(), later.size(), one);
  CHECK(coder.message.find("unknown coder") != std::string::npos);
  check_same(whole(later.data(), later.size(), two), coder);
}

TEST_CASE("limits apply to streams fed in pieces") {
  const Bytes& b = samples_of_each_kind()[1].bytes;
  DecodeOptions o;
  o.limits.max_bytes = b.size() - 1;
  CHECK(whole(b.data(), b.size(), o).status == Status::limit_exceeded);
  CHECK(streamed(b.data(), b.size(), [] { return std::size_t{1}; }, o).status == Status::limit_exceeded);
  o.limits.max_bytes = b.size();
  check_stream_equivalence(b, o);
  DecodeOptions p;
  p.limits.max_points = 10;
  check_same(streamed(b.data(), b.size(), [] { return std::size_t{3}; }, p), whole(b.data(), b.size(), p));
  DecodeOptions l;
  l.limits.max_levels = 2;
  check_same(streamed(b.data(), b.size(), [] { return std::size_t{5}; }, l), whole(b.data(), b.size(), l));
}

TEST_CASE("the C API's streaming decoder (through hmc.hpp) matches whole-buffer decoding") {
  for (const auto& s : samples_of_each_kind()) {
    CAPTURE(s.name);
    const Bytes& b = s.bytes;
    const Outcome ref = whole(b.data(), b.size());
    REQUIRE(ref.status == Status::ok);
    auto dec = capi::Decoder::create();
    REQUIRE(dec.ok());
    capi::Decoder& d = dec.value();
    Pieces pieces{std::mt19937_64(17), 500};
    std::size_t pos = 0, seen = 0;
    while (pos < b.size()) {
      const std::size_t n = std::min(b.size() - pos, pieces());
      auto r = d.feed(b.data() + pos, n);
      REQUIRE_MESSAGE(r.ok(), hmc::testgen::why(r));
      pos += n;
      for (; seen < r.value(); ++seen) {
        const DecodedLevel& want = ref.decoded.levels[seen];
        CHECK(want.stream_bytes <= pos);
        auto info = d.level_info(seen);
        REQUIRE(info.ok());
        CHECK(info.value().lod == want.lod);
        CHECK(info.value().point_count == want.points.size());
        auto pts = d.points(seen);
        REQUIRE(pts.ok());
        REQUIRE(pts.value().size() == 3 * want.points.size());
        for (std::size_t i = 0; i < want.points.size(); ++i)
          for (std::size_t a = 0; a < 3; ++a) REQUIRE(pts.value()[3 * i + a] == want.points[i][a]);
        auto pos3 = d.positions(seen);
        REQUIRE(pos3.ok());
        for (std::size_t i = 0; i < want.points.size(); ++i) {
          const Vec3 v = ref.decoded.quantizer.dequantize(want.points[i]);
          for (std::size_t a = 0; a < 3; ++a) REQUIRE(pos3.value()[3 * i + a] == v[a]);
        }
        auto tri = d.triangles(seen);
        auto tet = d.tetrahedra(seen);
        REQUIRE(tri.ok());
        REQUIRE(tet.ok());
        REQUIRE(tri.value().size() == 3 * want.triangles.size());
        REQUIRE(tet.value().size() == 4 * want.tetrahedra.size());
        for (std::size_t i = 0; i < want.triangles.size(); ++i)
          for (std::size_t a = 0; a < 3; ++a) REQUIRE(tri.value()[3 * i + a] == want.triangles[i][a]);
        for (std::size_t i = 0; i < want.tetrahedra.size(); ++i)
          for (std::size_t a = 0; a < 4; ++a) REQUIRE(tet.value()[4 * i + a] == want.tetrahedra[i][a]);
      }
    }
    auto end = d.finish();
    REQUIRE(end.ok());
    CHECK(end.value() == HMC_OK);
    CHECK(seen == ref.decoded.levels.size());
    const hmc_stream_info info = d.stream_info();
    CHECK(info.header_ready);
    CHECK(info.ended);
    CHECK(info.kind == static_cast<int>(ref.decoded.kind));
    CHECK(info.declared_levels == ref.decoded.declared_points.size());
    CHECK(info.bytes_consumed == b.size());
  }
  // A cut stream ends as incomplete, with its complete levels.
  const Bytes& b = samples_of_each_kind()[1].bytes;
  const Outcome ref = whole(b.data(), b.size() - 20);
  REQUIRE(ref.status == Status::ok);
  auto d = capi::Decoder::create();
  REQUIRE(d.ok());
  REQUIRE(d.value().feed(b.data(), b.size() - 20).ok());
  auto end = d.value().finish();
  REQUIRE(end.ok());
  CHECK(end.value() == HMC_INCOMPLETE);
  CHECK(d.value().message() == ref.decoded.warning);
  CHECK(d.value().level_count() == ref.decoded.levels.size());
  CHECK(d.value().stream_info().truncated == 1);
}

TEST_CASE("conformance vectors, if present, decode the same streamed as whole") {
  // HMC_CONFORMANCE_VECTORS names another vectors folder (e.g. freshly generated ones).
  const char* env = std::getenv("HMC_CONFORMANCE_VECTORS");
  const std::filesystem::path dir =
      env && *env ? std::filesystem::path(env) : std::filesystem::path(HMC_SOURCE_DIR) / "conformance" / "vectors";
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec)) {
    MESSAGE("no conformance/vectors folder: skipped");
    return;
  }
  std::vector<std::filesystem::path> streams;
  for (const auto& e : std::filesystem::directory_iterator(dir, ec)) {
    const auto p = e.path() / "stream.hmc";
    if (std::filesystem::is_regular_file(p, ec)) streams.push_back(p);
  }
  std::sort(streams.begin(), streams.end());
  MESSAGE(streams.size() << " conformance streams");
  std::string stream_order_differences;
  for (const auto& p : streams) {
    CAPTURE(p.parent_path().filename().string());
    const Bytes b = read_file(p);
    const Outcome ref = whole(b.data(), b.size());
    const Decoded* levels = ref.status == Status::ok ? &ref.decoded : nullptr;
    // As a whole: exactly decode()'s outcome, messages included.
    check_same(streamed(b.data(), b.size(), [] { return std::size_t{1}; }, {}, levels, Order::whole), ref);
    check_same(streamed(b.data(), b.size(), Pieces{std::mt19937_64(b.size()), 4096}, {}, levels, Order::whole), ref);
    // In stream order: the same, except on vectors with several defects
    // where decode() ranks a framing error first.
    const Outcome s1 = streamed(b.data(), b.size(), [] { return std::size_t{1}; }, {}, levels);
    if (s1.status != ref.status) {
      stream_order_differences += " " + p.parent_path().filename().string() + " (" + status_name(s1.status) +
                                  " for " + status_name(ref.status) + ")";
      CHECK((ref.status == Status::crc_mismatch || ref.status == Status::bad_chunk));
      CHECK(s1.status != Status::ok);
    } else {
      check_same(s1, ref, false);
    }
  }
  if (!stream_order_differences.empty())
    MESSAGE("reported otherwise in stream order (several defects):" << stream_order_differences);
}
