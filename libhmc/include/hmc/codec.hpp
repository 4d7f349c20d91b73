// SPDX-License-Identifier: AGPL-3.0-or-later
//
// hmc/codec.hpp — encoding a mesh or point set into an HMC stream, and
// decoding a stream back into points, level by level.
//
// An HMC stream carries only vertex positions, quantized to a uniform grid of
// 2^q cells per axis with one step for all three axes. It holds one or more
// levels of detail; level 0 is the finest, and the stream sends the coarsest
// level first. The decoded points of every level are exact: two conforming
// decoders produce the same integer grid points, in the same canonical order
// (ascending x, then y, then z).
//
// No function here throws. Decoding is safe on untrusted input: memory and
// time are bounded by DecodeLimits, checked before anything is allocated.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "hmc/mesh.hpp"
#include "hmc/status.hpp"

namespace hmc {

/// What the points describe, and so what the decoder rebuilds from them.
enum class Kind : std::uint8_t {
  points = 0,   ///< a bare point set; no connectivity is rebuilt
  surface = 1,  ///< all vertices lie on a surface (open or closed): triangles
  volume = 2,   ///< boundary and interior vertices of a solid: tetrahedra
};

/// "points", "surface" or "volume".
const char* kind_name(Kind k) noexcept;

/// A vertex on the quantization grid; each coordinate is below 2^q.
using GridPoint = std::array<std::uint32_t, 3>;

/// The uniform scalar quantizer: grid coordinate i maps to origin + i * step
/// on each axis (binary64, multiply then add, no fused multiply-add).
struct ScalarQuantizer {
  int bits = 12;       ///< q, 1 <= q <= 21
  Vec3 origin{};       ///< position of grid point (0, 0, 0)
  double step = 1.0;   ///< grid spacing, the same on all three axes

  /// The position of a grid point.
  Vec3 dequantize(const GridPoint& p) const noexcept;
  /// The number of cells per axis, 2^q.
  std::uint32_t cells() const noexcept { return std::uint32_t{1} << bits; }
};

/// How much reconstruction side information the encoder sends.
enum class Fidelity : std::uint8_t {
  rule = 0,   ///< only the rule's parameters: the decoder's own best guess
  shape = 1,  ///< also correct every label that changes the shape; leave flips of
              ///< flat tetrahedra (diagonals of near-planar quads) to the rule, and
              ///< mend where the input's own labels are unsound (edges with more
              ///< than two faces where input triangles are not Delaunay faces)
  exact = 2,  ///< also correct those: the decoded labels equal the input's exactly
  /// Between rule and shape: what shape corrects, except that flat flips stay
  /// with the rule even where together they change the surface's topology
  /// (shape then corrects every one): only the groups of them that change
  /// the Euler characteristic are corrected. The same components, Euler
  /// characteristic and soundness as shape, a little further from the input
  /// (flat flips side by side), fewer of its triangles, less side information.
  topology = 3,
};

/// How boundary (surface) vertices are chosen for removal (thesis §3.4.1):
/// by their distance to the plane (or chord) of their neighbours, below a
/// threshold Dmax that is constant over the levels, grows linearly with the
/// level, or adapts to each region's local spacing and level.
enum class BoundaryMode : std::uint8_t { constant = 0, linear = 1, adaptive = 2 };

/// How interior vertices of a volume are chosen for removal (thesis
/// §3.4.2): by importance, layer by layer from the boundary inward
/// (forward), from the centre outward (backward), all layers at once
/// (greedy), or whichever of those and of the central-layer variants keeps
/// the most important vertices (best).
enum class Optimizer : std::uint8_t { forward = 0, backward = 1, greedy = 2, best = 3 };

/// Stable lower-case names: "constant", "forward", ...
const char* boundary_mode_name(BoundaryMode m) noexcept;
const char* optimizer_name(Optimizer o) noexcept;

/// Encoder settings.
struct EncodeOptions {
  /// q, bits per axis of the quantization grid, 1..21.
  int bits = 12;
  /// The kind to record; when unset it is detected from the input
  /// (tetrahedra: volume; triangles: surface; neither: points).
  std::optional<Kind> kind;
  /// Write the ancillary `info` chunk (the encoder and, when points were merged, the input count).
  bool write_info = true;
  /// Reconstruction side information (surface and volume kinds).
  Fidelity fidelity = Fidelity::shape;
  /// Coarser levels (all but the finest) follow the input surface as the
  /// finest level does, with `fidelity`'s corrections and the input's
  /// topology as the target, instead of keeping the decoder's rule and
  /// repair. They then look like the model: on the 13 shared models at 4
  /// levels, Hausdorff distance to the input 0.1-1.5 % of the diagonal
  /// instead of 3-20 %, for 0.3-18 % more bytes (geometric mean 11.6 %,
  /// bench/results/coarse_levels.md); off by default. No effect with
  /// Fidelity::rule or Fidelity::exact (exact already corrects every label).
  bool fit_coarse_levels = false;
  /// Levels of detail, 1..64. Level 0 is the input; each coarser level
  /// removes an independent set of the finer level's vertices. Fewer levels
  /// are written when a level has nothing left to remove; preview_ratio
  /// adds levels below them.
  int levels = 1;
  /// Share of a level's vertices to remove to make the next coarser level
  /// (0 < ratio <= 1; 1 removes as many as independence allows).
  double removal_ratio = 0.3;
  /// Levels of octree cells below the independent-set levels, a preview
  /// that arrives first. A share r in (0, 1) makes each coarser level, below
  /// the coarsest of `levels`, keep one point per occupied cell of an octree
  /// over the grid (the point nearest the cell's centre) at the finest depth
  /// whose cells are at most half the level's points, until a level holds
  /// at most r times the input's points; their reconstruction is corrected
  /// towards the input surface merged onto their points (unless the
  /// fidelity is Fidelity::rule). 0 adds none. Independent sets shrink a
  /// level by a fifth or less, so a coarsest level of a few percent of the
  /// points would take dozens of their levels, each dearer than the last;
  /// cells take three or four. On the 13 shared models, 1 level with r =
  /// 0.04: 3-4 levels, the coarsest 0.7-3.9 % of the points in 1.9-5.7 % of
  /// the bytes, the whole stream 1.14 times the 1-level one (geometric mean;
  /// bench/results/preview.md). A choice of the encoder: the stream is an
  /// ordinary one, with more levels than `levels`. `hmc enc` uses 0.04 when
  /// given neither --levels nor --preview-ratio; the library's default
  /// stays 0, so that a program gets the levels it asks for.
  double preview_ratio = 0;
  /// Linear by default: a constant Dmax chosen on the finest level stalls
  /// on coarser ones, whose vertices are farther from their neighbours' plane.
  BoundaryMode boundary_mode = BoundaryMode::linear;
  Optimizer optimizer = Optimizer::best;
  /// Code the points for decoding speed: plain octrees (BASE coder 0, exact
  /// REFN layers without neighbours), which a decoder reads without
  /// a nearest-neighbour search per node. The stream is larger (the shared
  /// scanned surfaces' by about a fifth, a dense generated torus's by half:
  /// the ranked coders' prediction is off) and decoding the points is tens
  /// of times faster; reconstruction is unchanged.
  bool fast_decode = false;
  /// Called as the encoder advances: the level being planned (0 = finest)
  /// and the share of the work done, 0 to 1. It must not throw (it is
  /// called on the caller's thread).
  std::function<void(int level, double done)> progress = nullptr;
  /// Threads encode() may use, counting the caller's (at most 64). With 2
  /// or more, helper threads take whatever work is ready for them: the
  /// point layers, coded as soon as their levels are known, beside the
  /// planning of the coarser levels; half of the winding numbers that tell
  /// which tetrahedra lie inside the input; half of each batch of
  /// reconstruction trials that do not depend on each other; half of the
  /// nodes of a large base layer that no helper was free to code
  /// beforehand. The stream is the same, byte for byte. On five of the
  /// shared models with two threads: 22-28 % less wall-clock time at four
  /// levels, 30-39 % at one (measured before the base layer's split, which
  /// takes 5-11 % more off four-level encodes of the bunny, the horse and
  /// hand_tetgen).
  unsigned threads = 1;
  /// The grid to quantize onto, instead of one fitted to the input's bounding
  /// box: grid point i is origin + i * step (ScalarQuantizer), q = `bits`. A
  /// tiled model (spec/tiles.md) encodes every tile on its one global grid,
  /// so tiles decode to the lattice coordinates of the untiled model. Every
  /// input point must round into [0, 2^q - 1] on each axis (invalid_argument
  /// otherwise: nothing is clamped); origin finite, step finite and > 0.
  struct Lattice {
    Vec3 origin{};
    double step = 1.0;
  };
  std::optional<Lattice> lattice = std::nullopt;
  /// A tile's box (x0, y0, z0, x1, y1, z1: half-open, lattice coordinates,
  /// x0 < x1 <= 2^bits on each axis), for the streams of a tiled model:
  /// every level's reconstruction then floods the outside in only through
  /// faces with a vertex in the box (RCON seal, spec 11.3), not through the
  /// faces between margin points across the tile's cuts, and the encoder
  /// corrects only tetrahedra with a vertex in the box (the merged model
  /// keeps no other, spec/tiles.md). On a 51,940-point tile of a
  /// 100,000-point torus (q = 14, fidelity exact) that takes the RCON chunk
  /// from 16,180 to 5,043 bytes. Unset: no seal, as for an untiled stream.
  std::optional<std::array<std::uint32_t, 6>> seal_box = std::nullopt;
  /// The length (lattice units) that the encoder's geometric tolerances are
  /// fractions of: 1/1000 of it is how far a face of the reconstruction may
  /// stray from the input surface before the encoder drops it (`RCON` drop
  /// list), and how thin a tetrahedron fidelity shape leaves to the rule.
  /// 0: the diagonal of each level's bounding box. A tile gives the whole
  /// model's (hmc tile does), or its tolerances are its own smaller box's:
  /// a 58,382-point noisy height field in 4 tiles (q = 14) lost 1,876 of
  /// its 114,547 triangles to the drop list. Finite, >= 0.
  double tolerance_diagonal = 0;
};

/// Per-level figures of an encoded or decoded stream.
struct LevelReport {
  int lod = 0;                 ///< level index, 0 = finest
  std::uint64_t points = 0;    ///< points of this level (cumulative)
  std::uint64_t new_points = 0;///< points this level's layer adds
  std::uint64_t layer_bytes = 0;  ///< bytes of this level's point layer chunk, with framing
  std::uint64_t side_bytes = 0;   ///< bytes of its reconstruction side information (RCON), with framing
  std::uint64_t stream_bytes = 0; ///< prefix of the stream that decodes this level
  std::uint64_t label_corrections = 0;  ///< tetrahedron labels the side information corrects
  std::uint64_t rule_mismatches = 0;    ///< labels the rule alone gets wrong (encoder only)

  // Encoder only: how this level was decimated into the next coarser one.
  std::uint64_t simplices = 0;                 ///< triangles or tetrahedra of this level
  std::vector<std::uint64_t> layer_sizes;      ///< vertices per layer L0 (boundary), L1, ... of its mesh
  std::uint64_t boundary_removed = 0;          ///< boundary vertices removed from this level
  std::uint64_t inner_removed = 0;             ///< interior vertices removed from this level
  std::uint64_t classification_disagreements = 0;  ///< vertices the face and solid-angle tests classify differently
  double dmax = 0;                             ///< Dmax used (grid units)
  Optimizer optimizer = Optimizer::best;       ///< the inner optimiser that was used (what `best` chose)
  double mean_importance_retained = 0;         ///< mean IP (eq. 3.1) of the interior vertices kept

  /// Refinement coder of this level's layer (spec 8A): 0 conditional octree
  /// with the short header, 7 with the full header; 0 for the base.
  int coder = 0;
};

/// What the encoder did.
struct EncodeReport {
  Kind kind = Kind::points;
  ScalarQuantizer quantizer;
  std::uint64_t input_points = 0;       ///< points given
  std::uint64_t distinct_points = 0;    ///< distinct grid points after quantization
  std::uint64_t duplicates_merged = 0;  ///< input_points - distinct_points
  std::uint64_t total_bytes = 0;
  std::vector<LevelReport> levels;      ///< coarsest first
  /// What the caller may not expect of the stream, one sentence each: fewer
  /// levels than requested (and why), or a surface or volume whose points
  /// span no volume, for which the decoder rebuilds no connectivity. Empty
  /// when there is nothing to say.
  std::vector<std::string> notes;
};

/// One decoded level.
struct DecodedLevel {
  int lod = 0;                     ///< level index, 0 = finest
  std::vector<GridPoint> points;   ///< canonical order: ascending (x, y, z)
  std::uint64_t stream_bytes = 0;  ///< prefix length of the stream that decodes it
  /// Rebuilt connectivity, indices into `points` (surface kind: triangles,
  /// counter-clockwise seen from outside; volume kind: positively oriented
  /// tetrahedra), in canonical order (spec "Reconstruction").
  std::vector<Triangle> triangles;
  std::vector<Tetrahedron> tetrahedra;
  /// The connectivity was rebuilt (false for kind points, without
  /// DecodeOptions::reconstruct, and for the coarser levels without
  /// DecodeOptions::rebuild_coarser_levels).
  bool rebuilt = false;
};

/// An encoded stream with its report.
struct Encoded {
  std::vector<std::uint8_t> bytes;
  EncodeReport report;
  /// The finest level's points as the decoder will output them
  /// (distinct quantized input points, ascending).
  std::vector<GridPoint> points;
  /// The finest level's connectivity as the decoder will rebuild it
  /// (indices into `points`): triangles for surfaces, tetrahedra for volumes.
  std::vector<Triangle> triangles;
  std::vector<Tetrahedron> tetrahedra;
  /// Every level as the decoder will rebuild it, coarsest first.
  std::vector<DecodedLevel> levels;
};

/// Quantize and encode `input`. Errors: invalid_argument (bits out of range,
/// empty input, NaN or infinite coordinates, coordinate range too large for
/// binary64 steps).
Result<Encoded> encode(const Mesh& input, const EncodeOptions& options = {});

/// The grid encode() fits to `points` when EncodeOptions::lattice is unset
/// (box minimum, largest extent / (2^bits - 1)): what a tiled model's tiles
/// share (spec/tiles.md). Errors as encode()'s.
Result<ScalarQuantizer> fit_lattice(const std::vector<Vec3>& points, int bits);

/// Caps on what a decoder will accept; the defaults suit untrusted input.
struct DecodeLimits {
  std::uint64_t max_points = std::uint64_t{1} << 26;  ///< points of the finest level
  std::uint32_t max_levels = 64;                      ///< levels declared
  std::uint64_t max_bytes = std::uint64_t{1} << 32;   ///< stream size
  /// Approximate working memory of one decode, in bytes: the decoded levels'
  /// points and simplices plus the Delaunay tetrahedralization and the
  /// reconstruction of the level being rebuilt (the decoder counts 32 bytes
  /// per point and 160 per tetrahedron, what it measures at peak). A level
  /// that would need more fails with limit_exceeded before the memory is
  /// allocated; so does a Delaunay tetrahedralization that turns out larger
  /// than the rest allows (n points can have up to n(n-3)/2 tetrahedra).
  /// 2 GiB rebuilds surfaces of about 1.5 million points.
  std::uint64_t max_memory = std::uint64_t{1} << 31;
};

/// Decoder settings.
struct DecodeOptions {
  DecodeLimits limits;
  /// Stop after this level (0 = decode down to the finest level).
  int finest_level = 0;
  /// Rebuild triangles or tetrahedra (surface and volume kinds). When false
  /// only points are decoded; side information is still validated.
  bool reconstruct = true;
  /// With reconstruct: rebuild every decoded level (true, what a viewer that
  /// shows each level as it arrives needs), or only the finest one decoded
  /// (false). The coarser levels then come with points only, and their
  /// Delaunay tetrahedralizations and reconstructions are skipped: on the
  /// Stanford bunny's four-level stream (q = 12) that is less than half the
  /// work. The finest level's connectivity is the same either way; the
  /// coarser levels' side information is still parsed and checked, except
  /// for what only a reconstruction can check (toggle and drop indices
  /// against their tetrahedralization, spec section 10). When the stream
  /// stops before the requested level, the last complete level is rebuilt
  /// when the data ends (StreamDecoder: at finish()).
  bool rebuild_coarser_levels = true;
  /// Called as the decoder starts on a level (lod, 0 = finest): on its
  /// points (rebuilding false), then, if it rebuilds it, on its
  /// connectivity (true), the long part of a large level. It must not
  /// throw.
  std::function<void(int level, bool rebuilding)> progress = nullptr;
  /// Threads decode() may use, counting the caller's. With 2 or more (more
  /// are not used), a second thread takes:
  /// - the base layer's nearest-node searches, ahead of its decoding;
  /// - half of the long loops of each tetrahedralization's verification and
  ///   of the last level's reconstruction;
  /// - each other level's reconstruction (spec section 11, after its
  ///   tetrahedralization), while the next level's points and
  ///   tetrahedralization are decoded (up to one more level's working
  ///   memory at once: a fifth to a third more peak memory);
  /// - with rebuild_coarser_levels, the refinement layers' points, once the
  ///   base layer's are decoded, while the coarser levels are
  ///   tetrahedralized (where the limit leaves room for them beside the
  ///   finest level's tetrahedralization; 11 to 14 % less wall-clock time
  ///   on four-level streams, 2026-12-02);
  /// - without rebuild_coarser_levels, the coarser levels'
  ///   tetrahedralizations, while the finer levels' points are decoded; the
  ///   finest level's is built from the last of them, inserting only the
  ///   points added since.
  /// Less wall-clock time on the shared models (2026-11-25): one-level
  /// streams 14 to 21 %, four-level streams 24 to 25 % without
  /// rebuild_coarser_levels and 23 to 29 % with it, for 4 to 16 % more CPU
  /// time.
  /// The output, errors included, is the same, with one exception: under a
  /// max_memory so tight that building a tetrahedralization from scratch
  /// exceeds it part-way, building it from a coarser one may not, so two
  /// threads may decode a stream that one refuses (never the reverse).
  /// StreamDecoder, which hands out each level as it completes, uses one
  /// thread whatever this says.
  unsigned threads = 1;
};


/// A decoded stream.
struct Decoded {
  Kind kind = Kind::points;
  ScalarQuantizer quantizer;
  std::uint8_t version_major = 0, version_minor = 0;
  /// Levels the stream declares, and their point counts, coarsest first.
  std::vector<std::uint64_t> declared_points;
  /// Decoded levels, coarsest first.
  std::vector<DecodedLevel> levels;
  /// True when the stream stopped before the requested level: `levels`
  /// holds what was complete and `warning` says where it stopped.
  bool truncated = false;
  /// Set when the stream does not end with its end chunk (cut, or damaged
  /// after the last level), even if every requested level was decoded.
  std::string warning;
  /// Contents of the ancillary `info` chunk, if present (key, value).
  std::vector<std::pair<std::string, std::string>> info;

  /// Number of levels the stream declares.
  int level_count() const noexcept { return static_cast<int>(declared_points.size()); }
  /// The finest decoded level (levels must not be empty).
  const DecodedLevel& finest() const { return levels.back(); }
};

/// Decode a stream. A stream cut short after at least one complete level
/// succeeds with `truncated` set; one cut before that fails with
/// Status::truncated. Every other defect fails with its error class.
Result<Decoded> decode(const std::uint8_t* data, std::size_t size, const DecodeOptions& options = {});

/// One chunk as `inspect` sees it.
struct ChunkInfo {
  std::string type;
  std::uint64_t offset = 0;  ///< of the chunk's type field
  std::uint32_t length = 0;  ///< payload bytes
  bool critical = false;
  bool known = false;        ///< defined by the spec version this library implements
};

/// The structure of a stream, without decoding its layers.
struct StreamInfo {
  std::uint8_t version_major = 0, version_minor = 0;
  Kind kind = Kind::points;
  ScalarQuantizer quantizer;
  std::vector<std::uint64_t> declared_points;  ///< coarsest first
  std::vector<ChunkInfo> chunks;
  std::vector<LevelReport> levels;  ///< complete levels present, coarsest first
  std::uint64_t total_bytes = 0;
  bool truncated = false;
  std::string warning;
};

/// Parse framing, header and quantizer tables and list chunks and levels.
Result<StreamInfo> inspect(const std::uint8_t* data, std::size_t size, const DecodeLimits& limits = {});

/// The library version, "MAJOR.MINOR.PATCH".
const char* version_string() noexcept;

}  // namespace hmc
