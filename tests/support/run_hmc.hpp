// SPDX-License-Identifier: AGPL-3.0-or-later
// Running the built `hmc` program from a test, the way a user would.
#pragma once

#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace hmc::testgen {

/// Exit code (-1: killed by a signal) and captured output of one run.
struct Run {
  int code = -1;
  std::string out, err;
};

/// The whole content of a file ("" if it cannot be read).
inline std::string slurp(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

/// Runs `hmc ARGS` through the shell (ARGS quoted by the caller), with its
/// standard output and error captured through files in `dir`.
inline Run hmc_run(const std::string& dir, const std::string& args) {
  namespace fs = std::filesystem;
  const std::string o = dir + "/.stdout", e = dir + "/.stderr";
  const std::string cmd = std::string("'") + HMC_BINARY + "' " + args + " >'" + o + "' 2>'" + e + "'";
  const int status = std::system(cmd.c_str());
  Run r;
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = slurp(o);
  r.err = slurp(e);
  fs::remove(o);
  fs::remove(e);
  return r;
}

/// A shell-quoted argument (no single quotes inside).
inline std::string q(const std::string& s) { return "'" + s + "'"; }

}  // namespace hmc::testgen
