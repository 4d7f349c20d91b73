// SPDX-License-Identifier: AGPL-3.0-or-later
// Replays fuzz inputs without libFuzzer: linked with one fuzz target, it
// calls the target's LLVMFuzzerTestOneInput on every file named on the
// command line and on every file of every directory named there (sorted,
// recursively; names starting with '.' are skipped). A failing check in the
// target aborts, so CTest reports the run as failed; the driver then names
// the input on stderr. (A sanitizer report ends the process without an
// abort: set HMC_REPLAY_VERBOSE=1 to name every input before it runs.)
//
// usage: hmc_replay_<target> PATH...
// A directory that does not exist is skipped with a note (an empty
// regression directory is not kept by git); the run fails when no file at
// all was found.
#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <cstdint>
#include <cstring>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <system_error>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

namespace {

namespace fs = std::filesystem;

const char* volatile g_current = nullptr;

extern "C" void on_abort(int sig) {
  // Only async-signal-safe calls here.
  const char* name = g_current;
  if (name) {
    const char prefix[] = "replay: the failing input is ";
    ssize_t ignored = write(2, prefix, sizeof prefix - 1);
    ignored = write(2, name, std::strlen(name));
    ignored = write(2, "\n", 1);
    (void)ignored;
  }
  std::signal(sig, SIG_DFL);
  std::raise(sig);
}

bool hidden(const fs::path& p) {
  const std::string name = p.filename().string();
  return !name.empty() && name[0] == '.';
}

void collect(const fs::path& root, std::vector<fs::path>& files) {
  std::error_code ec;
  if (fs::is_regular_file(root, ec)) {
    files.push_back(root);
    return;
  }
  if (!fs::is_directory(root, ec)) {
    std::fprintf(stderr, "replay: %s does not exist, skipped\n", root.string().c_str());
    return;
  }
  std::vector<fs::path> found;
  for (auto it = fs::recursive_directory_iterator(root, ec); !ec && it != fs::recursive_directory_iterator();
       it.increment(ec)) {
    if (hidden(it->path())) {
      if (it->is_directory(ec)) it.disable_recursion_pending();
      continue;
    }
    if (it->is_regular_file(ec)) found.push_back(it->path());
  }
  if (ec) std::fprintf(stderr, "replay: cannot list %s: %s\n", root.string().c_str(), ec.message().c_str());
  std::sort(found.begin(), found.end());
  files.insert(files.end(), found.begin(), found.end());
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s FILE-OR-DIRECTORY...\n", argv[0]);
    return 2;
  }
  std::vector<fs::path> files;
  for (int i = 1; i < argc; ++i) collect(argv[i], files);
  if (files.empty()) {
    std::fprintf(stderr, "replay: no input files found\n");
    return 1;
  }
  std::signal(SIGABRT, on_abort);
  const bool verbose = std::getenv("HMC_REPLAY_VERBOSE") != nullptr;
  std::size_t bytes = 0;
  for (const fs::path& f : files) {
    std::ifstream in(f, std::ios::binary);
    if (!in) {
      std::fprintf(stderr, "replay: cannot read %s\n", f.string().c_str());
      return 1;
    }
    std::vector<std::uint8_t> data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const std::string name = f.string();
    g_current = name.c_str();
    if (verbose) std::fprintf(stderr, "replay: %s (%zu bytes)\n", name.c_str(), data.size());
    // libFuzzer never passes a null pointer, even for an empty input.
    const std::uint8_t empty = 0;
    LLVMFuzzerTestOneInput(data.empty() ? &empty : data.data(), data.size());
    g_current = nullptr;
    bytes += data.size();
  }
  std::printf("replay: %zu input(s), %zu bytes, all passed\n", files.size(), bytes);
  return 0;
}
