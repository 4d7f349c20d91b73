// SPDX-License-Identifier: AGPL-3.0-or-later
// The message of a failed hmc::Result for REQUIRE_MESSAGE / CHECK_MESSAGE.
// doctest evaluates a message also when the check passes (under -s, which
// reports successes), and error() on a successful Result throws: why()
// reads the error only when there is one.
#pragma once

#include <string>

namespace hmc::testgen {

template <class R>
std::string why(const R& r) {
  return r.ok() ? std::string("ok") : r.error().to_string();
}

}  // namespace hmc::testgen
