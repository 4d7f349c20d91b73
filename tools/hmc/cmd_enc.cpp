// SPDX-License-Identifier: AGPL-3.0-or-later
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <unistd.h>
#include <optional>
#include <string>

#include "cli.hpp"
#include "hmc/codec.hpp"
#include "hmc/meshio.hpp"

namespace hmc::cli {

namespace {

// hmc enc's preview when neither --levels nor --preview-ratio is given: on
// the 13 shared models a coarsest level of 0.7-3.9 % of the points in
// 1.9-5.7 % of the bytes, the whole stream 1.14 times the 1-level one.
constexpr double kDefaultPreview = 0.04;

std::optional<Kind> parse_kind(const std::string& s, bool& ok) {
  ok = true;
  if (s.empty() || s == "auto") return std::nullopt;
  if (s == "points") return Kind::points;
  if (s == "surface") return Kind::surface;
  if (s == "volume") return Kind::volume;
  ok = false;
  return std::nullopt;
}

}  // namespace

int cmd_enc(int argc, char** argv) {
  Args a(argc, argv, 2, {"--json", "--no-info", "--fast-decode", "--fit-coarse"},
         {"-o", "--output", "--bits", "--kind", "--canonical", "--format", "--fidelity", "--levels", "--ratio", "--preview-ratio",
          "--boundary", "--optimizer", "--vq-bits", "--vq-residual", "--threads", "--lattice", "--seal-box",
           "--tolerance-diagonal"});
  EncodeOptions opt;
  opt.bits = static_cast<int>(a.get_int("--bits", 12, 1, 21));
  bool kind_ok = true;
  opt.kind = parse_kind(a.get("--kind"), kind_ok);
  if (!kind_ok) {
    std::fprintf(stderr, "hmc enc: --kind must be points, surface, volume or auto\n");
    return kUsage;
  }
  opt.write_info = !a.flag("--no-info");
  opt.fast_decode = a.flag("--fast-decode");
  opt.fit_coarse_levels = a.flag("--fit-coarse");
  opt.threads = threads_option(a);
  opt.levels = static_cast<int>(a.get_int("--levels", 1, 1, 64));
  if (a.has("--vq-bits") || a.has("--vq-residual")) {
    // Named so that a script written for spec 0.26 and earlier learns why.
    std::fprintf(stderr,
                 "hmc enc: --vq-bits and --vq-residual were removed with the lossy refinement coder (spec 0.27):\n"
                 "         coding every point exactly at a smaller --bits reached a higher PSNR at the same rate\n"
                 "         on every model measured (bench/results/rd.md)\n");
    return kUsage;
  }
  // The default stream is a preview that arrives first: with neither
  // --levels nor --preview-ratio, the finest level plus octree-cell levels
  // down to kDefaultPreview of the points (bench/results/preview.md). The
  // library's EncodeOptions keeps levels = 1, preview_ratio = 0: a program
  // gets exactly the levels it asks for.
  if (!a.has("--levels") && !a.has("--preview-ratio")) opt.preview_ratio = kDefaultPreview;
  for (const std::string& bad : {share_option(a, "--ratio", Share::positive, opt.removal_ratio),
                                 share_option(a, "--preview-ratio", Share::below_one, opt.preview_ratio)})
    if (!bad.empty()) {
      std::fprintf(stderr, "hmc enc: %s\n", bad.c_str());
      return kUsage;
    }
  if (a.has("--lattice")) {
    // ox,oy,oz,step (the grid is one step on all axes; ox,oy,oz,s,s,s is accepted too).
    const auto v = parse_doubles(a.get("--lattice"));
    const bool six_equal = v.size() == 6 && v[3] == v[4] && v[4] == v[5];
    if (!(v.size() == 4 || six_equal)) {
      std::fprintf(stderr, "hmc enc: --lattice takes ox,oy,oz,step (one step for all three axes), got '%s'\n",
                   a.get("--lattice").c_str());
      return kUsage;
    }
    opt.lattice = EncodeOptions::Lattice{{v[0], v[1], v[2]}, v[3]};
  }
  if (a.has("--seal-box")) {
    // x0,y0,z0,x1,y1,z1: whole lattice coordinates, x0 < x1 <= 2^q per axis
    // (the encoder checks the bounds against --bits).
    const auto v = parse_doubles(a.get("--seal-box"));
    bool whole = v.size() == 6;
    std::array<std::uint32_t, 6> box{};
    for (std::size_t i = 0; whole && i < 6; ++i) {
      whole = v[i] >= 0 && v[i] <= double(1u << 21) && v[i] == std::floor(v[i]);
      if (whole) box[i] = static_cast<std::uint32_t>(v[i]);
    }
    for (int ax = 0; whole && ax < 3; ++ax) whole = box[ax] < box[3 + ax] && box[3 + ax] <= (1u << opt.bits);
    if (!whole) {
      std::fprintf(stderr,
                   "hmc enc: --seal-box takes x0,y0,z0,x1,y1,z1 in lattice coordinates, 0 <= x0 < x1 <= 2^%d, got '%s'\n",
                   opt.bits, a.get("--seal-box").c_str());
      return kUsage;
    }
    opt.seal_box = box;
  }
  if (a.has("--tolerance-diagonal")) {
    const auto v = parse_doubles(a.get("--tolerance-diagonal"));
    if (v.size() != 1 || !(v[0] >= 0) || !std::isfinite(v[0])) {
      std::fprintf(stderr, "hmc enc: --tolerance-diagonal takes one length >= 0 in lattice units, got '%s'\n",
                   a.get("--tolerance-diagonal").c_str());
      return kUsage;
    }
    opt.tolerance_diagonal = v[0];
  }
  const std::string bm = a.get("--boundary", "linear");
  if (bm == "constant") opt.boundary_mode = BoundaryMode::constant;
  else if (bm == "linear") opt.boundary_mode = BoundaryMode::linear;
  else if (bm == "adaptive") opt.boundary_mode = BoundaryMode::adaptive;
  else {
    std::fprintf(stderr, "hmc enc: --boundary must be constant, linear or adaptive\n");
    return kUsage;
  }
  const std::string om = a.get("--optimizer", "best");
  if (om == "forward") opt.optimizer = Optimizer::forward;
  else if (om == "backward") opt.optimizer = Optimizer::backward;
  else if (om == "greedy") opt.optimizer = Optimizer::greedy;
  else if (om == "best") opt.optimizer = Optimizer::best;
  else {
    std::fprintf(stderr, "hmc enc: --optimizer must be forward, backward, greedy or best\n");
    return kUsage;
  }
  const std::string fid = a.get("--fidelity", "shape");
  if (!parse_fidelity(fid, opt.fidelity)) {
    std::fprintf(stderr, "hmc enc: --fidelity must be rule, topology, shape or exact\n");
    return kUsage;
  }
  const std::string out = a.has("-o") ? a.get("-o") : a.get("--output");
  if (!a.ok() || a.positional().size() != 1 || (out.empty() && !a.has("--canonical"))) {
    std::fprintf(stderr,
                 "hmc enc: %s\n"
                 "usage: hmc enc IN -o OUT.hmc [--format F] [--bits Q] [--kind K] [--levels N] [--ratio R] [--preview-ratio R]\n"
                 "                  [--boundary M] [--optimizer O] [--fidelity F] [--fit-coarse]\n"
                 "                  [--fast-decode] [--lattice OX,OY,OZ,STEP] [--seal-box X0,Y0,Z0,X1,Y1,Z1]\n"
                 "                  [--tolerance-diagonal L]\n"
                 "                  [--canonical DIR] [--no-info] [--threads N] [--json]\n"
                 "                  (hmc --help says what each does)\n",
                 a.ok() ? "need one input file and -o OUT.hmc" : a.error().c_str());
    return kUsage;
  }
  const std::string in = a.positional()[0];
  io::Format in_format;
  if (!format_option(a, "hmc enc", in_format)) return kUsage;

  // Progress on a terminal only: scripts reading stderr get no noise.
  const bool tty = isatty(fileno(stderr)) != 0;
  if (tty)
    opt.progress = [](int level, double done) {
      std::fprintf(stderr, "\rhmc: encoding, level %d, %3.0f%%", level, 100 * done);
      std::fflush(stderr);
    };
  const auto t0 = std::chrono::steady_clock::now();
  auto mesh = io::read_mesh(in, in_format);
  if (!mesh) return report("cannot read " + in, mesh.error(), Stage::input);
  const auto t1 = std::chrono::steady_clock::now();
  auto enc = encode(mesh.value(), opt);
  if (!enc) return report("cannot encode " + in, enc.error(), Stage::input);
  const auto t2 = std::chrono::steady_clock::now();
  if (tty) std::fprintf(stderr, "\r%40s\r", "");
  const Encoded& e = enc.value();
  Outputs written;
  if (!out.empty()) {
    auto w = io::write_file_atomic(out, std::string_view(reinterpret_cast<const char*>(e.bytes.data()), e.bytes.size()), in);
    if (!w) return report("cannot write " + out, w.error(), Stage::output);
    written.add(out);
  }
  if (a.has("--canonical")) {
    const std::string dir = a.get("--canonical");
    const bool existed = exists(dir);
    std::vector<std::uint64_t> declared;
    std::vector<DumpLevel> levels;
    for (const auto& l : e.report.levels) declared.push_back(l.points);
    for (const auto& l : e.levels) levels.push_back({l.lod, &l.points, &l.triangles, &l.tetrahedra});
    auto w = write_canonical_dump(dir, e.report.kind, e.report.quantizer, declared, levels);
    if (!w) return report("cannot write the canonical dump", w.error(), Stage::output);
    if (!existed) written.add(dir);
  }
  written.commit();
  const double read_s = std::chrono::duration<double>(t1 - t0).count();
  const double enc_s = std::chrono::duration<double>(t2 - t1).count();
  const EncodeReport& r = e.report;
  const double bpp = r.distinct_points ? 8.0 * static_cast<double>(r.total_bytes) / static_cast<double>(r.distinct_points) : 0;
  if (a.flag("--json")) {
    Json j;
    j.begin_object();
    j.key("input").value(in).key("output").value(out);
    j.key("kind").value(kind_name(r.kind)).key("q").value(r.quantizer.bits);
    j.key("input_points").value(r.input_points).key("distinct_points").value(r.distinct_points);
    j.key("duplicates_merged").value(r.duplicates_merged);
    j.key("bytes").value(r.total_bytes).key("bits_per_point").value(bpp);
    j.key("read_seconds").value(read_s).key("encode_seconds").value(enc_s);
    j.key("levels").begin_array();
    for (const auto& l : r.levels) {
      j.begin_object();
      j.key("level").value(l.lod).key("points").value(l.points).key("new_points").value(l.new_points);
      j.key("layer_bytes").value(l.layer_bytes).key("side_bytes").value(l.side_bytes);
      j.key("stream_bytes").value(l.stream_bytes);
      j.key("label_corrections").value(l.label_corrections).key("rule_mismatches").value(l.rule_mismatches);
      j.key("simplices").value(l.simplices);
      j.key("boundary_removed").value(l.boundary_removed).key("inner_removed").value(l.inner_removed);
      j.key("classification_disagreements").value(l.classification_disagreements);
      j.key("dmax").value(l.dmax).key("optimizer").value(optimizer_name(l.optimizer));
      j.key("mean_importance_retained").value(l.mean_importance_retained);
      j.key("layers").begin_array();
      for (auto n : l.layer_sizes) j.value(n);
      j.end_array();
      j.key("coder").value(l.coder);
      j.end_object();
    }
    j.end_array();
    j.key("triangles").value(static_cast<std::uint64_t>(e.triangles.size()));
    j.key("tetrahedra").value(static_cast<std::uint64_t>(e.tetrahedra.size()));
    j.key("notes").begin_array();
    for (const auto& n : r.notes) j.value(n);
    j.end_array();
    j.end_object();
    std::fputs(j.str().c_str(), stdout);
  } else {
    std::printf("%s: %s, %llu points (%llu duplicates merged after quantization), q = %d\n", in.c_str(),
                kind_name(r.kind), static_cast<unsigned long long>(r.distinct_points),
                static_cast<unsigned long long>(r.duplicates_merged), r.quantizer.bits);
    std::printf("%6s %10s %10s %12s %11s %12s %12s\n", "level", "points", "new", "layer bytes", "side bytes",
                "corrections", "bits/point");
    for (const auto& l : r.levels)
      std::printf("%6d %10llu %10llu %12llu %11llu %12llu %12.3f\n", l.lod, static_cast<unsigned long long>(l.points),
                  static_cast<unsigned long long>(l.new_points), static_cast<unsigned long long>(l.layer_bytes),
                  static_cast<unsigned long long>(l.side_bytes), static_cast<unsigned long long>(l.label_corrections),
                  8.0 * static_cast<double>(l.stream_bytes) / static_cast<double>(l.points));
    if (r.kind != Kind::points)
      std::printf("rebuilt by the decoder: %zu triangles, %zu tetrahedra\n", e.triangles.size(), e.tetrahedra.size());
    std::printf("%s: %llu bytes, %.3f bits per point (read %.3f s, encode %.3f s)\n", out.empty() ? "(no output)" : out.c_str(),
                static_cast<unsigned long long>(r.total_bytes), bpp, read_s, enc_s);
    for (const auto& n : r.notes) std::printf("note: %s\n", n.c_str());
  }
  return kOk;
}

}  // namespace hmc::cli
