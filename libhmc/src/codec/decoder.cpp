// SPDX-License-Identifier: AGPL-3.0-or-later
#include <algorithm>
#include <chrono>
#include <deque>
#include <exception>
#include <future>
#include <memory>
#include <optional>
#include <string>

#include "codec/format.hpp"
#include "codec/stream_decoder.hpp"
#include "delaunay/delaunay.hpp"
#include "reconstruct/reconstruct.hpp"
#include "pointset/octree.hpp"
#include "pointset/refine.hpp"
#include "util/error.hpp"
#include "util/helpers.hpp"

namespace hmc {

namespace {

using namespace detail;

std::vector<std::pair<std::string, std::string>> parse_info(const ChunkView& c) {
  // Informative only: lines that are not key=value are ignored.
  std::vector<std::pair<std::string, std::string>> kv;
  std::string text(reinterpret_cast<const char*>(c.payload), c.length);
  std::size_t pos = 0;
  while (pos < text.size()) {
    std::size_t nl = text.find('\n', pos);
    if (nl == std::string::npos) nl = text.size();
    const std::string line = text.substr(pos, nl - pos);
    const std::size_t eq = line.find('=');
    if (eq != std::string::npos && eq > 0) kv.emplace_back(line.substr(0, eq), line.substr(eq + 1));
    pos = nl + 1;
  }
  return kv;
}

/// Walks the chunk sequence, enforcing the order rules of spec "Chunk order",
/// and calls back for the pieces a caller wants.
struct ChunkWalker {
  explicit ChunkWalker(const DecodeLimits& l) : limits(l) {}
  const DecodeLimits& limits;
  std::optional<Header> header;
  std::optional<ScalarQuantizer> quantizer;
  std::size_t layers = 0;  // layer chunks seen (BASE, then refinements)
  bool end_seen = false;

  std::size_t recons = 0;  // RCON chunks seen
  bool needs_recon() const { return header->kind != Kind::points; }
  /// Levels complete so far: a layer, plus its RCON for surface and volume kinds.
  std::size_t complete() const { return needs_recon() ? recons : layers; }

  enum class Action { skip, header, quantizer, layer, recon, end, info };

  Action classify(const ChunkView& c) {
    const std::string name = to_string(c.type) + " chunk at offset " + std::to_string(c.offset);
    if (!header && c.type != kHead) fail(Status::bad_chunk, name + ": the first chunk must be HEAD");
    if (!is_known_chunk(c.type)) {
      if (is_critical(c.type)) fail(Status::bad_chunk, name + ": unknown critical chunk");
      return Action::skip;
    }
    if (c.type == kInfo) return Action::info;
    if (c.type == kHead) {
      if (header) fail(Status::bad_chunk, name + ": second HEAD");
      header = Header::read(c, limits);
      return Action::header;
    }
    if (c.type == kScalarQuantizer) {
      if (quantizer) fail(Status::bad_chunk, name + ": second SQNT");
      quantizer = read_scalar_quantizer(c);
      const std::uint64_t finest = header->points.back();
      if (quantizer->bits < 21 && finest > (std::uint64_t{1} << (3 * quantizer->bits)))
        fail(Status::bad_header, "HEAD declares " + std::to_string(finest) + " points, more than a 2^" +
                                     std::to_string(quantizer->bits) + " grid holds");
      return Action::quantizer;
    }
    if (!quantizer) fail(Status::bad_chunk, name + ": SQNT must come before it");
    if (needs_recon() && recons < layers && c.type != kRecon && is_critical(c.type))
      fail(Status::bad_chunk, name + ": the previous level's RCON must come first");
    if (c.type == kBaseLayer) {
      if (layers) fail(Status::bad_chunk, name + ": second BASE");
      ++layers;
      return Action::layer;
    }
    if (c.type == kRefinement) {
      if (!layers) fail(Status::bad_chunk, name + ": REFN before BASE");
      if (layers == header->points.size())
        fail(Status::bad_chunk, name + ": more layers than the " + std::to_string(layers) + " declared levels");
      ++layers;
      return Action::layer;
    }
    if (c.type == kRecon) {
      if (!needs_recon()) fail(Status::bad_chunk, name + ": RCON in a stream of kind points");
      if (recons == layers) fail(Status::bad_chunk, name + ": RCON must follow its level's layer chunk, once");
      ++recons;
      return Action::recon;
    }
    // HEND
    if (c.length != 0) fail(Status::bad_chunk, name + ": HEND must be empty");
    if (complete() != header->points.size() || (needs_recon() && recons != layers))
      fail(Status::bad_chunk, name + ": HEND after " + std::to_string(complete()) + " of " +
                                  std::to_string(header->points.size()) + " declared levels");
    end_seen = true;
    return Action::end;
  }
};

void check_size(std::size_t size, const DecodeLimits& limits) {
  if (size > limits.max_bytes)
    fail(Status::limit_exceeded, "the stream has " + std::to_string(size) + " bytes, over the limit of " +
                                     std::to_string(limits.max_bytes));
}

// The decoder's memory accounting (DecodeLimits::max_memory): bytes per
// point of a level being decoded (kept points, the coarser level's copy and
// the added points), per tetrahedron of a Delaunay tetrahedralization being
// built and reconstructed (peak resident set, measured: about 125-160), and
// per kept output simplex.
constexpr std::uint64_t kPointBytes = 32;
constexpr std::uint64_t kTetBytes = 160;
constexpr std::uint64_t kSimplexBytes = 16;

// The n points that refinement layer `c` adds to `coarse`, decoded by the
// coder its first byte names.
std::vector<GridPoint> decode_layer(const ChunkView& c, int q, const std::vector<GridPoint>& coarse, std::uint64_t n,
                                    TableForm tables) {
  if (c.length < 1) fail(Status::bad_layer, to_string(c.type) + ": empty payload");
  if (is_octree_refine_coder(c.payload[0]))
    return decode_refinement(c.payload + 1, c.length - 1, q, coarse, n, tables, static_cast<RefineCoder>(c.payload[0]));
  fail(Status::bad_layer, "REFN: unknown coder " + std::to_string(c.payload[0]));
}

std::string truncation_warning(const ContainerView& view, const ChunkWalker& walk) {
  std::string why = view.truncated ? view.truncation : "the stream ends before HEND";
  return why + "; decoded " + std::to_string(walk.complete()) + " of " +
         std::to_string(walk.header->points.size()) + " levels";
}

}  // namespace

// The per-chunk decoding state, shared with the streaming decoder
// (codec/stream_decoder.hpp).
struct ChunkDecoder::State {
  explicit State(const DecodeOptions& o) : options(o), walk(options.limits), helpers(o.threads > 1 ? 2 : 1) {}
  DecodeOptions options;
  ChunkWalker walk;
  Decoded out;
  std::optional<DecodedLevel> pending;  // a level whose points are decoded, waiting for its RCON
  std::vector<GridPoint> previous_points;  // the last decoded level's points
  std::uint64_t memory = 0;                // bytes counted against limits.max_memory by the kept levels
  // The last reconstructed level's tetrahedralization, kept while a finer
  // level may follow: that level's is built from it (delaunay_refine),
  // inserting only the added points. Counted in `memory` while kept. Shared
  // with the reconstruction in flight, if any (read-only on both sides).
  std::shared_ptr<Tetrahedralization> previous_dt;
  std::uint64_t previous_dt_bytes = 0;
  // The last decoded level's border (resolved; indices of its points),
  // which the next level's RCON may inherit (flag bit 3).
  std::vector<std::uint32_t> previous_border;
  // Without DecodeOptions::rebuild_coarser_levels: the side information of
  // the last level, whose reconstruction waits until it turns out to be the
  // finest one decoded (at finish(), when the stream ends early).
  std::optional<ReconParams> deferred;
  bool finishing = false;  // in finish(): no level follows

  // Rebuild `level`'s connectivity from its side information. `coarser` is
  // the level decoded before it, if any: when its tetrahedralization was
  // kept, this one is built from it. `index`: the level's place in
  // out.levels once it is there (it may still be `pending`), where a
  // reconstruction put in flight is stored.
  void rebuild(DecodedLevel& level, const ReconParams& params, Kind kind, const DecodedLevel* coarser,
               std::size_t index);

  // DecodeOptions::threads > 1 in decode() (set_overlap()): the
  // reconstruction proper (spec 11, after the tetrahedralization) of a level
  // runs on a second thread while this one decodes the next level's points
  // and tetrahedralization; at most one is in flight. It reads only what it
  // owns or shares read-only (its points, its tetrahedralization, its side
  // information) and its result is stored by join(), on this thread, so the
  // output is the one of a sequential decode.
  bool overlap = false;
  HelperBudget helpers;  // one helper at most (the one in flight); outlives it
  struct InFlight {
    std::size_t index;    // in out.levels
    std::future<Reconstruction> result;
  };
  std::optional<InFlight> in_flight;  // the worker owns (shares) what it reads; waited for on destruction
  void store(DecodedLevel& level, Reconstruction&& rec) {
    level.triangles = std::move(rec.triangles);
    level.tetrahedra = std::move(rec.tetrahedra);
    level.rebuilt = true;
    memory += (level.triangles.size() + level.tetrahedra.size()) * kSimplexBytes;
  }
  // Waits for the reconstruction in flight and stores it; rethrows its error.
  void join() {
    if (!in_flight) return;
    InFlight f = std::move(*in_flight);
    in_flight.reset();
    store(out.levels[f.index], f.result.get());
  }
  // After an error on this thread: a reconstruction in flight belongs to an
  // earlier level, so its error, if any, is the one a sequential decode
  // would have met first.
  [[noreturn]] void join_and_rethrow(std::exception_ptr error) {
    if (in_flight) {
      InFlight f = std::move(*in_flight);
      in_flight.reset();
      f.result.get();  // throws the earlier error, if any
    }
    std::rethrow_exception(error);
  }
  // DecodeOptions::threads > 1 without rebuild_coarser_levels: the levels
  // before the rebuilt one get no tetrahedralization of their own, but a
  // helper builds one for the last of them it can, each from the previous
  // one it finished (delaunay_refine), while this thread decodes the finer
  // levels' points; the rebuilt level's is then built from it, inserting
  // only the points added since. The work is speculative: a failure there
  // (a limit, memory) is dropped and the level is tetrahedralized from
  // scratch, as with one thread, so the output and the errors are those of
  // a sequential decode. At most one in flight, its bytes counted in
  // `memory` (at its bound until joined).
  struct Ahead {
    int lod;  // the level whose points it tetrahedralizes
    std::shared_ptr<const std::vector<GridPoint>> points;
    std::future<std::optional<Tetrahedralization>> dt;  // empty when it failed
    std::uint64_t bytes;
  };
  std::optional<Ahead> ahead;
  void speculate(const DecodedLevel& level);
  struct Early {
    int lod;
    std::shared_ptr<const std::vector<GridPoint>> points;
    Tetrahedralization dt;
  };
  // Waits for the speculative tetrahedralization and takes it out of the
  // accounting; nullopt when there was none or it failed.
  std::optional<Early> take_ahead() {
    if (!ahead) return std::nullopt;
    Ahead a = std::move(*ahead);
    ahead.reset();
    memory -= a.bytes;
    std::optional<Tetrahedralization> dt = a.dt.get();  // the job throws nothing
    if (!dt) return std::nullopt;
    return Early{a.lod, std::move(a.points), std::move(*dt)};
  }

  // DecodeOptions::threads > 1 with rebuild_coarser_levels, in decode(),
  // which holds the whole stream (set_chunks()): once the base layer's
  // points are decoded, the helper decodes the refinement layers' points,
  // one after the other (a layer needs only the coarser level's points),
  // while this thread tetrahedralizes the coarser levels; the helper then
  // takes their reconstructions. Each layer's points, or its error, wait in
  // a slot until this thread meets the layer's chunk, in stream order, and
  // takes them there (a chunk other than the slot's, which only a malformed
  // stream has, drops the slots and is decoded here), so the output and the
  // errors are those of a sequential decode. The slots are not counted in
  // `memory`, so that every decision on the limit (the room a
  // tetrahedralization is given, which its error message quotes; whether a
  // tetrahedralization is kept) is the sequential one: the helper starts
  // only where `memory`, the slots' levels at kPointBytes per point and the
  // finest of them at 8 tetrahedra per point fit in the limit together.
  const std::vector<ChunkView>* chunks = nullptr;
  struct LayerSlot {
    const std::uint8_t* payload;  // the chunk's
    std::future<std::optional<std::vector<GridPoint>>> added;  // nullopt: not decoded ahead
  };
  std::deque<LayerSlot> slots;  // in stream order
  std::future<void> prefetch;   // the helper's job: ready once every slot is set
  void layers_ahead(const std::vector<GridPoint>& base, const ChunkView& base_chunk);
  // The slot of layer chunk `c` (an invalid future when there is none).
  std::future<std::optional<std::vector<GridPoint>>> take_layer(const ChunkView& c) {
    if (slots.empty()) return {};
    if (slots.front().payload != c.payload) {
      drop_layers();
      return {};
    }
    LayerSlot slot = std::move(slots.front());
    slots.pop_front();
    return std::move(slot.added);
  }
  void drop_layers() {
    if (prefetch.valid()) prefetch.wait();
    slots.clear();
  }

  ~State() {
    if (in_flight) in_flight->result.wait();
    if (ahead) ahead->dt.wait();
    if (prefetch.valid()) prefetch.wait();
  }

  // Fails with limit_exceeded unless `bytes` more fit in the memory limit.
  // The kept and the speculative tetrahedralizations only save time: they
  // go first, so that no stream fails that would decode without them.
  void reserve(std::uint64_t bytes, const std::string& what) {
    const std::uint64_t max = options.limits.max_memory;
    if (ahead && (bytes > max || memory > max - bytes)) take_ahead();
    if (previous_dt && (bytes > max || memory > max - bytes)) {
      previous_dt.reset();
      memory -= previous_dt_bytes;
      previous_dt_bytes = 0;
    }
    if (bytes > max || memory > max - bytes)
      fail(Status::limit_exceeded, what + " needs about " + std::to_string(bytes) + " bytes, and " +
                                       std::to_string(memory) + " are in use, over the memory limit of " +
                                       std::to_string(max));
  }
};

void ChunkDecoder::State::rebuild(DecodedLevel& level, const ReconParams& params, Kind kind,
                                  const DecodedLevel* coarser, std::size_t index) {
  if (options.progress) options.progress(level.lod, true);
  const std::uint64_t n = level.points.size();
  const std::string what =
      "the reconstruction of level " + std::to_string(level.lod) + " (" + std::to_string(n) + " points)";
  std::shared_ptr<Tetrahedralization> coarse = std::move(previous_dt);
  previous_dt.reset();
  // A reconstruction in flight still reads `coarse`: its bytes stay counted
  // until it is joined. Where that would fail this level, it is waited for
  // (settle()), which leaves the accounting a sequential decode has here.
  const std::uint64_t coarse_bytes = previous_dt_bytes;
  previous_dt_bytes = 0;
  bool coarse_counted = true;
  auto settle = [&] {
    join();
    if (coarse_counted) memory -= coarse_bytes, coarse_counted = false;
  };
  if (in_flight && in_flight->result.wait_for(std::chrono::seconds(0)) == std::future_status::ready) join();
  if (!in_flight) settle();
  // A speculative tetrahedralization leaves the accounting first, so that
  // the room is the one a sequential decode has.
  std::optional<Early> early = take_ahead();
  const std::uint64_t max = options.limits.max_memory;
  if (in_flight && (n * kPointBytes > max || memory > max - n * kPointBytes)) settle();
  reserve(n * kPointBytes, what);
  // The previous level is the coarser one, and its points a subset; so are
  // those of a speculative tetrahedralization of a coarser level. A helper
  // not busy with a reconstruction in flight takes half of the verification.
  HelperBudget* spare = overlap ? &helpers : nullptr;
  auto build = [&]() -> Tetrahedralization {
    const std::uint64_t room = max - memory - n * kPointBytes;
    if (early) {
      coarse.reset();
      // Insertions into it may fail where building from scratch does not
      // (the limit bounds the cells alive at any moment, and the two ways
      // pass through different ones): any failure falls back to that, whose
      // outcome is the sequential one.
      std::optional<Tetrahedralization> got;
      {
        Early e = std::move(*early);
        early.reset();
        try {
          if (e.lod == level.lod) got = std::move(e.dt);
          else got = delaunay_refine(level.points, *e.points, std::move(e.dt), room / kTetBytes, spare);
        } catch (...) {
        }
      }  // released before the fallback
      if (got) return std::move(*got);
      return delaunay(level.points, room / kTetBytes, spare);
    }
    if (coarse && coarser && coarser->lod == level.lod + 1) {
      // Handed over, or copied while the reconstruction in flight reads it.
      Tetrahedralization sub = in_flight ? *coarse : std::move(*coarse);
      return delaunay_refine(level.points, coarser->points, std::move(sub), room / kTetBytes, spare);
    }
    return delaunay(level.points, room / kTetBytes, spare);
  };
  Tetrahedralization dt;
  try {
    dt = build();
  } catch (const StreamError& e) {
    // Over the limit while the reconstruction in flight holds its bytes:
    // again with the room of a sequential decode.
    if (!in_flight || e.error().status != Status::limit_exceeded) throw;
    settle();
    dt = build();
  }
  coarse.reset();
  settle();
  const std::uint64_t keep = dt.tets.size() * 2 * sizeof(dt.tets[0]);
  auto shared = std::make_shared<Tetrahedralization>(std::move(dt));
  // The last level rebuilt (the requested one, or the last of a stream that
  // ends early) is reconstructed here, with the helper taking half of its
  // loops; any other level on the helper, while this thread goes on.
  const bool last = level.lod <= options.finest_level || finishing;
  if (overlap && !last) {
    // The points are copied: the level moves into out.levels meanwhile.
    auto points = std::make_shared<const std::vector<GridPoint>>(level.points);
    std::shared_ptr<const Tetrahedralization> tets = shared;
    // Without a thread to be had it is reconstructed here, as with one
    // thread. The points of the finer layers come first: they are the next
    // levels' inputs, and the helper is free for this once they are done.
    if (prefetch.valid()) prefetch.wait();
    auto f = helpers.try_run([points, tets, kind, params] { return reconstruct(*points, *tets, kind, params); });
    if (f.valid()) in_flight = InFlight{index, std::move(f)};
  }
  if (!in_flight) store(level, reconstruct(level.points, *shared, kind, params, spare));
  if (level.lod > std::max(options.finest_level, 0) && memory <= max && keep <= max - memory) {
    previous_dt = std::move(shared);
    previous_dt_bytes = keep;
    memory += keep;
  }
}

void ChunkDecoder::State::layers_ahead(const std::vector<GridPoint>& base, const ChunkView& base_chunk) {
  if (!chunks || !overlap || !options.reconstruct || !options.rebuild_coarser_levels) return;
  const auto& counts = walk.header->points;
  const auto levels = static_cast<int>(counts.size());
  // The layer chunks after the base one, up to the requested level.
  std::vector<ChunkView> layers;
  auto it = std::find_if(chunks->begin(), chunks->end(), [&](const ChunkView& v) { return v.payload == base_chunk.payload; });
  if (it == chunks->end()) return;
  for (++it; it != chunks->end() && layers.size() + 1 < counts.size(); ++it) {
    if (it->type != kRefinement) continue;
    if (levels - 1 - static_cast<int>(layers.size() + 1) < options.finest_level) break;
    layers.push_back(*it);
  }
  if (layers.empty()) return;
  std::uint64_t bytes = 0;
  for (std::size_t i = 0; i < layers.size(); ++i) bytes += counts[i + 1] * kPointBytes;
  const std::uint64_t finest = counts[layers.size()] * (kPointBytes + 8 * kTetBytes);
  const std::uint64_t max = options.limits.max_memory;
  if (memory > max || bytes > max - memory || finest > max - memory - bytes) return;
  std::vector<std::promise<std::optional<std::vector<GridPoint>>>> promises(layers.size());
  std::deque<LayerSlot> made;
  for (std::size_t i = 0; i < layers.size(); ++i)
    made.push_back({layers[i].payload, promises[i].get_future()});
  const int q = walk.quantizer->bits;
  const TableForm tables = walk.header->tables;
  std::vector<std::uint64_t> added_counts;
  for (std::size_t i = 0; i < layers.size(); ++i) added_counts.push_back(counts[i + 1] - counts[i]);
  auto job = [promises = std::move(promises), layers = std::move(layers), added_counts = std::move(added_counts),
              coarse = base, q, tables]() mutable {
    std::size_t i = 0;
    for (; i < promises.size(); ++i) {
      try {
        std::vector<GridPoint> added = decode_layer(layers[i], q, coarse, added_counts[i], tables);
        if (i + 1 < promises.size()) {
          std::vector<GridPoint> finer(coarse.size() + added.size());
          std::merge(coarse.begin(), coarse.end(), added.begin(), added.end(), finer.begin());
          coarse.swap(finer);
        }
        promises[i].set_value(std::move(added));
      } catch (...) {
        promises[i].set_exception(std::current_exception());
        ++i;
        break;
      }
    }
    for (; i < promises.size(); ++i) promises[i].set_value(std::nullopt);
  };
  auto f = helpers.try_run(std::move(job));
  if (!f.valid()) return;
  slots = std::move(made);
  prefetch = std::move(f);
}

void ChunkDecoder::State::speculate(const DecodedLevel& level) {
  if (!overlap) return;
  std::optional<Early> from;  // the last level the helper finished, if any
  if (ahead) {
    // Still busy: a later level refines from what it is building.
    if (ahead->dt.wait_for(std::chrono::seconds(0)) != std::future_status::ready) return;
    from = take_ahead();
  }
  // At most 8 tetrahedra per point (points on a surface or in a volume
  // have about 6.5; with more, as on skew lines, it gives up), counted at
  // that bound, so that the memory limit holds whatever the points.
  const std::uint64_t n = level.points.size();
  const std::uint64_t max_tets = 8 * n;
  const std::uint64_t bytes = max_tets * kTetBytes;
  const std::uint64_t max = options.limits.max_memory;
  if (memory > max || bytes > max - memory) return;
  auto points = std::make_shared<const std::vector<GridPoint>>(level.points);
  auto job = [points, from = std::move(from), max_tets]() mutable -> std::optional<Tetrahedralization> {
    try {
      if (from) return delaunay_refine(*points, *from->points, std::move(from->dt), max_tets);
      return delaunay(*points, max_tets);
    } catch (...) {
      return std::nullopt;  // the rebuilt level is tetrahedralized from scratch
    }
  };
  auto f = helpers.try_run(std::move(job));
  if (!f.valid()) return;
  memory += bytes;
  ahead = Ahead{level.lod, std::move(points), std::move(f), bytes};
}

ChunkDecoder::ChunkDecoder(const DecodeOptions& options) : s_(std::make_unique<State>(options)) {}
ChunkDecoder::~ChunkDecoder() = default;

void ChunkDecoder::set_version(std::uint8_t major, std::uint8_t minor) {
  s_->out.version_major = major;
  s_->out.version_minor = minor;
}

bool ChunkDecoder::chunk_impl(const ChunkView& c) {
  const DecodeOptions& options = s_->options;
  ChunkWalker& walk = s_->walk;
  Decoded& out = s_->out;
  std::optional<DecodedLevel>& pending = s_->pending;
  std::vector<GridPoint>& previous_points = s_->previous_points;
  const std::size_t levels_before = out.levels.size();
  switch (walk.classify(c)) {
    case ChunkWalker::Action::header:
      out.kind = walk.header->kind;
      out.declared_points = walk.header->points;
      break;
    case ChunkWalker::Action::quantizer: out.quantizer = *walk.quantizer; break;
    case ChunkWalker::Action::info: out.info = parse_info(c); break;
    case ChunkWalker::Action::layer: {
      // Layers after the requested level are checked for order only.
      if (!out.levels.empty() && out.levels.back().lod <= options.finest_level) break;
      const std::size_t k = walk.layers - 1;  // position in stream order
      const auto& counts = walk.header->points;
      if (c.length < 1) fail(Status::bad_layer, to_string(c.type) + ": empty payload");
      DecodedLevel level;
      level.lod = static_cast<int>(counts.size() - 1 - k);
      if (options.progress) options.progress(level.lod, false);
      s_->reserve(counts[k] * kPointBytes, "level " + std::to_string(level.lod) + " (" + std::to_string(counts[k]) + " points)");
      if (k == 0) {
        level.points = decode_base(c.payload, c.length, walk.quantizer->bits, counts.front(), walk.header->tables,
                                   s_->overlap ? &s_->helpers : nullptr);
        s_->layers_ahead(level.points, c);
      } else {
        const auto& coarse = previous_points;
        auto ahead = s_->take_layer(c);  // the points decoded ahead, if any
        std::optional<std::vector<GridPoint>> added = ahead.valid() ? ahead.get() : std::nullopt;
        if (!added)
          added = decode_layer(c, walk.quantizer->bits, coarse, counts[k] - counts[k - 1], walk.header->tables);
        level.points.resize(coarse.size() + added->size());
        std::merge(coarse.begin(), coarse.end(), added->begin(), added->end(), level.points.begin());
      }
      level.stream_bytes = c.offset + kChunkOverhead + c.length;
      // A copy for the next layer, when one may follow.
      if (k + 1 < counts.size() && level.lod > options.finest_level) previous_points = level.points;
      else std::vector<GridPoint>().swap(previous_points);
      s_->memory += level.points.size() * sizeof(GridPoint);
      if (walk.needs_recon()) {
        pending = std::move(level);
      } else {
        out.levels.push_back(std::move(level));
      }
      break;
    }
    case ChunkWalker::Action::recon: {
      if (!pending) break;  // a level after the requested one
      ReconParams params = read_recon(c, pending->points.size(), walk.header->tables);
      s_->deferred.reset();
      if (options.reconstruct) {
        // Levels are decoded coarsest first, so the last one is the coarser
        // level, whose points are a subset of these (none before the first:
        // it inherits the empty set).
        const DecodedLevel* coarser = out.levels.empty() ? nullptr : &out.levels.back();
        if (params.border_delta)
          resolve_border(params, coarser ? inherited_border(pending->points, coarser->points, s_->previous_border)
                                         : std::vector<std::uint32_t>{});
        s_->previous_border = params.border;
        // The requested level is the last one decoded; any other may be put off.
        if (options.rebuild_coarser_levels || pending->lod <= options.finest_level) {
          s_->rebuild(*pending, params, walk.header->kind, coarser, out.levels.size());
        } else {
          s_->deferred = std::move(params);
          s_->speculate(*pending);
        }
      }
      pending->stream_bytes = c.offset + kChunkOverhead + c.length;
      out.levels.push_back(std::move(*pending));
      pending.reset();
      break;
    }
    case ChunkWalker::Action::skip:
    case ChunkWalker::Action::end: break;
  }
  return out.levels.size() > levels_before;
}

bool ChunkDecoder::chunk(const ChunkView& c) {
  try {
    return chunk_impl(c);
  } catch (...) {
    s_->join_and_rethrow(std::current_exception());
  }
}

void ChunkDecoder::finish(const ContainerView& view) {
  try {
    s_->join();
    finish_impl(view);
    s_->join();
  } catch (...) {
    s_->join_and_rethrow(std::current_exception());
  }
}

void ChunkDecoder::finish_impl(const ContainerView& view) {
  const DecodeOptions& options = s_->options;
  const ChunkWalker& walk = s_->walk;
  Decoded& out = s_->out;
  // A level whose reconstruction was put off is the finest one decoded
  // when no finer level followed it.
  s_->finishing = true;
  if (s_->deferred && !out.levels.empty()) {
    const std::size_t k = out.levels.size();
    s_->rebuild(out.levels.back(), *s_->deferred, walk.header->kind, k > 1 ? &out.levels[k - 2] : nullptr, k - 1);
    s_->deferred.reset();
  }
  if (!walk.end_seen) {
    if (out.levels.empty())
      fail(Status::truncated, view.truncated ? view.truncation + "; no complete level"
                                             : std::string("the stream ends before its first level is complete"));
    // Without the end chunk the stream may have been cut: say so, and call
    // it truncated when the requested level is missing.
    out.warning = truncation_warning(view, walk);
    out.truncated = out.levels.back().lod > options.finest_level;
  }
}

const Decoded& ChunkDecoder::result() const { return s_->out; }
Decoded ChunkDecoder::take() {
  s_->join();
  return std::move(s_->out);
}
void ChunkDecoder::set_overlap(bool on) { s_->overlap = on; }
void ChunkDecoder::set_chunks(const std::vector<ChunkView>* chunks) { s_->chunks = chunks; }
bool ChunkDecoder::header_ready() const { return s_->walk.header && s_->walk.quantizer; }
bool ChunkDecoder::ended() const { return s_->walk.end_seen; }

namespace {

Decoded decode_impl(const std::uint8_t* data, std::size_t size, const DecodeOptions& options) {
  check_size(size, options.limits);
  const ContainerView view = parse_container(data, size, kEnd);
  ChunkDecoder decoder(options);
  decoder.set_overlap(options.threads > 1);
  decoder.set_chunks(&view.chunks);
  decoder.set_version(view.major, view.minor);
  for (const ChunkView& c : view.chunks) decoder.chunk(c);
  decoder.finish(view);
  return decoder.take();
}

StreamInfo inspect_impl(const std::uint8_t* data, std::size_t size, const DecodeLimits& limits) {
  check_size(size, limits);
  const ContainerView view = parse_container(data, size, kEnd);
  StreamInfo info;
  info.version_major = view.major;
  info.version_minor = view.minor;
  info.total_bytes = size;
  ChunkWalker walk(limits);
  for (const ChunkView& c : view.chunks) {
    ChunkInfo ci;
    ci.type = to_string(c.type);
    ci.offset = c.offset;
    ci.length = c.length;
    ci.critical = is_critical(c.type);
    ci.known = is_known_chunk(c.type);
    info.chunks.push_back(ci);
    const auto action = walk.classify(c);
    if (action == ChunkWalker::Action::header) {
      info.kind = walk.header->kind;
      info.declared_points = walk.header->points;
    } else if (action == ChunkWalker::Action::quantizer) {
      info.quantizer = *walk.quantizer;
    } else if (action == ChunkWalker::Action::recon) {
      info.levels.back().side_bytes = kChunkOverhead + c.length;
      info.levels.back().stream_bytes = c.offset + kChunkOverhead + c.length;
    } else if (action == ChunkWalker::Action::layer) {
      LevelReport lr;  // BASE or REFN
      const std::size_t k = walk.layers - 1;
      lr.lod = static_cast<int>(walk.header->points.size() - 1 - k);
      lr.points = walk.header->points[k];
      lr.new_points = lr.points - (k ? walk.header->points[k - 1] : 0);
      lr.layer_bytes = kChunkOverhead + c.length;
      lr.stream_bytes = c.offset + kChunkOverhead + c.length;
      if (k > 0 && c.length > 0) lr.coder = c.payload[0];
      info.levels.push_back(lr);
    }
  }
  if (!walk.end_seen) {
    info.truncated = true;
    info.warning = walk.header ? truncation_warning(view, walk)
                               : (view.truncated ? view.truncation : std::string("no HEAD chunk"));
  }
  return info;
}

}  // namespace

Result<Decoded> decode(const std::uint8_t* data, std::size_t size, const DecodeOptions& options) {
  return guarded<Result<Decoded>>([&] { return Result<Decoded>(decode_impl(data, size, options)); });
}

Result<StreamInfo> inspect(const std::uint8_t* data, std::size_t size, const DecodeLimits& limits) {
  return guarded<Result<StreamInfo>>([&] { return Result<StreamInfo>(inspect_impl(data, size, limits)); });
}

// Here rather than in encoder.cpp: a decoder-only build has it too.
const char* version_string() noexcept { return HMC_VERSION_STRING; }

}  // namespace hmc
