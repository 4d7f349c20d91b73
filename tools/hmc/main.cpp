// SPDX-License-Identifier: AGPL-3.0-or-later
// hmc — the command line of the HMC codec. See `hmc help`.
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include "cli.hpp"
#include "hmc/codec.hpp"
#include "hmc/meshio.hpp"

namespace hmc::cli {
int cmd_enc(int argc, char** argv);
int cmd_dec(int argc, char** argv);
int cmd_info(int argc, char** argv);
int cmd_gen(int argc, char** argv);
int cmd_quality(int argc, char** argv);
int cmd_analyze(int argc, char** argv);
int cmd_tile(int argc, char** argv);
int cmd_tile_split(int argc, char** argv);
}  // namespace hmc::cli

namespace {

const char* kUsage =
    "usage: hmc <command> [options]\n"
    "\n"
    "commands:\n"
    "  enc IN -o OUT.hmc   encode a mesh or point file (PLY, OBJ, OFF, XYZ, STL, TetGen .node/.ele,\n"
    "                      MEDIT .mesh, Gmsh .msh, VTK) into an HMC stream\n"
    "      --bits Q            quantization bits per axis, 1..21 (default 12)\n"
    "      --kind K            points | surface | volume (default: detected from the input)\n"
    "      --format F          read IN as this format (ply, obj, off, xyz, stl, node, mesh, msh, vtk)\n"
    "                          whatever its extension\n"
    "      --levels N          levels of detail by independent sets, 1..64; fewer when a level has\n"
    "                          nothing left to remove (a note says so). Default: 1 level and\n"
    "                          --preview-ratio 0.04; with --levels alone, no preview levels\n"
    "      --ratio R           share of a level's vertices removed per level, (0,1] (default 0.3)\n"
    "      --preview-ratio R   below the --levels levels, levels of one point per octree cell, each at\n"
    "                          most half the next finer one, down to R of the points, 0 <= R < 1\n"
    "                          (default 0.04 without --levels, else 0: none)\n"
    "      --boundary M        constant | linear | adaptive Dmax (default linear)\n"
    "      --optimizer O       forward | backward | greedy | best, for volume interiors (default best)\n"
    "      --fidelity F        rule | topology | shape | exact reconstruction side information (default shape)\n"
    "      --fit-coarse        coarser levels follow the input surface too (with --fidelity's corrections):\n"
    "                          previews that look like the model, for about 12 % more bytes\n"
    "      --lattice OX,OY,OZ,STEP  quantize onto this grid (point i at origin + i * STEP, q = --bits)\n"
    "                          instead of one fitted to the input's box; every point must fall on it\n"
    "      --seal-box X0,Y0,Z0,X1,Y1,Z1  a tile's box (half-open, lattice units): the reconstruction\n"
    "                          ignores hull faces between points outside it (hmc tile sets it)\n"
    "      --tolerance-diagonal L  the length (lattice units) whose 1/1000 is how far a face may stray\n"
    "                          from the input before it is dropped (default: the points' box\n"
    "                          diagonal; hmc tile gives each tile the whole model's)\n"
    "      --canonical DIR     also write the canonical dump of every level\n"
    "      --fast-decode       plain octrees that decode without neighbour searches: points decode\n"
    "                          tens of times faster, streams get larger (surfaces by a fifth to a half)\n"
    "      --no-info           omit the ancillary info chunk\n"
    "      --threads N         1: encode on one thread; 2 or more (default where the machine has two):\n"
    "                          helpers take the point layers and half of some batches, the same stream\n"
    "      --json              print the report as JSON\n"
    "  dec IN.hmc -o OUT   decode the finest level (or --level K) to PLY, OBJ, XYZ, VTK, VTU, ...;\n"
    "                      with -o alone only that level's connectivity is rebuilt\n"
    "      --level K           stop at level K (0 = finest)\n"
    "      --all-levels DIR    write every decoded level to DIR/level-K.<ext> (--ext; default ply,\n"
    "                          vtk for tetrahedra)\n"
    "      --canonical DIR     write the canonical dump (header.json, level-K.points)\n"
    "      --coords C          binary PLY/VTK coordinates: float, double, or auto (default: float when\n"
    "                          that moves no coordinate by more than 1/16 of the quantization step)\n"
    "      --rebuild R         all | finest: rebuild every level's connectivity, or only the finest\n"
    "                          decoded one (default: finest with -o alone, else all)\n"
    "      --points-only       decode points only: no reconstruction (RCON is still checked)\n"
    "      --max-points N      refuse streams with more points (default 67108864)\n"
    "      --max-levels N      refuse streams that declare more levels (default 64)\n"
    "      --max-memory MIB    refuse levels needing more working memory (default 2048 MiB)\n"
    "      --threads N         1: decode on one thread; 2 or more (default where the machine has two):\n"
    "                          a second thread searches the base layer's neighbours ahead, and\n"
    "                          reconstructs each level (--rebuild all) or tetrahedralizes the\n"
    "                          coarser levels ahead (finest) while the next level decodes\n"
    "      --json              print a summary as JSON\n"
    "  info IN.hmc         list chunks and levels [--json]\n"
    "  quality MESH        element quality (thesis 3.5): triangle angle and edge ratio, QT1-QT4 [--json]\n"
    "  analyze IN          the thesis' per-level tables (4.1-4.12) for a mesh or a stream [--json]\n"
    "      a mesh is encoded with the enc options --bits --kind --levels (here 4 unless given) --ratio\n"
    "      --boundary --fidelity; --optimizer takes a comma-separated list: a volume is encoded once\n"
    "      per entry (forward,backward,greedy unless given); --classes C  MEC classes (16 unless given)\n"
    "  tile IN -o TILED    a tiled model (spec/tiles.md): tiles.json + one stream per tile, encoded as\n"
    "                      independent jobs on Dask (a local cluster, or --scheduler ADDRESS); hmc tile --help\n"
    "  tile-split IN -o WORKDIR  the per-tile inputs and plan.json that hmc tile encodes\n"
    "      --tile-points N  --bits Q  --margin M (lattice units; default 4 mean edge lengths)  --kind K\n"
    "      (dec and info take a tiled model's directory too: dec TILED --canonical DIR | -o OUT\n"
    "       [--region xmin,ymin,zmin,xmax,ymax,zmax] [--level K]; info TILED)\n"
    "  gen SAMPLE -o OUT   write a generated sample: torus, sphere (surfaces), ball, lattice (points)\n"
    "      --vertices N        about N vertices (default 36450)    --seed S   random seed\n"
    "      --ascii             ASCII PLY (default binary)\n"
    "  version             print the library version\n"
    "\n"
    "exit codes: 0 ok, 1 usage, 2 input file error, 3 invalid or corrupt stream,\n"
    "            4 output error, 5 decoder limit exceeded, 6 out of memory, 70 internal error\n";

}  // namespace

int main(int argc, char** argv) {
  // A full disk or a file-size limit must surface as a failed write (exit 4,
  // nothing left behind), not as a SIGXFSZ kill halfway through a file.
  std::signal(SIGXFSZ, SIG_IGN);
#if defined(__GLIBC__)
  // The codec allocates and frees many buffers of 0.1 to 30 MB per level
  // (tetrahedra, adjacency, per-vertex lists). Mapped afresh each time,
  // every page of them faults again: with glibc's mmap threshold fixed at
  // 128 KiB, about a third of a 4-level decode's CPU time went to page
  // faults. So buffers below 32 MiB (glibc's largest threshold) come from
  // the heap, and freed space is given back only beyond 64 MiB at its top.
  // Against the 128 KiB threshold (one thread, paired medians of 3,
  // 2026-12-01): every level of the bunny's 4-level stream decodes in 0.83 s
  // of CPU instead of 1.26 for 30.6 MB of peak memory instead of 24.7;
  // hand_tetgen's in 0.61 s instead of 0.99 (31.7 MB, 25.0); its 4-level
  // encode takes 3.18 s instead of 5.10 (54.5 MB, 50.7), the bunny's 4.35
  // instead of 6.28 (60.4 MB, 55.1).
  mallopt(M_MMAP_THRESHOLD, 32 * 1024 * 1024);
  mallopt(M_TRIM_THRESHOLD, 64 * 1024 * 1024);
#endif
  if (argc < 2) {
    std::fputs(kUsage, stderr);
    return hmc::cli::kUsage;
  }
  const std::string cmd = argv[1];
  if (cmd == "tile") return hmc::cli::cmd_tile(argc, argv);  // its own --help (tools/hmc_tile.py)
  for (int i = 2; i < argc; ++i)
    if (std::strcmp(argv[i], "--help") == 0 || std::strcmp(argv[i], "-h") == 0) {
      std::fputs(kUsage, stdout);
      return 0;
    }
  if (cmd == "enc") return hmc::cli::cmd_enc(argc, argv);
  if (cmd == "dec") return hmc::cli::cmd_dec(argc, argv);
  if (cmd == "info") return hmc::cli::cmd_info(argc, argv);
  if (cmd == "gen") return hmc::cli::cmd_gen(argc, argv);
  if (cmd == "quality") return hmc::cli::cmd_quality(argc, argv);
  if (cmd == "analyze") return hmc::cli::cmd_analyze(argc, argv);
  if (cmd == "tile-split") return hmc::cli::cmd_tile_split(argc, argv);
  if (cmd == "version" || cmd == "--version") {
    std::printf("hmc %s\n", hmc::version_string());
    return 0;
  }
  if (cmd == "help" || cmd == "--help" || cmd == "-h") {
    std::fputs(kUsage, stdout);
    return 0;
  }
  std::fprintf(stderr, "hmc: unknown command '%s'\n\n%s", cmd.c_str(), kUsage);
  return hmc::cli::kUsage;
}
