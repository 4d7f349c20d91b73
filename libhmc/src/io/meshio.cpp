// SPDX-License-Identifier: AGPL-3.0-or-later
// Public entry points: format detection, dispatch to the readers and
// writers, whole-file reading and atomic writing.
#include "hmc/meshio.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <system_error>
#include <vector>

#include "io/common.hpp"
#include "util/error.hpp"

namespace hmc::io {

namespace fs = std::filesystem;
using hmc::detail::fail;

namespace {

std::string os_reason(int err) { return std::error_code(err, std::generic_category()).message(); }

std::string lower_extension(std::string_view path) {
  const std::size_t slash = path.find_last_of('/');
  const std::string_view file = slash == std::string_view::npos ? path : path.substr(slash + 1);
  const std::size_t dot = file.find_last_of('.');
  if (dot == std::string_view::npos || dot == 0) return {};
  return detail::to_lower(file.substr(dot + 1));
}

class Fd {
 public:
  explicit Fd(int fd) noexcept : fd_(fd) {}
  Fd(const Fd&) = delete;
  Fd& operator=(const Fd&) = delete;
  ~Fd() {
    if (fd_ >= 0) ::close(fd_);
  }
  int get() const noexcept { return fd_; }
  int release() noexcept {
    const int f = fd_;
    fd_ = -1;
    return f;
  }

 private:
  int fd_;
};

// A temporary file beside its target, written and synced but not yet renamed
// into place. Removes itself unless committed.
class Staged {
 public:
  Staged(std::string target, std::string_view bytes) : target_(std::move(target)) {
    try {
      write(bytes);
    } catch (...) {
      // The destructor does not run for a constructor that throws.
      if (!temp_.empty()) ::unlink(temp_.c_str());
      throw;
    }
  }
  Staged(const Staged&) = delete;
  Staged& operator=(const Staged&) = delete;
  Staged(Staged&& o) noexcept : target_(std::move(o.target_)), temp_(std::move(o.temp_)) { o.temp_.clear(); }
  ~Staged() {
    if (!temp_.empty()) ::unlink(temp_.c_str());
  }

  const std::string& target() const noexcept { return target_; }

  void commit() {
    if (::rename(temp_.c_str(), target_.c_str()) != 0) {
      const int err = errno;
      fail(Status::io_error, "cannot write '" + target_ + "': " + os_reason(err));
    }
    temp_.clear();
  }

 private:
  void write(std::string_view bytes) {
    if (target_.empty()) fail(Status::invalid_argument, "empty output path");
    const fs::path target(target_);
    const std::string dir = target.has_parent_path() ? target.parent_path().string() : std::string(".");
    const std::string base = target.filename().string();
    if (base.empty() || base == "." || base == "..")
      fail(Status::invalid_argument, "output path '" + target_ + "' does not name a file");

    static std::atomic<std::uint64_t> counter{0};
    const auto nonce = static_cast<std::uint64_t>(std::chrono::steady_clock::now().time_since_epoch().count());
    int fd = -1;
    int err = 0;
    for (int attempt = 0; attempt < 100 && fd < 0; ++attempt) {
      const std::uint64_t k = counter.fetch_add(1) ^ (nonce * 0x9e3779b97f4a7c15ull);
      temp_ = dir + "/." + base + ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(k % 1000000007ull);
      fd = ::open(temp_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
      err = errno;
      if (fd < 0 && err != EEXIST) break;
    }
    if (fd < 0) {
      temp_.clear();
      fail(Status::io_error, "cannot write '" + target_ + "': " + os_reason(err));
    }
    Fd file(fd);
    const char* p = bytes.data();
    std::size_t left = bytes.size();
    while (left > 0) {
      const ::ssize_t w = ::write(file.get(), p, left);
      if (w < 0) {
        if (errno == EINTR) continue;
        fail_write(errno);
      }
      p += w;
      left -= static_cast<std::size_t>(w);
    }
    if (::fsync(file.get()) != 0) fail_write(errno);
    if (::close(file.release()) != 0) fail_write(errno);
  }

  [[noreturn]] void fail_write(int err) {
    fail(Status::io_error, "cannot write '" + target_ + "': " + os_reason(err));
  }

  std::string target_;
  std::string temp_;
};

// Makes the directory entry of a rename durable; failures are harmless here
// (the data itself is already synced), so they are ignored.
void sync_directory_of(const std::string& path) noexcept {
  try {
    fs::path dir = fs::path(path).parent_path();
    if (dir.empty()) dir = ".";
    const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd >= 0) {
      ::fsync(fd);
      ::close(fd);
    }
  } catch (...) {
  }
}

bool same_file(const std::string& a, const std::string& b) {
  std::error_code ec1, ec2;
  const bool ea = fs::exists(a, ec1), eb = fs::exists(b, ec2);
  if (ea && eb) {
    std::error_code ec;
    const bool eq = fs::equivalent(a, b, ec);
    if (!ec) return eq;
  }
  // Absolute first, so that a relative and an absolute spelling of a file in
  // a directory that does not exist yet still compare equal.
  const fs::path aa = fs::absolute(a).lexically_normal(), ab = fs::absolute(b).lexically_normal();
  std::error_code ca, cb;
  const fs::path pa = fs::weakly_canonical(aa, ca), pb = fs::weakly_canonical(ab, cb);
  if (ca || cb) return aa == ab;
  return pa == pb;
}

// Writes several files all-or-nothing as far as the OS allows: everything is
// staged first, so a failure while writing data leaves every target as it
// was; only a failing rename (after the checks below) can leave a partial
// set, and then the files already renamed by this call are removed.
void write_files(const std::vector<std::pair<std::string, std::string>>& files) {
  for (const auto& f : files) {
    std::error_code ec;
    if (fs::is_directory(f.first, ec))
      fail(Status::io_error, "cannot write '" + f.first + "': it is a directory");
  }
  std::vector<Staged> staged;
  staged.reserve(files.size());
  for (const auto& f : files) staged.emplace_back(f.first, f.second);
  std::size_t done = 0;
  try {
    for (; done < staged.size(); ++done) staged[done].commit();
  } catch (...) {
    for (std::size_t i = 0; i < done; ++i) ::unlink(staged[i].target().c_str());
    throw;
  }
  if (!staged.empty()) sync_directory_of(staged.front().target());
}

void check_writable(const Mesh& m, Format f, const WriteOptions& opt) {
  if (opt.precision < 1)
    fail(Status::invalid_argument, "precision must be at least 1, not " + std::to_string(opt.precision));
  if (m.points.size() > 0xffffffffull) fail(Status::invalid_argument, "too many points for 32-bit indices");
  for (std::size_t i = 0; i < m.points.size(); ++i)
    for (double c : m.points[i])
      if (!std::isfinite(c))
        fail(Status::invalid_argument, "point " + std::to_string(i) + " has a non-finite coordinate");
  const std::size_t n = m.points.size();
  for (std::size_t i = 0; i < m.triangles.size(); ++i)
    for (std::uint32_t v : m.triangles[i])
      if (v >= n)
        fail(Status::invalid_argument, "triangle " + std::to_string(i) + " has vertex index " + std::to_string(v) +
                                           " out of range (" + std::to_string(n) + " points)");
  for (std::size_t i = 0; i < m.tetrahedra.size(); ++i)
    for (std::uint32_t v : m.tetrahedra[i])
      if (v >= n)
        fail(Status::invalid_argument, "tetrahedron " + std::to_string(i) + " has vertex index " +
                                           std::to_string(v) + " out of range (" + std::to_string(n) + " points)");
  if ((f == Format::ply || f == Format::obj) && !m.tetrahedra.empty())
    fail(Status::invalid_argument, std::string(format_name(f)) + " cannot store tetrahedra (the mesh has " +
                                       std::to_string(m.tetrahedra.size()) +
                                       "); write vtk, vtu, medit or tetgen instead");
}

Mesh read_any(const std::string& path, Format format) {
  if (format == Format::automatic) {
    format = format_from_path(path);
    if (format == Format::automatic)
      fail(Status::unsupported_format, "cannot tell the format of '" + path + "' from its extension");
  }
  switch (format) {
    case Format::tetgen: return detail::read_tetgen(path);
    case Format::vtu: fail(Status::unsupported_format, "reading VTU files is not supported: '" + path + "'");
    case Format::medit:
      if (lower_extension(path) == "meshb")
        fail(Status::unsupported_format, "binary MEDIT files (.meshb) are not supported: '" + path + "'");
      break;
    default: break;
  }
  const std::string data = detail::load_file(path);
  switch (format) {
    case Format::ply: return detail::read_ply(path, data);
    case Format::obj: return detail::read_obj(path, data);
    case Format::off: return detail::read_off(path, data);
    case Format::xyz: return detail::read_xyz(path, data);
    case Format::stl: return detail::read_stl(path, data);
    case Format::medit: return detail::read_medit(path, data);
    case Format::gmsh: return detail::read_gmsh(path, data);
    case Format::vtk: return detail::read_vtk(path, data);
    default: break;
  }
  fail(Status::invalid_argument, "unknown format value");
}

void write_any(const std::string& path, const Mesh& mesh, Format format, const WriteOptions& opt) {
  if (format == Format::automatic) {
    format = format_from_path(path);
    if (format == Format::automatic)
      fail(Status::unsupported_format, "cannot tell the format to write '" + path + "' from its extension");
  }
  switch (format) {
    case Format::off:
    case Format::stl:
    case Format::gmsh:
      fail(Status::unsupported_format, std::string("writing ") + format_name(format) + " files is not supported");
    default: break;
  }
  check_writable(mesh, format, opt);
  std::string bytes;
  switch (format) {
    case Format::ply: bytes = detail::write_ply(mesh, opt); break;
    case Format::obj: bytes = detail::write_obj(mesh, opt); break;
    case Format::xyz: bytes = detail::write_xyz(mesh, opt); break;
    case Format::vtk: bytes = detail::write_vtk(mesh, opt); break;
    case Format::vtu: bytes = detail::write_vtu(mesh, opt); break;
    case Format::medit: bytes = detail::write_medit(mesh, opt); break;
    case Format::tetgen: {
      detail::TetgenFiles t = detail::write_tetgen(mesh, opt);
      const detail::TetgenPaths p = detail::tetgen_paths(path);
      std::vector<std::pair<std::string, std::string>> files;
      files.emplace_back(p.node, std::move(t.node));
      if (!mesh.tetrahedra.empty()) files.emplace_back(p.ele, std::move(t.ele));
      if (!mesh.triangles.empty()) files.emplace_back(p.face, std::move(t.face));
      write_files(files);
      return;
    }
    default: fail(Status::invalid_argument, "unknown format value");
  }
  std::vector<std::pair<std::string, std::string>> files;
  files.emplace_back(path, std::move(bytes));
  write_files(files);
}

}  // namespace

namespace detail {

std::string load_file(const std::string& path, std::uint64_t max_bytes) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) {
    const int err = errno;
    fail(Status::io_error, "cannot open '" + path + "': " + os_reason(err));
  }
  Fd file(fd);
  struct stat st {};
  if (::fstat(fd, &st) != 0) {
    const int err = errno;
    fail(Status::io_error, "cannot read '" + path + "': " + os_reason(err));
  }
  if (S_ISDIR(st.st_mode)) fail(Status::io_error, "cannot read '" + path + "': it is a directory");
  std::string out;
  if (S_ISREG(st.st_mode)) {
    const auto size = static_cast<std::uint64_t>(st.st_size);
    if (size > max_bytes)
      fail(Status::io_error, "cannot read '" + path + "': its " + std::to_string(size) +
                                 " bytes exceed the limit of " + std::to_string(max_bytes));
    out.reserve(static_cast<std::size_t>(size));
  }
  char buf[1 << 16];
  for (;;) {
    const ::ssize_t r = ::read(fd, buf, sizeof buf);
    if (r < 0) {
      if (errno == EINTR) continue;
      const int err = errno;
      fail(Status::io_error, "cannot read '" + path + "': " + os_reason(err));
    }
    if (r == 0) break;
    if (out.size() + static_cast<std::uint64_t>(r) > max_bytes)
      fail(Status::io_error, "cannot read '" + path + "': it exceeds the limit of " + std::to_string(max_bytes) +
                                 " bytes");
    out.append(buf, static_cast<std::size_t>(r));
  }
  return out;
}

}  // namespace detail

const char* format_name(Format f) noexcept {
  switch (f) {
    case Format::automatic: return "automatic";
    case Format::ply: return "ply";
    case Format::obj: return "obj";
    case Format::off: return "off";
    case Format::xyz: return "xyz";
    case Format::stl: return "stl";
    case Format::tetgen: return "tetgen";
    case Format::medit: return "medit";
    case Format::gmsh: return "gmsh";
    case Format::vtk: return "vtk";
    case Format::vtu: return "vtu";
  }
  return "unknown";
}

Format format_from_path(std::string_view path) noexcept {
  try {
    const std::string ext = lower_extension(path);
    if (ext == "ply") return Format::ply;
    if (ext == "obj") return Format::obj;
    if (ext == "off") return Format::off;
    if (ext == "xyz" || ext == "pts" || ext == "txt") return Format::xyz;
    if (ext == "stl") return Format::stl;
    if (ext == "node" || ext == "ele" || ext == "face") return Format::tetgen;
    if (ext == "mesh" || ext == "meshb") return Format::medit;
    if (ext == "msh") return Format::gmsh;
    if (ext == "vtk") return Format::vtk;
    if (ext == "vtu") return Format::vtu;
  } catch (...) {
  }
  return Format::automatic;
}

Result<Mesh> read_mesh(const std::string& path, Format format) {
  return hmc::detail::guarded<Result<Mesh>>([&]() -> Result<Mesh> { return read_any(path, format); });
}

Result<Done> write_mesh(const std::string& path, const Mesh& mesh, Format format, const WriteOptions& options) {
  return hmc::detail::guarded<Result<Done>>([&]() -> Result<Done> {
    if (!options.protect_path.empty() && same_file(path, options.protect_path))
      fail(Status::invalid_argument, "output would overwrite the input '" + options.protect_path + "'");
    write_any(path, mesh, format, options);
    return Done{};
  });
}

Result<Done> write_file_atomic(const std::string& path, std::string_view bytes, const std::string& protect_path) {
  return hmc::detail::guarded<Result<Done>>([&]() -> Result<Done> {
    if (path.empty()) fail(Status::invalid_argument, "empty output path");
    if (!protect_path.empty() && same_file(path, protect_path))
      fail(Status::invalid_argument, "output would overwrite the input '" + protect_path + "'");
    Staged s(path, bytes);
    s.commit();
    sync_directory_of(path);
    return Done{};
  });
}

Result<std::string> read_file(const std::string& path, std::uint64_t max_bytes) {
  return hmc::detail::guarded<Result<std::string>>(
      [&]() -> Result<std::string> { return detail::load_file(path, max_bytes); });
}

}  // namespace hmc::io
