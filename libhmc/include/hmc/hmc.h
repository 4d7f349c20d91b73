/* SPDX-License-Identifier: AGPL-3.0-or-later */
/**
 * @file hmc.h
 * @brief The C API of libhmc: encode meshes to HMC streams and decode them,
 *        whole or as the bytes arrive.
 *
 * Plain C99, for C programs and for foreign-function interfaces (Python
 * ctypes/cffi, Rust, Go, Java, ...). Every type the API hands out is either
 * an opaque handle (::hmc_encoder, ::hmc_decoder), a plain struct of
 * integers and doubles, or a buffer the caller owns.
 *
 * **Errors.** Every function that can fail returns an ::hmc_status; the
 * handle then holds a message saying what was wrong and where
 * (hmc_encoder_message(), hmc_decoder_message()). No C++ exception ever
 * leaves the library. A decoder that met an error in the stream enters a
 * permanent failed state: every later hmc_decoder_feed(),
 * hmc_decoder_finish() and hmc_decoder_decode() returns the same status
 * again. Misuse (a NULL argument, an index out of range, a setting changed
 * after decoding began) returns ::HMC_INVALID_ARGUMENT and leaves the
 * handle as it was.
 *
 * **Memory.** Handles, and every buffer a function returns to the caller
 * (encoded bytes, points, positions, triangles, tetrahedra), are allocated
 * with the ::hmc_allocator given when the handle was created (malloc,
 * realloc and free when NULL), and so is the decoder's buffer for the
 * chunk it is receiving. The caller frees returned buffers with hmc_free()
 * and the same allocator. The codec's internal working memory (decoded
 * levels, Delaunay tetrahedralizations) comes from the C++ heap.
 *
 * **Streaming.** A decoder takes the stream in pieces of any size
 * (hmc_decoder_feed()) and decodes each chunk as soon as its last byte is
 * in. It is *poll style*: after each feed, hmc_decoder_level_count() tells
 * how many levels are complete, coarsest first; a level is complete when its
 * layer chunk and, for surfaces and volumes, its `RCON` chunk have arrived
 * (spec section 3), and its points and rebuilt triangles or tetrahedra are
 * then readable. hmc_decoder_finish() ends the stream: ::HMC_OK when it was
 * whole, ::HMC_INCOMPLETE when it was cut after at least one complete
 * level, ::HMC_TRUNCATED (an error) when it was cut before.
 *
 * The levels, points and simplices a streaming decoder outputs are those
 * hmc_decoder_decode() outputs for the same bytes, and so are the warning
 * and truncation of a cut stream. Errors: the whole-buffer decoder checks
 * the size limit, then the framing (chunk types, lengths, CRCs) of the whole
 * stream, and only then interprets chunks (spec section 13). By default a
 * streaming decoder fails at once on the first defect in stream order, so on
 * a stream with several defects it may report another error class;
 * hmc_decoder_set_error_order() with ::HMC_ERRORS_AS_WHOLE makes it report
 * exactly what hmc_decoder_decode() reports, at hmc_decoder_finish().
 *
 * **Threads.** A handle must not be used by two threads at once. By
 * default the C API starts no thread of its own: encoding and decoding run
 * on the caller's. hmc_encoder_set_threads() and hmc_decoder_set_threads()
 * let a call use helper threads too (`EncodeOptions::threads` and
 * `DecodeOptions::threads` of the C++ API), for the same output in less
 * wall-clock time; a decoder fed in pieces stays on the caller's thread.
 *
 * Example (whole buffer):
 * @code
 * hmc_decoder *dec = hmc_decoder_create(NULL);
 * hmc_status st = hmc_decoder_decode(dec, bytes, size);
 * if (st != HMC_OK && st != HMC_INCOMPLETE) {
 *   fprintf(stderr, "%s: %s\n", hmc_status_string(st), hmc_decoder_message(dec));
 * } else {
 *   size_t n = hmc_decoder_level_count(dec);   // levels, coarsest first
 *   double *xyz; size_t count;
 *   if (hmc_decoder_level_positions(dec, n - 1, &xyz, &count) == HMC_OK) {
 *     // xyz[3*i+0..2]: the finest level's vertices
 *     hmc_free(NULL, xyz);
 *   }
 * }
 * hmc_decoder_destroy(dec);
 * @endcode
 */
#ifndef HMC_HMC_H
#define HMC_HMC_H

#include <stddef.h>
#include <stdint.h>

#ifndef HMC_API
#if defined(_WIN32)
#define HMC_API
#elif defined(__GNUC__) && __GNUC__ >= 4
#define HMC_API __attribute__((visibility("default")))
#else
#define HMC_API
#endif
#endif

#ifdef __cplusplus
extern "C" {
#endif

/** Outcome of a call. The values equal those of `hmc::Status` in
 *  `<hmc/status.hpp>` and are stable across releases. */
typedef enum hmc_status {
  HMC_OK = 0, /**< success */

  /* Stream error classes (normative, spec section 13). */
  HMC_BAD_MAGIC = 1,           /**< the first 8 bytes are not the HMC signature */
  HMC_UNSUPPORTED_VERSION = 2, /**< the major version is not one this decoder knows */
  HMC_CRC_MISMATCH = 3,        /**< a chunk's CRC-32 does not match its contents */
  HMC_TRUNCATED = 4,           /**< the stream ends before its first level is complete */
  HMC_BAD_CHUNK = 5,           /**< chunk length, order, count or type is invalid */
  HMC_BAD_HEADER = 6,          /**< a header or quantizer field is out of range */
  HMC_BAD_HUFFMAN_TABLE = 7,   /**< a Huffman code-length table is invalid */
  HMC_BAD_LAYER = 8,           /**< a vertex layer or side-information payload is malformed */
  HMC_LIMIT_EXCEEDED = 9,      /**< the stream needs more than the decoder's limits allow */

  /* Caller and environment errors. */
  HMC_INVALID_ARGUMENT = 20,   /**< an argument or option is out of range, or a call out of order */
  HMC_IO_ERROR = 21,           /**< a file could not be read or written */
  HMC_PARSE_ERROR = 22,        /**< an input mesh or point file is malformed */
  HMC_UNSUPPORTED_FORMAT = 23, /**< the file format is not recognised or not supported */
  HMC_OUT_OF_MEMORY = 24,      /**< an allocation failed */
  HMC_INTERNAL_ERROR = 25,     /**< a bug in libhmc; please report it */

  /** Not an error (C API only): the stream stopped before its end chunk,
   *  after at least one complete level. The complete levels are readable;
   *  hmc_decoder_message() says where the stream stopped, and
   *  ::hmc_stream_info.truncated whether the level asked for is missing. */
  HMC_INCOMPLETE = 100
} hmc_status;

/** What the points describe, and so what the decoder rebuilds from them. */
typedef enum hmc_kind {
  HMC_KIND_AUTO = -1,   /**< encoder only: detect (tetrahedra: volume; triangles: surface; else points) */
  HMC_KIND_POINTS = 0,  /**< a bare point set; no connectivity is rebuilt */
  HMC_KIND_SURFACE = 1, /**< vertices of a surface: triangles are rebuilt */
  HMC_KIND_VOLUME = 2   /**< boundary and interior vertices of a solid: tetrahedra are rebuilt */
} hmc_kind;

/** How much reconstruction side information the encoder sends. */
typedef enum hmc_fidelity {
  HMC_FIDELITY_RULE = 0,  /**< only the rule's parameters */
  HMC_FIDELITY_SHAPE = 1, /**< also correct every label that changes the shape (default) */
  HMC_FIDELITY_EXACT = 2, /**< the decoded labels equal the input's exactly */
  HMC_FIDELITY_TOPOLOGY = 3 /**< shape's corrections, but flat flips kept unless they change the topology */
} hmc_fidelity;

/** How boundary vertices are chosen for removal between levels (Dmax threshold). */
typedef enum hmc_boundary_mode {
  HMC_BOUNDARY_CONSTANT = 0, /**< the same threshold at every level */
  HMC_BOUNDARY_LINEAR = 1,   /**< a threshold growing linearly with the level (default) */
  HMC_BOUNDARY_ADAPTIVE = 2  /**< a threshold adapted to local spacing and level */
} hmc_boundary_mode;

/** How interior vertices of a volume are chosen for removal between levels. */
typedef enum hmc_optimizer {
  HMC_OPTIMIZER_FORWARD = 0,  /**< layer by layer from the boundary inward */
  HMC_OPTIMIZER_BACKWARD = 1, /**< from the centre outward */
  HMC_OPTIMIZER_GREEDY = 2,   /**< all layers at once */
  HMC_OPTIMIZER_BEST = 3      /**< whichever keeps the most important vertices (default) */
} hmc_optimizer;

/** Most levels a stream can declare. */
#define HMC_MAX_LEVELS 64

/**
 * Memory functions with a user pointer, in the style of malloc, realloc and
 * free. `malloc_fn` and `realloc_fn` return memory aligned for any type, or
 * NULL on failure; `realloc_fn` is called with a non-NULL pointer it or
 * `malloc_fn` returned; `free_fn` may be called with NULL and must then do
 * nothing. All three are required.
 */
typedef struct hmc_allocator {
  void *(*malloc_fn)(void *user, size_t size);             /**< like malloc(size) */
  void *(*realloc_fn)(void *user, void *ptr, size_t size); /**< like realloc(ptr, size) */
  void (*free_fn)(void *user, void *ptr);                  /**< like free(ptr) */
  void *user; /**< passed to each function unchanged */
} hmc_allocator;

/** The library's version.
 *  @return "MAJOR.MINOR.PATCH", a static string (never NULL) */
HMC_API const char *hmc_version_string(void);

/** The stable name of a status.
 *  @param status any value
 *  @return a static lower-case identifier, e.g. "crc_mismatch", "incomplete";
 *          "unknown_status" for a value that is not a status (never NULL) */
HMC_API const char *hmc_status_string(hmc_status status);

/** A description of a status.
 *  @param status any value
 *  @return a static one-sentence English description (never NULL) */
HMC_API const char *hmc_status_description(hmc_status status);

/**
 * Free a buffer the API returned.
 * @param allocator the allocator given when creating the handle that returned
 *                  the buffer, or NULL if that was NULL (the C library's free)
 * @param ptr       the buffer; NULL does nothing
 */
HMC_API void hmc_free(const hmc_allocator *allocator, void *ptr);

/* ------------------------------------------------------------------------ */
/** @name Encoder */
/** @{ */

/** An encoder: settings plus the message of its last failure. */
typedef struct hmc_encoder hmc_encoder;

/** Encoder settings (see `hmc::EncodeOptions`). Initialise with
 *  hmc_encode_options_init(), then change what you need. */
typedef struct hmc_encode_options {
  int bits;             /**< q, bits per axis of the quantization grid, 1..21 (default 12) */
  int levels;           /**< levels of detail, 1..64 (default 1); fewer are written when a level has nothing left to remove */
  double removal_ratio; /**< share of a level's vertices removed to make the next coarser one, (0, 1] (default 0.3) */
  int kind;             /**< an ::hmc_kind; ::HMC_KIND_AUTO detects it from the connectivity given (default) */
  int fidelity;         /**< an ::hmc_fidelity (default ::HMC_FIDELITY_SHAPE) */
  int boundary_mode;    /**< an ::hmc_boundary_mode (default ::HMC_BOUNDARY_LINEAR) */
  int optimizer;        /**< an ::hmc_optimizer (default ::HMC_OPTIMIZER_BEST) */
  int write_info;       /**< non-zero: write the ancillary `info` chunk (default 1) */
  int fast_decode;      /**< non-zero: code the points for decoding speed, in larger streams (default 0; see
                             `hmc::EncodeOptions::fast_decode`) */
} hmc_encode_options;

/** Fill encoder settings with the defaults.
 *  @param options the settings to fill; NULL does nothing */
HMC_API void hmc_encode_options_init(hmc_encode_options *options);

/**
 * Create an encoder with default settings.
 * @param allocator memory functions for the handle and for the buffers it
 *                  returns, copied; NULL for malloc, realloc and free
 * @return the encoder, or NULL when memory ran out or `allocator` lacks a function
 */
HMC_API hmc_encoder *hmc_encoder_create(const hmc_allocator *allocator);

/** Destroy an encoder. Buffers it returned stay valid.
 *  @param encoder the encoder; NULL does nothing */
HMC_API void hmc_encoder_destroy(hmc_encoder *encoder);

/**
 * Replace the encoder's settings.
 * @param encoder the encoder
 * @param options the new settings (copied), from hmc_encode_options_init() then changed
 * @return ::HMC_OK, or ::HMC_INVALID_ARGUMENT when a field is out of range
 *         (the settings are then unchanged)
 */
HMC_API hmc_status hmc_encoder_set_options(hmc_encoder *encoder, const hmc_encode_options *options);

/**
 * Let hmc_encoder_encode() use helper threads (see `hmc::EncodeOptions::threads`):
 * the same stream, byte for byte, in less wall-clock time. The setting
 * survives hmc_encoder_set_options().
 * @param encoder the encoder
 * @param threads threads an encode may use, the caller's included, 1..64
 *                (default 1: the caller's alone)
 * @return ::HMC_OK, or ::HMC_INVALID_ARGUMENT when `threads` is out of range
 */
HMC_API hmc_status hmc_encoder_set_threads(hmc_encoder *encoder, unsigned threads);

/**
 * Add preview levels below the independent-set levels (see
 * `hmc::EncodeOptions::preview_ratio`, and `hmc enc`, which uses 0.04 when
 * given no --levels): levels that keep one point per occupied octree cell
 * until a level holds at most `ratio` of the points. The setting survives
 * hmc_encoder_set_options().
 * @param encoder the encoder
 * @param ratio   0 <= ratio < 1 (default 0: none)
 * @return ::HMC_OK, or ::HMC_INVALID_ARGUMENT when `ratio` is out of range
 */
HMC_API hmc_status hmc_encoder_set_preview_ratio(hmc_encoder *encoder, double ratio);

/**
 * Quantize and encode a point set or mesh.
 *
 * The arrays stay the caller's and are only read. Connectivity is optional:
 * it tells the encoder the kind (when ::HMC_KIND_AUTO) and lets it classify
 * and tune, but only points are transmitted.
 *
 * @param encoder           the encoder
 * @param xyz               3 * `point_count` coordinates: x0 y0 z0 x1 y1 z1 ...
 * @param point_count       number of points, at least 1
 * @param triangles         3 * `triangle_count` 0-based indices into the points, or NULL
 * @param triangle_count    number of triangles (0 when `triangles` is NULL)
 * @param tetrahedra        4 * `tetrahedron_count` indices, or NULL
 * @param tetrahedron_count number of tetrahedra (0 when `tetrahedra` is NULL)
 * @param[out] out_bytes    receives the stream, allocated with the encoder's
 *                          allocator; free it with hmc_free()
 * @param[out] out_size     receives its size in bytes
 * @return ::HMC_OK; ::HMC_INVALID_ARGUMENT (NULL pointer, no points, an index
 *         out of range, NaN or infinite coordinates, ...); ::HMC_OUT_OF_MEMORY.
 *         On failure `*out_bytes` is NULL and `*out_size` 0.
 */
HMC_API hmc_status hmc_encoder_encode(hmc_encoder *encoder, const double *xyz, size_t point_count,
                                      const uint32_t *triangles, size_t triangle_count,
                                      const uint32_t *tetrahedra, size_t tetrahedron_count,
                                      uint8_t **out_bytes, size_t *out_size);

/** What the encoder's last failing call was about.
 *  @param encoder the encoder (NULL gives "")
 *  @return the message, "" if none; it belongs to the encoder and is valid
 *          until the encoder's next call (never NULL) */
HMC_API const char *hmc_encoder_message(const hmc_encoder *encoder);

/** What the encoder's last successful hmc_encoder_encode() noted about the
 *  stream (see `hmc::EncodeReport::notes`): fewer levels than requested and
 *  why, or points that span no volume, for which the decoder rebuilds no
 *  connectivity. One sentence per line, each ending in a newline.
 *  @param encoder the encoder (NULL gives "")
 *  @return the notes, "" if none or if the last encode failed; they belong
 *          to the encoder and are valid until its next call (never NULL) */
HMC_API const char *hmc_encoder_notes(const hmc_encoder *encoder);

/** @} */

/* ------------------------------------------------------------------------ */
/** @name Decoder */
/** @{ */

/** A decoder of one stream, given whole (hmc_decoder_decode()) or in pieces
 *  (hmc_decoder_feed(), hmc_decoder_finish()). */
typedef struct hmc_decoder hmc_decoder;

/**
 * Create a decoder with the default limits (2^26 points, 64 levels, 2^32
 * bytes), decoding down to the finest level, with reconstruction.
 * @param allocator memory functions for the handle, its input buffer and the
 *                  buffers it returns, copied; NULL for malloc, realloc and free
 * @return the decoder, or NULL when memory ran out or `allocator` lacks a function
 */
HMC_API hmc_decoder *hmc_decoder_create(const hmc_allocator *allocator);

/** Destroy a decoder. Buffers it returned stay valid.
 *  @param decoder the decoder; NULL does nothing */
HMC_API void hmc_decoder_destroy(hmc_decoder *decoder);

/**
 * Cap what the decoder accepts; a stream over a cap fails with
 * ::HMC_LIMIT_EXCEEDED before memory is allocated for it. Only before the
 * first hmc_decoder_feed() or hmc_decoder_decode().
 * @param decoder    the decoder
 * @param max_points most points of the finest level the stream declares
 * @param max_levels most levels the stream declares
 * @param max_bytes  most bytes in the stream (a streaming decoder fails as
 *                   soon as more have been fed)
 * @return ::HMC_OK, or ::HMC_INVALID_ARGUMENT when decoding has begun
 */
HMC_API hmc_status hmc_decoder_set_limits(hmc_decoder *decoder, uint64_t max_points, uint32_t max_levels,
                                          uint64_t max_bytes);

/**
 * Cap the decoder's working memory: the decoded levels' points and
 * simplices plus the Delaunay tetrahedralization and reconstruction of the
 * level being rebuilt, counted as 32 bytes per point and 160 per
 * tetrahedron. A level that needs more fails with ::HMC_LIMIT_EXCEEDED
 * before the memory is allocated, including a level whose points have an
 * unusually large tetrahedralization (n points can have n(n-3)/2
 * tetrahedra). The default, 2^31 bytes, rebuilds surfaces of about 1.5
 * million points. Only before the first hmc_decoder_feed() or
 * hmc_decoder_decode().
 * @param decoder    the decoder
 * @param max_memory the cap in bytes
 * @return ::HMC_OK, or ::HMC_INVALID_ARGUMENT when decoding has begun
 */
HMC_API hmc_status hmc_decoder_set_memory_limit(hmc_decoder *decoder, uint64_t max_memory);

/** The decoder's memory cap in bytes (hmc_decoder_set_memory_limit()).
 *  @param decoder the decoder
 *  @return the cap, or 0 when `decoder` is NULL */
HMC_API uint64_t hmc_decoder_memory_limit(const hmc_decoder *decoder);

/**
 * The decoder's limits.
 * @param decoder         the decoder
 * @param[out] max_points receives the points limit, or NULL
 * @param[out] max_levels receives the levels limit, or NULL
 * @param[out] max_bytes  receives the bytes limit, or NULL
 * @return ::HMC_OK, or ::HMC_INVALID_ARGUMENT when `decoder` is NULL
 */
HMC_API hmc_status hmc_decoder_get_limits(const hmc_decoder *decoder, uint64_t *max_points, uint32_t *max_levels,
                                          uint64_t *max_bytes);

/**
 * Stop after a level: finer levels are checked for chunk order only. A
 * stream cut before that level is complete is *truncated*
 * (::hmc_stream_info.truncated). Only before decoding begins.
 * @param decoder the decoder
 * @param level   the finest level wanted, 0 (the finest of the stream, the default) to 63
 * @return ::HMC_OK, or ::HMC_INVALID_ARGUMENT (negative, above 63, or decoding has begun)
 */
HMC_API hmc_status hmc_decoder_set_finest_level(hmc_decoder *decoder, int level);

/**
 * Whether to rebuild triangles or tetrahedra. Only before decoding begins.
 * @param decoder     the decoder
 * @param reconstruct non-zero (the default): rebuild them; 0: decode only
 *                    points (the side information is still validated)
 * @return ::HMC_OK, or ::HMC_INVALID_ARGUMENT when decoding has begun
 */
HMC_API hmc_status hmc_decoder_set_reconstruct(hmc_decoder *decoder, int reconstruct);

/**
 * With reconstruction on, whether the coarser levels are rebuilt too, or
 * only the finest level decoded (the requested one, or the last complete
 * one of a cut stream, rebuilt when hmc_decoder_finish() is called). The
 * coarser levels then have points only (no triangles or tetrahedra) and
 * decoding does less than half the work on multi-level streams; the finest
 * level's connectivity is the same. Only before decoding begins.
 * @param decoder the decoder
 * @param all     non-zero (the default): rebuild every level, as each one
 *                completes; 0: only the finest one
 * @return ::HMC_OK, or ::HMC_INVALID_ARGUMENT when decoding has begun
 */
HMC_API hmc_status hmc_decoder_set_rebuild_coarser_levels(hmc_decoder *decoder, int all);

/**
 * Let hmc_decoder_decode() use a second thread (see `hmc::DecodeOptions::threads`):
 * the same levels in less wall-clock time (one-level streams about a sixth
 * less, four-level streams about a quarter, on two cores). A decoder fed in
 * pieces (hmc_decoder_feed()) uses the caller's thread alone whatever this
 * says. Only before decoding begins.
 * @param decoder the decoder
 * @param threads threads a decode may use, the caller's included, 1..64
 *                (default 1; more than 2 are not used)
 * @return ::HMC_OK, or ::HMC_INVALID_ARGUMENT when `threads` is out of range
 *         or decoding has begun
 */
HMC_API hmc_status hmc_decoder_set_threads(hmc_decoder *decoder, unsigned threads);

/** When a decoder fed in pieces reports a defect of the stream. */
typedef enum hmc_error_order {
  /** At once: the hmc_decoder_feed() that meets the first defect in stream
   *  order fails with it (the default). */
  HMC_ERRORS_IN_STREAM_ORDER = 0,
  /** As hmc_decoder_decode() would for the whole stream (spec section 13:
   *  the size limit, then framing errors anywhere, then content errors):
   *  a defect is held, later bytes are still checked for framing, and
   *  hmc_decoder_finish() reports what ranks first. Exceeding the byte
   *  limit is reported at once. No level is completed after a defect. */
  HMC_ERRORS_AS_WHOLE = 1
} hmc_error_order;

/**
 * Choose when a decoder fed in pieces reports defects. Only before decoding
 * begins; hmc_decoder_decode() always reports as ::HMC_ERRORS_AS_WHOLE.
 * @param decoder the decoder
 * @param order   an ::hmc_error_order
 * @return ::HMC_OK, or ::HMC_INVALID_ARGUMENT (unknown order, or decoding has begun)
 */
HMC_API hmc_status hmc_decoder_set_error_order(hmc_decoder *decoder, int order);

/**
 * Decode a whole stream held in memory. Only on a decoder that has not
 * decoded or been fed yet.
 * @param decoder the decoder
 * @param data    the stream (only read during the call; NULL when `size` is 0)
 * @param size    its length in bytes
 * @return ::HMC_OK; ::HMC_INCOMPLETE when the stream stops before its end
 *         chunk but after a complete level; an error otherwise (the decoder
 *         is then failed; ::HMC_TRUNCATED when no level is complete)
 */
HMC_API hmc_status hmc_decoder_decode(hmc_decoder *decoder, const void *data, size_t size);

/**
 * Give the decoder the next bytes of the stream, in pieces of any size.
 * Every chunk the bytes complete is checked and decoded during the call; a
 * level whose last chunk arrives is complete when the call returns (see
 * hmc_decoder_level_count()).
 * @param decoder the decoder
 * @param data    the next bytes; only read during the call (the decoder
 *                copies the part of a chunk it still waits for); NULL when
 *                `size` is 0
 * @param size    how many (0 is allowed)
 * @return ::HMC_OK; an error in the stream (the decoder is then failed, and
 *         the levels completed before the error stay readable);
 *         ::HMC_INVALID_ARGUMENT after hmc_decoder_finish() or hmc_decoder_decode()
 */
HMC_API hmc_status hmc_decoder_feed(hmc_decoder *decoder, const void *data, size_t size);

/**
 * The stream has ended: no more bytes will come.
 * @param decoder the decoder
 * @return ::HMC_OK when the stream was complete (its end chunk was read);
 *         ::HMC_INCOMPLETE when it stopped after at least one complete level
 *         (the levels complete so far are the result, hmc_decoder_message()
 *         says where it stopped); ::HMC_TRUNCATED, an error, when no level
 *         was complete; the decoder's error if it had failed. Calling it
 *         again returns the same status.
 */
HMC_API hmc_status hmc_decoder_finish(hmc_decoder *decoder);

/**
 * The decoder's state.
 * @param decoder the decoder
 * @return ::HMC_OK while decoding or after a complete stream,
 *         ::HMC_INCOMPLETE after a cut stream, or the error it failed with
 *         (::HMC_INVALID_ARGUMENT for a NULL decoder)
 */
HMC_API hmc_status hmc_decoder_status(const hmc_decoder *decoder);

/** What the decoder's last non-OK status was about: an error, or where an
 *  incomplete stream stopped.
 *  @param decoder the decoder (NULL gives "")
 *  @return the message, "" if none; it belongs to the decoder and is valid
 *          until the decoder's next call (never NULL) */
HMC_API const char *hmc_decoder_message(const hmc_decoder *decoder);

/** The stream's header and progress. */
typedef struct hmc_stream_info {
  int header_ready;          /**< non-zero once `HEAD` and `SQNT` are read; the fields below up to `declared_points` are valid only then */
  int version_major;         /**< stream major version */
  int version_minor;         /**< stream minor version */
  int kind;                  /**< an ::hmc_kind */
  int bits;                  /**< q: the grid has 2^q cells per axis */
  double origin[3];          /**< position of grid point (0, 0, 0) */
  double step;               /**< grid spacing, the same on all three axes */
  uint32_t declared_levels;  /**< levels the stream declares */
  uint64_t declared_points[HMC_MAX_LEVELS]; /**< points per level, coarsest first; 0 past `declared_levels` */
  uint64_t bytes_consumed;   /**< bytes fed or decoded so far */
  uint32_t complete_levels;  /**< levels decoded so far (hmc_decoder_level_count()) */
  int ended;                 /**< non-zero once the end chunk is read */
  int truncated;             /**< non-zero when the stream was cut before the level asked for (after hmc_decoder_finish() or hmc_decoder_decode()) */
} hmc_stream_info;

/**
 * The stream's header and progress, at any time.
 * @param decoder   the decoder
 * @param[out] info receives them
 * @return ::HMC_OK, or ::HMC_INVALID_ARGUMENT when a pointer is NULL
 */
HMC_API hmc_status hmc_decoder_stream_info(const hmc_decoder *decoder, hmc_stream_info *info);

/** The number of complete levels so far.
 *  @param decoder the decoder
 *  @return the count; levels are numbered 0 (the coarsest) to count - 1 (the
 *          finest so far); 0 for a NULL decoder */
HMC_API size_t hmc_decoder_level_count(const hmc_decoder *decoder);

/** One decoded level's figures. */
typedef struct hmc_level_info {
  int lod;                    /**< level of detail, 0 = the finest level of the stream */
  uint64_t point_count;       /**< points of this level (all of them, not only the added ones) */
  uint64_t triangle_count;    /**< rebuilt triangles (kind surface) */
  uint64_t tetrahedron_count; /**< rebuilt tetrahedra (kind volume) */
  uint64_t stream_bytes;      /**< length of the stream prefix that decodes this level */
} hmc_level_info;

/**
 * Figures of a complete level.
 * @param decoder   the decoder
 * @param index     the level, 0 = the coarsest
 * @param[out] info receives them
 * @return ::HMC_OK, or ::HMC_INVALID_ARGUMENT (NULL pointer, index not below
 *         hmc_decoder_level_count())
 */
HMC_API hmc_status hmc_decoder_level_info(const hmc_decoder *decoder, size_t index, hmc_level_info *info);

/**
 * Grid points of a complete level, in canonical order (ascending x, then y,
 * then z): 3 * `*out_count` integers, each below 2^q.
 * @param decoder        the decoder
 * @param index          the level, 0 = the coarsest
 * @param[out] out_xyz   receives the array, allocated with the decoder's
 *                       allocator (NULL when empty); free it with hmc_free()
 * @param[out] out_count receives the number of points
 * @return ::HMC_OK, ::HMC_INVALID_ARGUMENT or ::HMC_OUT_OF_MEMORY
 */
HMC_API hmc_status hmc_decoder_level_points(const hmc_decoder *decoder, size_t index, uint32_t **out_xyz,
                                            size_t *out_count);

/**
 * Positions of a complete level's points (origin + grid * step, in the
 * order of hmc_decoder_level_points()): 3 * `*out_count` doubles.
 * @param decoder        the decoder
 * @param index          the level, 0 = the coarsest
 * @param[out] out_xyz   receives the array, allocated with the decoder's
 *                       allocator (NULL when empty); free it with hmc_free()
 * @param[out] out_count receives the number of points
 * @return ::HMC_OK, ::HMC_INVALID_ARGUMENT or ::HMC_OUT_OF_MEMORY
 */
HMC_API hmc_status hmc_decoder_level_positions(const hmc_decoder *decoder, size_t index, double **out_xyz,
                                               size_t *out_count);

/**
 * Rebuilt triangles of a complete level (kind surface; none otherwise or
 * without reconstruction): 3 * `*out_count` indices into the level's
 * points, counter-clockwise seen from outside, in canonical order.
 * @param decoder          the decoder
 * @param index            the level, 0 = the coarsest
 * @param[out] out_indices receives the array, allocated with the decoder's
 *                         allocator (NULL when empty); free it with hmc_free()
 * @param[out] out_count   receives the number of triangles
 * @return ::HMC_OK, ::HMC_INVALID_ARGUMENT or ::HMC_OUT_OF_MEMORY
 */
HMC_API hmc_status hmc_decoder_level_triangles(const hmc_decoder *decoder, size_t index, uint32_t **out_indices,
                                               size_t *out_count);

/**
 * Rebuilt tetrahedra of a complete level (kind volume): 4 * `*out_count`
 * indices into the level's points, positively oriented, in canonical order.
 * @param decoder          the decoder
 * @param index            the level, 0 = the coarsest
 * @param[out] out_indices receives the array, allocated with the decoder's
 *                         allocator (NULL when empty); free it with hmc_free()
 * @param[out] out_count   receives the number of tetrahedra
 * @return ::HMC_OK, ::HMC_INVALID_ARGUMENT or ::HMC_OUT_OF_MEMORY
 */
HMC_API hmc_status hmc_decoder_level_tetrahedra(const hmc_decoder *decoder, size_t index, uint32_t **out_indices,
                                                size_t *out_count);

/** @} */

#ifdef __cplusplus
}
#endif

#endif /* HMC_HMC_H */
