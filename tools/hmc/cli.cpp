// SPDX-License-Identifier: AGPL-3.0-or-later
#include "cli.hpp"

#include <cerrno>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <random>
#include <thread>
#include <algorithm>

#include "hmc/meshio.hpp"

namespace hmc::cli {

namespace fs = std::filesystem;

int exit_code(const Error& e, Stage stage) {
  switch (e.status) {
    case Status::ok: return kOk;
    case Status::bad_magic:
    case Status::unsupported_version:
    case Status::crc_mismatch:
    case Status::truncated:
    case Status::bad_chunk:
    case Status::bad_header:
    case Status::bad_huffman_table:
    case Status::bad_layer: return kStream;
    case Status::limit_exceeded: return kLimit;
    case Status::out_of_memory: return kMemory;
    case Status::internal_error: return kInternal;
    case Status::invalid_argument: return stage == Stage::input ? kInput : kUsage;
    case Status::parse_error:
    case Status::unsupported_format: return stage == Stage::input ? kInput : kOutput;
    case Status::io_error: return stage == Stage::input ? kInput : kOutput;
  }
  return kInternal;
}

int report(const std::string& what, const Error& e, Stage stage) {
  std::fprintf(stderr, "hmc: %s: %s\n", what.c_str(), e.to_string().c_str());
  return exit_code(e, stage);
}

Args::Args(int argc, char** argv, int first, const std::vector<std::string>& flags,
           const std::vector<std::string>& options) {
  auto known = [](const std::vector<std::string>& v, const std::string& s) {
    for (const auto& x : v)
      if (x == s) return true;
    return false;
  };
  for (int i = first; i < argc; ++i) {
    std::string a = argv[i];
    if (a.size() > 1 && a[0] == '-' && a != "-") {
      std::string name = a, val;
      bool has_val = false;
      if (auto eq = a.find('='); eq != std::string::npos) {
        name = a.substr(0, eq);
        val = a.substr(eq + 1);
        has_val = true;
      }
      if (known(flags, name) && !has_val) {
        flags_[name] = true;
      } else if (known(options, name)) {
        if (!has_val) {
          if (i + 1 >= argc) {
            error_ = "option " + name + " needs a value";
            return;
          }
          val = argv[++i];
        }
        values_[name] = val;
      } else {
        error_ = "unknown option " + a;
        return;
      }
    } else {
      positional_.push_back(a);
    }
  }
}

std::string Args::get(const std::string& name, const std::string& def) const {
  auto it = values_.find(name);
  return it == values_.end() ? def : it->second;
}

long long Args::get_int(const std::string& name, long long def, long long lo, long long hi) {
  auto it = values_.find(name);
  if (it == values_.end()) return def;
  char* end = nullptr;
  errno = 0;
  long long v = std::strtoll(it->second.c_str(), &end, 10);
  if (errno || end == it->second.c_str() || *end || v < lo || v > hi) {
    error_ = name + " must be an integer from " + std::to_string(lo) + " to " + std::to_string(hi) + ", got '" +
             it->second + "'";
    return def;
  }
  return v;
}

Outputs::~Outputs() {
  std::error_code ec;
  for (auto it = paths_.rbegin(); it != paths_.rend(); ++it) fs::remove_all(*it, ec);
}

bool exists(const std::string& path) {
  std::error_code ec;
  return fs::exists(path, ec);
}

unsigned threads_option(Args& a) {
  return static_cast<unsigned>(a.get_int("--threads", std::thread::hardware_concurrency() >= 2 ? 2 : 1, 1, 1024));
}

bool parse_fidelity(const std::string& name, Fidelity& out) {
  if (name == "rule") out = Fidelity::rule;
  else if (name == "topology") out = Fidelity::topology;
  else if (name == "shape") out = Fidelity::shape;
  else if (name == "exact") out = Fidelity::exact;
  else return false;
  return true;
}

bool format_option(Args& a, const char* command, io::Format& out) {
  out = io::Format::automatic;
  if (!a.has("--format")) return true;
  out = io::format_from_path("x." + a.get("--format"));
  if (out != io::Format::automatic) return true;
  std::fprintf(stderr, "%s: unknown --format '%s'\n", command, a.get("--format").c_str());
  return false;
}

std::string share_option(const Args& a, const std::string& name, Share range, double& out) {
  if (!a.has(name)) return {};
  const std::string r = a.get(name);
  char* end = nullptr;
  const double v = std::strtod(r.c_str(), &end);
  const bool in = range == Share::positive ? v > 0 && v <= 1 : v >= 0 && v < 1;
  if (end == r.c_str() || *end || !in)
    return name + " must be a number in " + (range == Share::positive ? "(0, 1]" : "[0, 1)") + ", got '" + r + "'";
  out = v;
  return {};
}

std::string json_escape(const std::string& s) {
  std::string o = "\"";
  for (unsigned char c : s) {
    switch (c) {
      case '"': o += "\\\""; break;
      case '\\': o += "\\\\"; break;
      case '\n': o += "\\n"; break;
      case '\t': o += "\\t"; break;
      case '\r': o += "\\r"; break;
      default:
        if (c < 0x20) {
          char buf[8];
          std::snprintf(buf, sizeof buf, "\\u%04x", c);
          o += buf;
        } else {
          o += static_cast<char>(c);
        }
    }
  }
  return o + "\"";
}

std::string g17(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

void Json::sep() {
  if (after_key_) {
    after_key_ = false;
    return;
  }
  if (!first_.back()) out_ += ", ";
  first_.back() = false;
}
Json& Json::key(const std::string& k) {
  sep();
  out_ += json_escape(k) + ": ";
  after_key_ = true;
  return *this;
}
Json& Json::value(const std::string& s) {
  sep();
  out_ += json_escape(s);
  return *this;
}
Json& Json::value(double d) {
  sep();
  out_ += std::isfinite(d) ? g17(d) : "null";
  return *this;
}
Json& Json::value(std::uint64_t u) {
  sep();
  out_ += std::to_string(u);
  return *this;
}
Json& Json::value(std::int64_t i) {
  sep();
  out_ += std::to_string(i);
  return *this;
}
Json& Json::value(bool b) {
  sep();
  out_ += b ? "true" : "false";
  return *this;
}
Json& Json::begin_object() {
  sep();
  out_ += "{";
  first_.push_back(true);
  return *this;
}
Json& Json::end_object() {
  out_ += "}";
  first_.pop_back();
  return *this;
}
Json& Json::begin_array() {
  sep();
  out_ += "[";
  first_.push_back(true);
  return *this;
}
Json& Json::end_array() {
  out_ += "]";
  first_.pop_back();
  return *this;
}

namespace {

std::string header_json(Kind kind, const ScalarQuantizer& q, const std::vector<std::uint64_t>& declared) {
  std::string s = "{\n";
  s += "  \"kind\": \"" + std::string(kind_name(kind)) + "\",\n";
  s += "  \"q\": " + std::to_string(q.bits) + ",\n";
  s += "  \"origin\": [" + g17(q.origin[0]) + ", " + g17(q.origin[1]) + ", " + g17(q.origin[2]) + "],\n";
  s += "  \"step\": " + g17(q.step) + ",\n";
  s += "  \"levels\": " + std::to_string(declared.size()) + ",\n";
  s += "  \"level_points\": [";
  // Listed finest first, so entry K is level K.
  for (std::size_t i = 0; i < declared.size(); ++i)
    s += (i ? ", " : "") + std::to_string(declared[declared.size() - 1 - i]);
  s += "]\n}\n";
  return s;
}

std::string points_text(const std::vector<GridPoint>& pts) {
  std::string s;
  s.reserve(pts.size() * 22);
  char buf[40];
  for (const auto& p : pts) {
    int n = std::snprintf(buf, sizeof buf, "%u %u %u\n", p[0], p[1], p[2]);
    s.append(buf, static_cast<std::size_t>(n));
  }
  return s;
}

}  // namespace

template <std::size_t N>
std::string simplices_text(const std::vector<std::array<std::uint32_t, N>>& simplices) {
  std::vector<std::array<std::uint32_t, N>> s(simplices);
  for (auto& x : s) std::sort(x.begin(), x.end());
  std::sort(s.begin(), s.end());
  std::string out;
  for (const auto& x : s) {
    for (std::size_t i = 0; i < N; ++i) out += (i ? " " : "") + std::to_string(x[i]);
    out += "\n";
  }
  return out;
}

Result<Done> write_canonical_dump(const std::string& dir, Kind kind, const ScalarQuantizer& q,
                                  const std::vector<std::uint64_t>& declared_points,
                                  const std::vector<DumpLevel>& levels) {
  std::vector<std::pair<std::string, std::string>> files;
  files.emplace_back("header.json", header_json(kind, q, declared_points));
  for (const auto& l : levels) {
    const std::string stem = "level-" + std::to_string(l.lod);
    files.emplace_back(stem + ".points", points_text(*l.points));
    // No simplices file when connectivity was not rebuilt (points-only decoding).
    if (kind == Kind::surface && l.triangles && !l.points_only) files.emplace_back(stem + ".simplices", simplices_text(*l.triangles));
    if (kind == Kind::volume && l.tetrahedra && !l.points_only) files.emplace_back(stem + ".simplices", simplices_text(*l.tetrahedra));
  }

  std::error_code ec;
  const bool existed = fs::exists(dir, ec);
  fs::path target = dir;
  fs::path work = target;
  if (!existed) {
    std::random_device rd;
    work = target.parent_path() / (target.filename().string() + ".tmp-" + std::to_string(rd()));
    if (target.parent_path().empty()) work = fs::path(target.filename().string() + ".tmp-" + std::to_string(rd()));
    if (!fs::create_directory(work, ec))
      return Error{Status::io_error, "cannot create directory " + work.string() + ": " + ec.message()};
  } else if (!fs::is_directory(dir, ec)) {
    return Error{Status::io_error, dir + " exists and is not a directory"};
  }
  std::vector<fs::path> written;
  for (const auto& [name, content] : files) {
    auto r = io::write_file_atomic((work / name).string(), content);
    if (!r) {
      for (const auto& p : written) fs::remove(p, ec);
      if (!existed) fs::remove_all(work, ec);
      return r.error();
    }
    written.push_back(work / name);
  }
  if (!existed) {
    fs::rename(work, target, ec);
    if (ec) {
      const std::string why = ec.message();
      fs::remove_all(work, ec);
      return Error{Status::io_error, "cannot rename " + work.string() + " to " + dir + ": " + why};
    }
  }
  return Done{};
}

std::vector<double> parse_doubles(const std::string& s) {
  std::vector<double> out;
  std::size_t at = 0;
  while (at <= s.size()) {
    const std::size_t comma = std::min(s.find(',', at), s.size());
    const std::string item = s.substr(at, comma - at);
    char* end = nullptr;
    const double v = std::strtod(item.c_str(), &end);
    if (item.empty() || *end || !std::isfinite(v)) return {};
    out.push_back(v);
    at = comma + 1;
  }
  return out;
}

}  // namespace hmc::cli
