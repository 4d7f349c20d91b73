// SPDX-License-Identifier: AGPL-3.0-or-later
// Internal error propagation. Inside libhmc, a malformed stream or a failed
// precondition raises StreamError; every public entry point catches it (and
// std::bad_alloc) and returns it as an hmc::Error, so no exception crosses
// the API.
#pragma once

#include <exception>
#include <new>
#include <string>
#include <utility>

#include "hmc/status.hpp"

namespace hmc::detail {

class StreamError : public std::exception {
 public:
  StreamError(Status s, std::string m) : error_{s, std::move(m)} {}
  const char* what() const noexcept override { return error_.message.c_str(); }
  const Error& error() const noexcept { return error_; }

 private:
  Error error_;
};

[[noreturn]] inline void fail(Status s, std::string message) { throw StreamError(s, std::move(message)); }

/// Runs `f` and converts anything it throws into an Error.
template <class R, class F>
R guarded(F&& f) noexcept {
  try {
    return f();
  } catch (const StreamError& e) {
    return e.error();
  } catch (const std::bad_alloc&) {
    return Error{Status::out_of_memory, "allocation failed"};
  } catch (const std::exception& e) {
    return Error{Status::internal_error, e.what()};
  } catch (...) {
    return Error{Status::internal_error, "unknown exception"};
  }
}

}  // namespace hmc::detail
