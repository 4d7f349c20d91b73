// SPDX-License-Identifier: AGPL-3.0-or-later
// Shared pieces of the hmc command line: argument parsing, exit codes,
// JSON output, and mapping library errors to exit codes and messages.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "hmc/codec.hpp"
#include "hmc/meshio.hpp"
#include "hmc/status.hpp"

namespace hmc::cli {

/// Exit codes (documented in README and `hmc help`).
enum Exit : int {
  kOk = 0,
  kUsage = 1,        // bad command line
  kInput = 2,        // input file unreadable, malformed or unsuitable
  kStream = 3,       // invalid or corrupt HMC stream
  kOutput = 4,       // output could not be written
  kLimit = 5,        // a decoder limit was exceeded
  kMemory = 6,       // out of memory
  kInternal = 70,    // bug
};

/// What a failed operation was doing, which decides its exit code.
enum class Stage { input, output };

/// Exit code for a failed operation: stream errors are kStream whatever the
/// stage; otherwise input problems are kInput, and output problems kOutput
/// (kUsage when the output was refused, e.g. it would overwrite the input).
int exit_code(const Error& e, Stage stage);

/// Print "hmc: <what>: <error>" to stderr and return the exit code.
int report(const std::string& what, const Error& e, Stage stage);

/// Minimal argument parser: positional arguments, --flag and --opt VALUE
/// (also --opt=VALUE). Options are declared up front so typos are errors.
class Args {
 public:
  Args(int argc, char** argv, int first, const std::vector<std::string>& flags,
       const std::vector<std::string>& options);
  bool ok() const { return error_.empty(); }
  const std::string& error() const { return error_; }
  bool flag(const std::string& name) const { return flags_.count(name) != 0; }
  bool has(const std::string& name) const { return values_.count(name) != 0; }
  std::string get(const std::string& name, const std::string& def = {}) const;
  /// Integer option within [lo, hi]; sets error() on failure.
  long long get_int(const std::string& name, long long def, long long lo, long long hi);
  const std::vector<std::string>& positional() const { return positional_; }

 private:
  std::map<std::string, std::string> values_;
  std::map<std::string, bool> flags_;
  std::vector<std::string> positional_;
  std::string error_;
};

/// The files and directories a command has written so far. Unless
/// commit() is called, the destructor removes them, so a command that fails
/// part-way leaves nothing behind.
class Outputs {
 public:
  Outputs() = default;
  Outputs(const Outputs&) = delete;
  Outputs& operator=(const Outputs&) = delete;
  ~Outputs();
  /// Record a path written by this run (a directory only if this run created it).
  void add(const std::string& path) { paths_.push_back(path); }
  void commit() { paths_.clear(); }

 private:
  std::vector<std::string> paths_;
};

/// True if `path` exists (file or directory).
bool exists(const std::string& path);

/// `--threads N` for enc and dec (EncodeOptions/DecodeOptions::threads):
/// by default 2 where the machine has two hardware threads, else 1; the
/// output is the same either way.
unsigned threads_option(Args& a);

/// The `--fidelity` names of enc and analyze: rule, topology, shape, exact.
/// False (and `out` untouched) for any other name.
bool parse_fidelity(const std::string& name, Fidelity& out);

/// `--format F` of enc and tile-split: the reader to use whatever IN's
/// extension, io::Format::automatic when absent. False, after a message
/// naming `command`, for an unknown name.
bool format_option(Args& a, const char* command, io::Format& out);

/// A share of the points (`--ratio`, `--preview-ratio`): a number in (0, 1]
/// (Share::positive) or in [0, 1) (Share::below_one), read into `out` when
/// the option is given. Returns the message for a bad value, else empty.
enum class Share { positive, below_one };
std::string share_option(const Args& a, const std::string& name, Share range, double& out);

/// A tiny JSON writer producing one object, keys in insertion order.
class Json {
 public:
  Json& key(const std::string& k);
  Json& value(const std::string& s);
  Json& value(const char* s) { return value(std::string(s)); }
  Json& value(double d);
  Json& value(std::uint64_t u);
  Json& value(std::int64_t i);
  Json& value(int i) { return value(static_cast<std::int64_t>(i)); }
  Json& value(bool b);
  Json& begin_object();
  Json& end_object();
  Json& begin_array();
  Json& end_array();
  std::string str() const { return out_ + "\n"; }

 private:
  void sep();
  std::string out_;
  std::vector<bool> first_{true};
  bool after_key_ = false;
};

std::string json_escape(const std::string& s);

/// One level of a canonical dump.
struct DumpLevel {
  int lod = 0;
  const std::vector<GridPoint>* points = nullptr;
  const std::vector<Triangle>* triangles = nullptr;       // surface kind
  const std::vector<Tetrahedron>* tetrahedra = nullptr;   // volume kind
  bool points_only = false;                                // connectivity not rebuilt: no .simplices
};

/// Canonical dump (spec "Canonical dump"): header.json, level-K.points and,
/// for surface and volume kinds, level-K.simplices. Written atomically: into
/// a fresh directory renamed into place, or file by file into an existing
/// directory, removing what was written on failure.
Result<Done> write_canonical_dump(const std::string& dir, Kind kind, const ScalarQuantizer& q,
                                  const std::vector<std::uint64_t>& declared_points,
                                  const std::vector<DumpLevel>& levels);

/// Comma-separated numbers ("1,2.5,-3"); empty when any item is not a
/// finite number.
std::vector<double> parse_doubles(const std::string& s);

/// Format a double as C printf "%.17g".
std::string g17(double v);

}  // namespace hmc::cli
